"""Whole-batch evaluation speed of the seed 000 and 004 examples (issue 12), before vs after.

    .venv/bin/python benchmarks/bench_evaluation.py [--repeat 15] [--rounds 3] [--before DIR]

For ``examples/000_swing_energy_flat.yaml``, ``000_swing_energy_obstacle.yaml`` and
``004_path_tracking.yaml`` the problem is built with :func:`legcore.runner.prepare` and
``problem.evaluate(X)`` is timed on a fixed random population of the example's size (its
``pop_size``; uniform in the decision box, snapped to the gene grid; seed 12). Reported:
samples/s = B · K / t (K time samples per candidate), t the best of ``--repeat`` calls after a
warm-up call (numba compilation excluded). Rows ``fk:ROBOT``: ``legcore.kinematics.fk`` alone on
random configurations (100 × 301) of ``calderon_leg`` and ``puma560``.

``--before DIR``: also time the code of another source tree — DIR holds its ``legcore``
package, e.g. ``git archive <commit> legcore | tar -x -C DIR`` — on the same populations,
each side in its own subprocess, alternating for ``--rounds`` rounds (best per side), and print
before/after samples/s, the ratio and the max |ΔF|, |ΔG| between the two evaluations.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = (
    "000_swing_energy_flat",
    "000_swing_energy_obstacle",
    "004_path_tracking",
)
CASES = (*EXAMPLES, "fk:calderon_leg", "fk:puma560")


def population(problem: Any, size: int, seed: int = 12) -> np.ndarray:
    """A fixed random population (size, n_var) uniform in the box, on the gene grid."""
    rng = np.random.default_rng(seed)
    X = problem.xl + rng.random((size, problem.n_var)) * (problem.xu - problem.xl)
    return np.asarray(problem.snap(X), dtype=float)


def build(name: str) -> tuple[Any, np.ndarray, int]:
    """(problem, X, K) of one example: its problem, population and samples per candidate."""
    from legcore.runner import prepare

    spec = yaml.safe_load((ROOT / "examples" / f"{name}.yaml").read_text())
    problem = prepare(spec).problem
    size = int(spec["optimizer"]["params"]["pop_size"])
    return problem, population(problem, size), int(problem.n_samples)


def best_time(problem: Any, X: np.ndarray, repeat: int) -> tuple[float, np.ndarray, np.ndarray]:
    """Best wall time (s) of ``problem.evaluate(X)`` over ``repeat`` calls after a warm-up."""
    F, G = problem.evaluate(X)
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        F, G = problem.evaluate(X)
        best = min(best, time.perf_counter() - t0)
    return best, F, G


class _FK:
    """``fk`` of a catalog robot posing as a problem (F = the tool poses, no G)."""

    def __init__(self, robot: str) -> None:
        from legcore.robots import catalog

        self.robot = catalog.get(robot)

    def evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        from legcore.kinematics import fk

        return fk(self.robot, X), np.zeros(0)


def measure(repeat: int) -> dict[str, np.ndarray]:
    """Every case's best time, B, K, X, F, G (keys ``name/field``)."""
    out: dict[str, np.ndarray] = {}
    for name in CASES:
        if name.startswith("fk:"):
            problem: Any = _FK(name[3:])
            r = problem.robot
            X = np.random.default_rng(12).uniform(r.q_min, r.q_max, (100, 301, r.nq))
            K = 301
        else:
            problem, X, K = build(name)
        t, F, G = best_time(problem, X, repeat)
        out.update({f"{name}/t": np.array(t), f"{name}/K": np.array(K), f"{name}/X": X,
                    f"{name}/F": F, f"{name}/G": G})
    return out


def run_side(src: Path | None, repeat: int, tmp: Path) -> dict[str, np.ndarray]:
    """:func:`measure` in a subprocess importing ``legcore`` from ``src`` (None: this tree)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(src or ROOT)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    path = tmp / "side.npz"
    cmd = [sys.executable, str(Path(__file__).resolve()), "--repeat", str(repeat),
           "--worker", str(path)]
    subprocess.run(cmd, env=env, check=True)
    return dict(np.load(path))


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--before", type=Path, default=None)
    ap.add_argument("--worker", type=Path, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker is not None:
        np.savez(args.worker, **measure(args.repeat))
        return
    if args.before is None:
        res = measure(args.repeat)
        print(f"{'example':28s} {'B':>4s} {'K':>4s} {'t (ms)':>8s} {'samples/s':>10s}")
        for name in CASES:
            B, K, t = res[f"{name}/X"].shape[0], int(res[f"{name}/K"]), float(res[f"{name}/t"])
            print(f"{name:28s} {B:4d} {K:4d} {t * 1e3:8.2f} {B * K / t:10.3g}")
        return
    best: dict[str, dict[str, float]] = {"before": {}, "after": {}}
    sides: dict[str, dict[str, np.ndarray]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.rounds):
            for side, src in (("before", args.before.resolve()), ("after", None)):
                sides[side] = run_side(src, args.repeat, Path(tmp))
                for name in CASES:
                    t = float(sides[side][f"{name}/t"])
                    best[side][name] = min(best[side].get(name, float("inf")), t)
    print(f"{'example':28s} {'B':>4s} {'K':>4s} {'before [samples/s]':>19s} "
          f"{'after [samples/s]':>18s} {'ratio':>6s} {'max|dF|':>8s} {'max|dG|':>8s}")
    for name in CASES:
        a, b = sides["after"], sides["before"]
        if not np.array_equal(a[f"{name}/X"], b[f"{name}/X"]):
            raise SystemExit(f"{name}: the two trees drew different populations")
        B, K = a[f"{name}/X"].shape[0], int(a[f"{name}/K"])
        sb, sa = B * K / best["before"][name], B * K / best["after"][name]
        dF = float(np.max(np.abs(a[f"{name}/F"] - b[f"{name}/F"])))
        dG = float(np.max(np.abs(a[f"{name}/G"] - b[f"{name}/G"]), initial=0.0))
        print(f"{name:28s} {B:4d} {K:4d} {sb:19.3g} {sa:18.3g} {sa / sb:5.2f}× "
              f"{dF:8.1e} {dG:8.1e}")


if __name__ == "__main__":
    main()
