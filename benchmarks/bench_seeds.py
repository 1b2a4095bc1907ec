"""Every single-objective example over ≥ 10 seeds (issue 11): the optimum beside where the
search started, mean ± sd, with a rank test — so no headline rests on one lucky seed.

For each example the job runs with seeds 1..N (recording off). Per seed: the optimum's
objective, the best of the initial population, and the solution the problem's encoding gives
without search (`StudyProblem.free_start`: the original placement of seed 001, the
coordinated motion of seed 000's deviation coding), plus the example's headline metrics.
p: Wilcoxon signed-rank of the N optimum values against the free solution's value (two-sided,
as every p of the benchmarks and docs; the direction is in the means).

    .venv/bin/python benchmarks/bench_seeds.py             # N = 10, every example below
    .venv/bin/python benchmarks/bench_seeds.py --seeds 3 --only 001
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from scipy.stats import wilcoxon

from legcore.runner import run

ROOT = Path(__file__).resolve().parents[1]
#: example → headline metrics printed beside the objective
EXAMPLES = {
    "001_path_placement_pan.yaml": ("energy_J", "mean_manipulability"),
    "001_path_placement_jar.yaml": ("energy_J", "mean_manipulability"),
    "003_quadruped_gait.yaml": ("min_stability_margin_m",),
    "004_path_tracking.yaml": ("energy",),
}


def _ms(a: np.ndarray) -> str:
    a = a[np.isfinite(a)]
    if a.size == 0:
        return "—"
    return f"{a.mean():.4g} ± {a.std(ddof=1) if a.size > 1 else 0.0:.2g}"


def one(example: str, seeds: list[int], headline: tuple[str, ...]) -> str:
    with open(ROOT / "examples" / example) as fh:
        base: dict[str, Any] = yaml.safe_load(fh)
    opt, ini, free, cols = [], [], [], {k: [] for k in headline}
    name, free_what = "?", None
    t0 = time.perf_counter()
    for seed in seeds:
        spec = dict(base, seed=seed, record=False)
        doc = run(spec).to_dict()
        row = doc["start"]["objectives"][0]
        name = row["objective"]
        opt.append(row["optimum"])
        ini.append(row.get("initial", np.nan))
        free.append(row.get("free", np.nan))
        free_what = (doc["start"].get("free") or {}).get("what")
        for k in headline:
            v = doc["best"]["metrics"].get(k)
            cols[k].append(np.nan if v is None else v)
    o, i, f = np.asarray(opt), np.asarray(ini, dtype=float), np.asarray(free, dtype=float)
    p = "—"
    if np.all(np.isfinite(f)) and np.any(o != f):
        p = f"{wilcoxon(o - f, alternative='two-sided').pvalue:.2g}"
    heads = " | ".join(f"{k} {_ms(np.asarray(v, dtype=float))}" for k, v in cols.items())
    free_col = f"{_ms(f)} ({free_what})" if free_what else "— "
    return (f"| {example} ({time.perf_counter() - t0:.0f} s) | {name} | {_ms(o)} | {_ms(i)} | "
            f"{free_col} | {p} | {heads} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--only", default="", help="substring of the example file names")
    args = ap.parse_args()
    seeds = list(range(1, args.seeds + 1))
    print(f"# bench_seeds — {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}, "
          f"seeds 1–{args.seeds}\n")
    print("| example | objective (minimised) | optimum | initial population's best | "
          "free solution (no search) | p (optimum vs free, two-sided) | "
          "headline metrics of the optimum |")
    print("|---|---|---|---|---|---|---|")
    for ex, heads in EXAMPLES.items():
        if args.only in ex:
            print(one(ex, seeds, heads), flush=True)


if __name__ == "__main__":
    main()
