"""A job's finishing work (issue 23 item 2): seed 002's ``legcore.run`` with the numpy pose
workspace and MOEA/D update (before) against the compiled ones (after), in one process.

    .venv/bin/python benchmarks/bench_finishing.py [--rounds 9] [--gens 2]

Jobs: ``examples/002_hexapod_workspace.yaml`` as it is (MOEA/D 300 × 100) and a tiny version of
it (``--gens`` generations, default 2). *numpy* = this tree with the formulations the compiled
code replaced patched back in: the body-pose IK and pose workspace of
``geometry.body_pose_ik_reference`` (eager joint angles, the masks written cell by cell) and
MOEA/D's replacement and archive update of ``legcore.optimizers.moead_reference``; *compiled* =
this tree as it is. The two alternate within each round (``--rounds`` rounds, after a warm-up
run of each); reported: the median wall time of ``legcore.run`` per side and their ratio, and,
from separately instrumented runs, the median time inside MOEA/D's ``tell`` and inside the
study's ``extras`` per job. "max |Δ|": the largest difference between the two sides'
``RunResult.to_dict()`` numbers, wall times left out (the pose IK agrees to ~1e-15 rad,
everything else is equal).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import platform
import statistics
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from legcore.optimizers.moead import MOEAD  # noqa: E402
from legcore.optimizers.moead_reference import archive_reference, replace_reference  # noqa: E402
from legcore.runner import run  # noqa: E402
from legcore.studies.hexapod_workspace import geometry as geo  # noqa: E402
from legcore.studies.hexapod_workspace import problem as hexproblem  # noqa: E402

EXAMPLE = ROOT / "examples" / "002_hexapod_workspace.yaml"


def _replace_numpy(self: MOEAD, Y: np.ndarray, FY: np.ndarray, cvY: np.ndarray) -> None:
    j, i = replace_reference(self.neighbors, self.weights, self._z, self._F, self._cv, FY, cvY)
    self._X[j] = Y[i]
    self._F[j] = FY[i]
    self._cv[j] = cvY[i]


def _archive_numpy(self: MOEAD, X: np.ndarray, F: np.ndarray, cv: np.ndarray) -> None:
    cap = self._params["archive_size"]
    if cap == 0:
        return
    merged = archive_reference(X, F, cv, self._AX, self._AF, self.pop_size if cap is None else cap)
    if merged is not None:
        self._AX, self._AF = merged


class _LoopMasks(geo.PoseWorkspace):
    """The pose workspace whose masks are written cell by cell, as before."""

    def summary(self, masks: bool = True) -> dict[str, Any]:
        out = super().summary(masks=False)
        if masks:
            out["masks"] = [["".join("1" if v else "0" for v in row) for row in plane]
                            for plane in self.reachable]
        return out


def _pose_workspace_numpy(tripod: Any, feet_world: Any, x: Any, y: Any, yaw: Any,
                          knee: str = "up", q_ref: Any = None) -> geo.PoseWorkspace:
    xs, ys, yaws = (np.asarray(v, dtype=float).ravel() for v in (x, y, yaw))
    Yaw, Y, X = np.meshgrid(yaws, ys, xs, indexing="ij")
    q, ok = geo.body_pose_ik_reference(tripod, feet_world, X, Y, Yaw, knee=knee, q_ref=q_ref)
    reach = np.asarray(ok.all(axis=-1), dtype=bool)
    q = np.where(reach[..., None, None], q, np.nan)
    return _LoopMasks(xs, ys, yaws, reach, np.asarray(feet_world, dtype=float).copy(), knee,
                      lambda: q)


@contextlib.contextmanager
def numpy_side() -> Iterator[None]:
    """This tree with the numpy formulations patched back in (module docstring)."""
    saved = (MOEAD._replace, MOEAD._update_archive, hexproblem.body_pose_ik,
             hexproblem.pose_workspace)
    MOEAD._replace = _replace_numpy  # type: ignore[method-assign]
    MOEAD._update_archive = _archive_numpy  # type: ignore[method-assign]
    hexproblem.body_pose_ik = geo.body_pose_ik_reference  # type: ignore[assignment]
    hexproblem.pose_workspace = _pose_workspace_numpy  # type: ignore[assignment]
    try:
        yield
    finally:
        MOEAD._replace, MOEAD._update_archive = saved[:2]  # type: ignore[method-assign]
        hexproblem.body_pose_ik, hexproblem.pose_workspace = saved[2:]  # type: ignore[assignment]


def _side(name: str) -> contextlib.AbstractContextManager[None]:
    return numpy_side() if name == "numpy" else contextlib.nullcontext()


@contextlib.contextmanager
def instrumented(acc: dict[str, float]) -> Iterator[None]:
    """Add the seconds spent in MOEA/D's ``_tell`` and the study's ``extras`` to ``acc``."""
    tell, extras = MOEAD._tell, hexproblem.HexapodWorkspaceProblem.extras

    def timed(key: str, fn: Any) -> Any:
        def wrapper(*a: Any, **k: Any) -> Any:
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                acc[key] = acc.get(key, 0.0) + time.perf_counter() - t0
        return wrapper

    MOEAD._tell = timed("tell", tell)  # type: ignore[method-assign]
    hexproblem.HexapodWorkspaceProblem.extras = timed("extras", extras)  # type: ignore[method-assign]
    try:
        yield
    finally:
        MOEAD._tell = tell  # type: ignore[method-assign]
        hexproblem.HexapodWorkspaceProblem.extras = extras  # type: ignore[method-assign]


def _max_diff(a: Any, b: Any) -> float:
    """Largest |difference| between the numbers of two JSON-like trees (inf if shapes differ)."""
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            return float("inf")
        return max((_max_diff(a[k], b[k]) for k in a if "elapsed" not in k), default=0.0)
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return float("inf")
        return max((_max_diff(x, y) for x, y in zip(a, b, strict=True)), default=0.0)
    if isinstance(a, float | int) and isinstance(b, float | int) and not isinstance(a, bool):
        return abs(float(a) - float(b))
    return 0.0 if a == b else float("inf")


def measure(spec: dict[str, Any], rounds: int) -> dict[str, Any]:
    """Median run / tell / extras seconds per side and the result difference."""
    times: dict[str, list[float]] = {"numpy": [], "compiled": []}
    parts: dict[str, list[dict[str, float]]] = {"numpy": [], "compiled": []}
    results = {}
    for side in times:  # warm-up (and the results compared)
        with _side(side):
            results[side] = run(spec).to_dict()
    for _ in range(rounds):
        for side in times:
            with _side(side):
                t0 = time.perf_counter()
                run(spec)
                times[side].append(time.perf_counter() - t0)
                acc: dict[str, float] = {}
                with instrumented(acc):
                    run(spec)
                parts[side].append(acc)
    out: dict[str, Any] = {"diff": _max_diff(results["numpy"], results["compiled"])}
    for side in times:
        out[side] = {"run": statistics.median(times[side])}
        for k in ("tell", "extras"):
            out[side][k] = statistics.median(p[k] for p in parts[side])
    return out


def _machine() -> str:
    model = "?"
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    return (f"{os.cpu_count()} cores ({model}), {platform.system()}, "
            f"Python {platform.python_version()}")


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--rounds", type=int, default=9)
    ap.add_argument("--gens", type=int, default=2, help="generations of the tiny job")
    args = ap.parse_args()
    spec = yaml.safe_load(EXAMPLE.read_text())
    tiny = {**spec, "budget": {"generations": args.gens}}
    load0 = os.getloadavg()[0]
    rows = [("002 full", spec), (f"002 tiny ({args.gens} gen.)", tiny)]
    res = [(name, measure(s, args.rounds)) for name, s in rows]
    load1 = os.getloadavg()[0]
    print(f"machine: {_machine()}; load average {load0:.1f} -> {load1:.1f}; "
          f"medians of {args.rounds} interleaved rounds")
    print("| job | numpy s | compiled s | compiled / numpy | tell numpy → compiled ms "
          "| extras numpy → compiled ms | max |Δ| result |")
    print("|---|---|---|---|---|---|---|")
    for name, r in res:
        a, b = r["numpy"], r["compiled"]
        print(f"| {name} | {a['run']:.3f} | {b['run']:.3f} | **{b['run'] / a['run']:.2f}** | "
              f"{a['tell'] * 1e3:.1f} → {b['tell'] * 1e3:.1f} | "
              f"{a['extras'] * 1e3:.1f} → {b['extras'] * 1e3:.1f} | {r['diff']:.1e} |")


if __name__ == "__main__":
    main()
