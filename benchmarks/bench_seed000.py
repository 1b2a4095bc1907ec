"""Seed 000 over seeds (issue 11): the proposed GA (deviation coding and the paper's literal
coding) against the literature's GA baselines, ≥ 10 seeds each at equal budgets, with a rank test.

Every GA here — the proposed score GA and the three GA baselines (min θ_T, multi-criteria,
min energy) — runs the seed's budget (population 100 × 100 generations, 3 % mutation, the same
operators); seeds 1..N for the proposed runs and ``baseline_seed`` 1..N for the baselines. The
parabolic and shortest-path baselines are constructions (one value). p: two-sided Mann–Whitney U
of the N energies of the proposed run vs each GA baseline's N energies; against a construction,
a one-sample Wilcoxon signed-rank test of the N energies minus its value.

    python3 run.py bench seed000            # N = 10, both cases (~10 min on 2 loaded cores)
    .venv/bin/python benchmarks/bench_seed000.py --seeds 3 --case flat
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from scipy.stats import mannwhitneyu, wilcoxon

from legcore.runner import prepare, run

ROOT = Path(__file__).resolve().parents[1]
CASES = {"flat": "examples/000_swing_energy_flat.yaml",
         "obstacle": "examples/000_swing_energy_obstacle.yaml"}
GA_BASELINES = ("tian_collins2004_min_displacement", "solteiro2007_multi_criteria",
                "perez2010_min_energy")
CONSTRUCTIONS = ("calderon2008_parabolic", "shankar_kaur2011_min_distance")


def _spec(case: str) -> dict[str, Any]:
    with open(ROOT / CASES[case]) as fh:
        spec: dict[str, Any] = yaml.safe_load(fh)
    spec["record"] = False
    return spec


def proposed(case: str, seeds: list[int], encoding: str) -> dict[str, np.ndarray]:
    """Energy (J), score and feasibility of the proposed GA's optimum per seed."""
    out: dict[str, list[float]] = {"energy": [], "score": [], "feasible": [], "initial": []}
    for seed in seeds:
        spec = _spec(case)
        spec["seed"] = seed
        spec["problem"]["encoding"] = encoding
        spec["problem"]["baselines"] = ["calderon2008_parabolic"]  # cheap; others below
        doc = run(spec).to_dict()
        m = doc["best"]["metrics"]
        out["energy"].append(m["energy_total"])
        out["score"].append(m["score"])
        out["feasible"].append(m["feasible"])
        out["initial"].append(-doc["start"]["objectives"][0]["initial"])
    return {k: np.asarray(v) for k, v in out.items()}


def baselines(case: str, seeds: list[int]) -> dict[str, dict[str, np.ndarray]]:
    """Energy and score of every baseline; the GA ones per ``baseline_seed``."""
    res: dict[str, dict[str, list[float]]] = {}
    for seed in seeds:
        spec = _spec(case)
        spec["problem"]["baseline_seed"] = seed
        sols = prepare(spec).problem.baseline_solutions()
        for name, sol in sols.items():
            if name in CONSTRUCTIONS and name in res:
                continue
            r = res.setdefault(name, {"energy": [], "score": [], "feasible": []})
            r["energy"].append(sol.metrics["energy_total"])
            r["score"].append(sol.metrics["score"])
            r["feasible"].append(sol.metrics["feasible"])
    return {n: {k: np.asarray(v) for k, v in d.items()} for n, d in res.items()}


def _ms(a: np.ndarray, digits: int = 4) -> str:
    if a.size == 1:
        return f"{a[0]:.{digits}g}"
    return f"{a.mean():.{digits}g} ± {a.std(ddof=1):.2g}"


def _p(ours: np.ndarray, other: np.ndarray) -> str:
    if other.size == 1:
        d = ours - other[0]
        if np.all(d == 0):
            return "equal"
        return f"{wilcoxon(d).pvalue:.2g} (Wilcoxon)"
    return f"{mannwhitneyu(ours, other, alternative='two-sided').pvalue:.2g}"


def table(case: str, n: int) -> str:
    seeds = list(range(1, n + 1))
    t0 = time.perf_counter()
    dev = proposed(case, seeds, "deviation")
    lit = proposed(case, seeds, "absolute")
    base = baselines(case, seeds)
    elapsed = time.perf_counter() - t0
    head = ("| trajectory | energy ∫\\|τω\\|dt (J) | score F | feasible "
            "| energy vs proposed (deviation): Mann–Whitney p | vs proposed (literal) |")
    rows = [f"### Case {case} — {n} seeds ({elapsed:.0f} s)", "", head, "|---|---|---|---|---|---|"]

    def row(name: str, d: dict, p_dev: str, p_lit: str) -> str:
        feasible = f"{int(d['feasible'].sum())}/{d['energy'].size}"
        return (f"| {name} | {_ms(d['energy'])} | {_ms(d['score'])} | {feasible} | {p_dev} "
                f"| {p_lit} |")

    rows.append(row("proposed GA, deviation coding (shipped)", dev, "—",
                    _p(dev["energy"], lit["energy"])))
    rows.append(row("proposed GA, literal coding (the paper's)", lit,
                    _p(lit["energy"], dev["energy"]), "—"))
    for name, d in base.items():
        kind = "construction" if name in CONSTRUCTIONS else "GA, same budget"
        rows.append(row(f"{name} ({kind})", d, _p(dev["energy"], d["energy"]),
                        _p(lit["energy"], d["energy"])))
    rows.append("")
    rows.append("Initial population's best score (what the GA started from): deviation "
                f"{_ms(dev['initial'])}, literal {_ms(lit['initial'])}.")
    return "\n".join(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--case", choices=[*CASES, "both"], default="both")
    args = ap.parse_args()
    print(f"# bench_seed000 — {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}\n")
    for case in (CASES if args.case == "both" else [args.case]):
        print(table(case, args.seeds), flush=True)
        print()


if __name__ == "__main__":
    main()
