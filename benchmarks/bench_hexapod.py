"""Seed 002 hexapod workspace: our MOEA/D and NSGA-II against pymoo's, same problem and budget.

    .venv/bin/python benchmarks/bench_hexapod.py [--seeds 10] [--pop 300] [--gen 100]

Problem: ``hexapod_workspace`` with the paper's settings (stance 1-3-5, θ1 ∈ [−π/6, π/6],
θ2 = −π/8, θ3 = −π/4; objectives f1, f2 in rad, f3 in m). Budget: ``pop × gen`` evaluations for
every algorithm — MOEA/D with N = pop weight vectors (Das–Dennis, 3 objectives: 300 is exact,
H = 23), T = 20, Tchebycheff, SBX(η=20, p=1) + PM(η=20); NSGA-II with pop_size = pop. pymoo's
MOEAD is given the same weight vectors, T, mating probability and operators and
``Tchebicheff()`` (its default for 3 objectives would be PBI); our NSGA-II runs at pymoo's
settings (``prob_mutant=0.9``). Hypervolume of each run's final
front against the study's fixed reference point ``HV_REF`` (1°, 1°, 1 mm), also shown normalised
by the reference box volume. Like against like: every front is the non-dominated part of the
final population — our MOEA/D runs with ``archive_size=0`` (the study's default keeps an
external archive; pymoo's MOEAD has none). ``--archive`` scores ours on its archive instead
(not comparable with pymoo's).

Prints a table: algorithm, wall time mean ± sd (s), HV mean ± sd, normalised HV mean.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np
from pymoo.core.problem import Problem as PymooProblem

from legcore.metrics import hypervolume
from legcore.optimizers import MaxGenerations, get_algorithm, minimize
from legcore.optimizers.moead import lattice_divisions
from legcore.robots import catalog
from legcore.studies.hexapod_workspace.problem import HV_REF, Params
from legcore.studies.hexapod_workspace.study import build

REF = np.asarray(HV_REF)


def make_problem() -> Any:
    return build(catalog.get("citedi_hexapod"), Params())


class AsPymoo(PymooProblem):
    """Our vectorised problem seen by pymoo (it calls ``evaluate`` with whatever batch it has)."""

    def __init__(self, problem: Any) -> None:
        self.inner = problem
        super().__init__(n_var=problem.n_var, n_obj=problem.n_obj, xl=problem.xl, xu=problem.xu)

    def _evaluate(self, X: np.ndarray, out: dict, *args: Any, **kwargs: Any) -> None:
        out["F"] = self.inner.evaluate(X)[0]


def run_ours(
    kind: str, seed: int, pop: int, gen: int, archive: bool = False
) -> tuple[float, np.ndarray]:
    problem = make_problem()
    params: dict[str, Any] = (  # NSGA-II at pymoo's settings: an offspring mutated w.p. 0.9
        {"n_subproblems": pop, "n_neighbors": 20, **({} if archive else {"archive_size": 0})}
        if kind == "moead" else {"pop_size": pop, "prob_mutant": 0.9}
    )
    algo = get_algorithm(kind, **params)
    t0 = time.perf_counter()
    res = minimize(problem, algo, MaxGenerations(gen), seed=seed)
    return time.perf_counter() - t0, np.asarray(res.front_F)


def run_pymoo(kind: str, seed: int, pop: int, gen: int) -> tuple[float, np.ndarray]:
    from pymoo.algorithms.moo.moead import MOEAD
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.decomposition.tchebicheff import Tchebicheff
    from pymoo.operators.crossover.sbx import SBX
    from pymoo.operators.mutation.pm import PM
    from pymoo.optimize import minimize as pymoo_minimize
    from pymoo.util.ref_dirs import get_reference_directions

    problem = AsPymoo(make_problem())
    if kind == "moead":
        dirs = get_reference_directions("das-dennis", 3, n_partitions=lattice_divisions(3, pop))
        algo = MOEAD(dirs, n_neighbors=20, prob_neighbor_mating=0.9,
                     decomposition=Tchebicheff(), crossover=SBX(prob=1.0, eta=20),
                     mutation=PM(eta=20))
    else:
        algo = NSGA2(pop_size=pop)
    t0 = time.perf_counter()
    res = pymoo_minimize(problem, algo, ("n_gen", gen), seed=seed)
    return time.perf_counter() - t0, np.asarray(res.F)


def compare(seeds: list[int], pop: int, gen: int, which: tuple[str, ...] = (
        "ours moead", "pymoo moead", "ours nsga2", "pymoo nsga2"),
        archive: bool = False) -> dict[str, np.ndarray]:
    """{label: (n_seeds, 2) [wall s, HV]} for the algorithms in ``which``."""
    out: dict[str, np.ndarray] = {}
    for label in which:
        impl, kind = label.split()
        rows = []
        for s in seeds:
            if impl == "ours":
                dt, F = run_ours(kind, s, pop, gen, archive)
            else:
                dt, F = run_pymoo(kind, s, pop, gen)
            rows.append((dt, hypervolume(F, REF).value))
        out[label] = np.array(rows)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--pop", type=int, default=300)
    ap.add_argument("--gen", type=int, default=100)
    ap.add_argument("--archive", action="store_true",
                    help="score our MOEA/D on its external archive (not like for like)")
    a = ap.parse_args()
    run_ours("moead", 0, 20, 2)  # warm-up (imports)
    res = compare(list(range(a.seeds)), a.pop, a.gen, archive=a.archive)
    vol = float(np.prod(REF))
    print(f"hexapod_workspace (seed 002), {a.pop} x {a.gen}, seeds 0..{a.seeds - 1}, "
          f"HV reference point {tuple(float(r) for r in REF)} (box volume {vol:.4g})")
    print(f"{'algorithm':<13} {'wall s (mean ± sd)':>20} {'HV (mean ± sd)':>26} {'HV / box':>10}")
    for label, r in res.items():
        wall, hv = r[:, 0], r[:, 1]
        print(f"{label:<13} {wall.mean():>10.3f} ± {wall.std(ddof=1):<7.3f} "
              f"{hv.mean():>13.5e} ± {hv.std(ddof=1):<10.2e} {hv.mean() / vol:>10.5f}")
    from scipy.stats import mannwhitneyu

    for kind in ("moead", "nsga2"):  # two-sided rank test of the HVs over the seeds
        ours, theirs = res.get(f"ours {kind}"), res.get(f"pymoo {kind}")
        if ours is not None and theirs is not None and len(ours) > 1:
            p = mannwhitneyu(ours[:, 1], theirs[:, 1], alternative="two-sided").pvalue
            print(f"{kind}: HV ours vs pymoo, Mann-Whitney U p = {p:.3g}"
                  + (" (ours on its archive: not like for like)" if a.archive and kind == "moead"
                     else ""))


if __name__ == "__main__":
    main()
