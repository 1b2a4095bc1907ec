"""Minimum cycle time against the physical minimum (issue 19): ``path_tracking`` with the paper's
trapezoid laws (``speeds: per_segment``, before) and with a speed profile (``speeds: profile``,
after), each over N seeds at the example's own budget, beside TOPP-RA's time-optimal profile
of the same joint path under the same limits (the run's ``time_optimal`` baseline, kept on a
dense resampling).

Per case and encoding: the optimum's T (mean ± sd over the seeds; every optimum is checked on a
dense resampling — "feasible" counts those that hold), the physical minimum T*, the ratio T / T*
(mean, worst), and the Mann–Whitney U test (two-sided) of the N optimum times of the two
encodings. Then ``objective: energy_time`` with the speed profile: the front's fastest point
over T* and its lowest energy against the paper's law's. The cases: seed 004's example and the
UR5 and Panda presets (their URDFs from the example-robot-data wheel).

    .venv/bin/python benchmarks/bench_time_optimal.py              # N = 10
    .venv/bin/python benchmarks/bench_time_optimal.py --seeds 3 --only ur5
"""

from __future__ import annotations

import argparse
import importlib.metadata
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from scipy.stats import mannwhitneyu

from legcore.runner import run
from services.spec_files import inline_robot_files

ROOT = Path(__file__).resolve().parents[1]
CASES = {
    "seed 004 (articulated_5dof)": ROOT / "examples" / "004_path_tracking.yaml",
    "ur5 preset": ROOT / "examples" / "presets" / "path_tracking_ur5.yaml",
    "panda preset": ROOT / "examples" / "presets" / "path_tracking_panda.yaml",
}
ENCODINGS = ("per_segment", "profile")


def _erd() -> Path:
    dist = importlib.metadata.distribution("example-robot-data")
    return Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))


def _spec(path: Path) -> dict[str, Any]:
    data = yaml.safe_load(path.read_text())
    return inline_robot_files(data, _erd()) if "urdf_file" in data.get("robot", {}) else data


def one(name: str, path: Path, seeds: list[int]) -> list[str]:
    base = _spec(path)
    out, times = [], {}
    for enc in ENCODINGS:
        T, ok, T_star = [], 0, float("nan")
        t0 = time.perf_counter()
        for seed in seeds:
            spec = {**base, "seed": seed, "record": False,
                    "problem": {**base["problem"], "speeds": enc}}
            res = run(spec)
            T.append(res.best.objectives["time"])
            ok += res.feasible
            T_star = res.baselines["time_optimal"].objectives["time"]
        wall = (time.perf_counter() - t0) / len(seeds)
        a = np.array(T)
        times[enc] = a
        r = a / T_star
        out.append(f"| {name} | {enc} | {a.mean():.4f} ± {a.std(ddof=1) if a.size > 1 else 0:.4f}"
                   f" | {ok}/{len(seeds)} | {T_star:.4f} | {r.mean():.4f}× | {r.max():.4f}× "
                   f"| {wall:.1f} |")
    p = mannwhitneyu(times["per_segment"], times["profile"]).pvalue if len(seeds) > 1 else 1.0
    out.append(f"| {name} | profile vs per_segment | p = {p:.2g} (Mann–Whitney U, two-sided) "
               "| | | | | |")
    return out


def front_span(name: str, path: Path, seeds: list[int]) -> str:
    """``objective: energy_time`` with the speed profile: the front's fastest point over T*,
    and its lowest energy against the paper's law's (the start)."""
    base = _spec(path)
    fast, low, seed_E = [], [], float("nan")
    for seed in seeds:
        spec = {**base, "seed": seed, "record": False,
                "problem": {**base["problem"], "speeds": "profile", "objective": "energy_time"}}
        res = run(spec)
        F = np.array([p["objectives"] for p in res.pareto])
        T_star = res.baselines["time_optimal"].objectives["time"]
        fast.append(F[:, 0].min() / T_star)
        low.append(F[:, 1].min())
        seed_E = res.baselines["seed"].objectives["energy"]
    f, e = np.array(fast), np.array(low)
    return (f"| {name} | {f.mean():.4f}× (worst {f.max():.4f}×) | {e.mean():.4f} ± "
            f"{e.std(ddof=1) if e.size > 1 else 0:.4f} | {seed_E:.4f} | "
            f"{int(np.sum(e <= seed_E))}/{e.size} |")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--only", default="")
    args = ap.parse_args()
    seeds = list(range(1, args.seeds + 1))
    print("| case | encoding | optimum T s (mean ± sd) | feasible | physical minimum T* s "
          "| T / T* mean | T / T* worst | wall s per run |")
    print("|---|---|---|---|---|---|---|---|")
    cases = {name: path for name, path in CASES.items() if args.only in name}
    for name, path in cases.items():
        for line in one(name, path, seeds):
            print(line, flush=True)
    print("\n| case | energy_time front: fastest T / T* | lowest energy J (mean ± sd) | paper's "
          "law's energy J | seeds with lowest ≤ the law's |")
    print("|---|---|---|---|---|")
    for name, path in cases.items():
        print(front_span(name, path, seeds), flush=True)


if __name__ == "__main__":
    main()
