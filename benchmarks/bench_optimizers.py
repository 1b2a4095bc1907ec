"""Our MOEA/D and NSGA-II against pymoo's on the same problem, budget and reference point;
our GA at the seed-000 setting (100 x 100) on a 30-variable integer problem.

    .venv/bin/python benchmarks/bench_optimizers.py [--problem dtlz2] [--pop 300] [--gens 100]
        [--seeds 0 1 2] [--skip-pymoo-moead] [--skip-ga]

``--problem`` is a name of ``PROBLEMS`` below (``zdt1``, ``zdt2``, ``dtlz2``), ``study:KIND`` for
a seed study's default problem (e.g. ``study:hexapod_workspace``, seed 002: its default robot and
parameters), or an import path ``package.module:factory`` of a zero-argument callable returning
a legcore ``Problem``, so any problem can be plugged in without editing this file. For a problem
with constraints pymoo's MOEAD is skipped (it does not support them).

For each algorithm and implementation: mean wall time over the seeds (our run includes
everything the driver does; pymoo's is its ``minimize``), the hypervolume of the final front
(mean ± std) against ONE reference point for all runs (the problem's, or the nadir of all fronts
+ 10 %), and the ratios ours/pymoo. Both MOEA/Ds use Tchebycheff decomposition, the same
Das–Dennis weights and T = 20; both NSGA-IIs use SBX(15) + PM(20).
"""

from __future__ import annotations

import argparse
import importlib
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from legcore.metrics import hypervolume, reference_point
from legcore.optimizers import MaxGenerations, get_algorithm, minimize
from legcore.optimizers.moead import simplex_lattice
from legcore.problems import Problem
from legcore.problems.benchmarks import DTLZ2, ZDT1, ZDT2, Rastrigin


@dataclass(frozen=True)
class BenchProblem:
    """A problem to benchmark and, if known, its reference point for the hypervolume."""

    make: Callable[[], Problem]
    ref_point: tuple[float, ...] | None = None


PROBLEMS: dict[str, BenchProblem] = {
    "zdt1": BenchProblem(lambda: ZDT1(30), (1.1, 1.1)),
    "zdt2": BenchProblem(lambda: ZDT2(30), (1.1, 1.1)),
    "dtlz2": BenchProblem(lambda: DTLZ2(12, 3), (1.1, 1.1, 1.1)),
}


def study_problem(kind: str) -> Problem:
    """The default problem of a seed study (its default robot and parameters)."""
    from legcore.problems.registry import get_study
    from legcore.robots import catalog

    study = get_study(kind)
    return study.build(catalog.get(study.default_robot), study.params())


def load_problem(name: str) -> BenchProblem:
    """A registered name, ``study:KIND``, or ``module:factory`` returning a Problem."""
    if name in PROBLEMS:
        return PROBLEMS[name]
    if name.startswith("study:"):
        kind = name.split(":", 1)[1]
        return BenchProblem(lambda: study_problem(kind), None)
    if ":" not in name:
        raise SystemExit(f"--problem: unknown {name!r}; use one of {sorted(PROBLEMS)}, "
                         "study:KIND or package.module:factory")
    module, attr = name.split(":", 1)
    factory = getattr(importlib.import_module(module), attr)
    return BenchProblem(factory, None)


def as_pymoo(problem: Problem) -> Any:
    """Wrap a legcore Problem for pymoo (vectorised evaluation, same numbers)."""
    from pymoo.core.problem import Problem as PymooProblem

    class Wrapped(PymooProblem):
        def __init__(self) -> None:
            super().__init__(n_var=problem.n_var, n_obj=problem.n_obj,
                             n_ieq_constr=problem.n_constr, xl=problem.xl, xu=problem.xu)

        def _evaluate(self, X: np.ndarray, out: dict, *args: Any, **kwargs: Any) -> None:
            F, G = problem.evaluate(X)
            out["F"] = F
            if problem.n_constr:
                out["G"] = G

    return Wrapped()


def run_ours(kind: str, problem: Problem, pop: int, gens: int, seed: int) -> tuple[float, Any]:
    params = {"n_subproblems": pop} if kind == "moead" else {"pop_size": pop}
    t0 = time.perf_counter()
    res = minimize(problem, get_algorithm(kind, **params), MaxGenerations(gens), seed=seed)
    return time.perf_counter() - t0, res.front_F


def run_pymoo(kind: str, problem: Problem, pop: int, gens: int, seed: int) -> tuple[float, Any]:
    from pymoo.algorithms.moo.moead import MOEAD
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.decomposition.tchebicheff import Tchebicheff
    from pymoo.optimize import minimize as pymoo_minimize

    if kind == "moead":
        weights = simplex_lattice(problem.n_obj, pop)  # the same weights as ours
        algo = MOEAD(weights, n_neighbors=20, decomposition=Tchebicheff())
    else:
        algo = NSGA2(pop_size=pop)
    wrapped = as_pymoo(problem)
    t0 = time.perf_counter()
    res = pymoo_minimize(wrapped, algo, ("n_gen", gens), seed=seed)
    elapsed = time.perf_counter() - t0
    F = res.F if res.F is not None else np.zeros((0, problem.n_obj))
    return elapsed, np.atleast_2d(F)


def compare(args: argparse.Namespace) -> None:
    bench = load_problem(args.problem)
    problem = bench.make()
    print(f"problem {args.problem}: n_var={problem.n_var} n_obj={problem.n_obj} "
          f"n_constr={problem.n_constr}; population {args.pop} x {args.gens} generations; "
          f"seeds {args.seeds}")
    # warm-up (imports, first-call costs) outside the timings
    run_ours("nsga2", problem, 8, 2, 0)
    run_pymoo("nsga2", problem, 8, 2, 0)

    runs: dict[tuple[str, str], list[tuple[float, np.ndarray]]] = {}
    for kind in ("moead", "nsga2"):
        for impl in ("ours", "pymoo"):
            if impl == "pymoo" and kind == "moead" and (args.skip_pymoo_moead or problem.n_constr):
                continue
            fn = run_ours if impl == "ours" else run_pymoo
            runs[(kind, impl)] = [fn(kind, problem, args.pop, args.gens, s) for s in args.seeds]

    if bench.ref_point is not None:
        ref = np.asarray(bench.ref_point, dtype=float)
    else:
        ref = reference_point(np.vstack([F for r in runs.values() for _, F in r if len(F)]))
    print(f"reference point {tuple(round(float(v), 6) for v in ref)}\n")
    print(f"{'algorithm':10s} {'impl':6s} {'time s':>8s} {'HV mean':>9s} {'HV std':>8s} "
          f"{'time ratio':>11s} {'HV ratio':>9s}")
    stats: dict[tuple[str, str], tuple[float, float, float]] = {}
    for (kind, impl), r in runs.items():
        t = float(np.mean([e for e, _ in r]))
        hvs = np.array([hypervolume(F, ref).value if len(F) else 0.0 for _, F in r])
        stats[(kind, impl)] = (t, float(hvs.mean()), float(hvs.std()))
    for (kind, impl), (t, hv, sd) in stats.items():
        ratio_t = ratio_hv = ""
        if impl == "ours" and (kind, "pymoo") in stats:
            pt, phv, _ = stats[(kind, "pymoo")]
            ratio_t = f"{t / pt:.3f}"
            ratio_hv = f"{hv / phv:.4f}" if phv > 0 else "-"
        print(f"{kind:10s} {impl:6s} {t:8.3f} {hv:9.5f} {sd:8.5f} {ratio_t:>11s} {ratio_hv:>9s}")
    print("\n(time ratio = ours / pymoo, < 1 is faster; HV ratio = ours / pymoo)")


def ga_at_seed_setting(args: argparse.Namespace) -> None:
    problem = Rastrigin(30, resolution=0.01)
    print("\nGA, seed 000 setting: population 100 x 100 generations, mutation 3 %, "
          "on Rastrigin with 30 integer genes (resolution 0.01, [-5.12, 5.12])")
    times, best, evals = [], [], 0
    for s in args.seeds:
        t0 = time.perf_counter()
        res = minimize(problem, get_algorithm("ga"), MaxGenerations(100), seed=s)
        times.append(time.perf_counter() - t0)
        best.append(float(res.F[0]))
        evals = res.n_evals
        k = res.x / 0.01
        assert np.allclose(k, np.rint(k), atol=1e-9), "a solution left the grid"
    rng = np.random.default_rng(0)
    random_best = float(problem.evaluate(problem.snap(
        rng.uniform(problem.xl, problem.xu, (evals, problem.n_var))))[0].min())
    print(f"time {np.mean(times):.3f} s per run ({evals} evaluations); best f "
          f"{np.median(best):.3f} median over seeds (min {min(best):.3f}); "
          f"random search with the same budget: {random_best:.3f}; optimum 0")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--problem", default="dtlz2")
    ap.add_argument("--pop", type=int, default=300)
    ap.add_argument("--gens", type=int, default=100)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--skip-pymoo-moead", action="store_true",
                    help="pymoo's MOEAD evaluates one offspring at a time and is slow")
    ap.add_argument("--skip-ga", action="store_true")
    args = ap.parse_args()
    compare(args)
    if not args.skip_ga:
        ga_at_seed_setting(args)


if __name__ == "__main__":
    main()
