"""How far the metaheuristics end from a gradient-based optimum, and how fast they get near it.

    python benchmarks/bench_optimum.py [--quick] [--seeds N] [--cases flat obstacle tracking]

Cases (each example's own problem, single objective): seed 000 flat and obstacle
(``examples/000_swing_energy_*.yaml``, score to maximise, best 10), seed 001 pan and jar
(``examples/001_path_placement_*.yaml``, the placement objective J), seed 003
(``examples/003_quadruped_gait.yaml``, energy per metre) and seed 004
(``examples/004_path_tracking.yaml``, cycle time T to minimise; its exact reference, the
physical minimum, is ``bench_time_optimal.py``'s). Seed 002 has three objectives: no single gap.

1. **Gradient optimum.** Multi-start :func:`legcore.optimizers.refine.refine` (SLSQP on the
   continuous relaxation, batched central finite differences, ``max_iter`` 300) from the
   problem's own reference points (seed 000: the coordinated motion and the five paper
   baselines; seed 004: the seed's law and its fastest single-speed variant) and 6 random
   points of the decision box. Reported: the best value on the problem's own decision space
   (seed 000: on the control grid, feasible), the best relaxed (off-grid) value SLSQP met,
   evaluations and seconds of the whole multi-start.
2. **Metaheuristics** at the example's budget, ``--seeds`` seeds: the example's optimiser (GA for
   seed 000, NSGA-II for seed 004) and HKA (its defaults, the same number of evaluations):
   mean ± sd of the best over the feasible runs, how many are feasible, gap to the optimum in %
   (``(F − F*) / |F*|``, positive = worse), and time-to-quality: median evaluations and seconds
   (over the seeds that get there) until the best is feasible and within 1 % / 5 % of the
   optimum, with how many seeds get there.
3. **GA + refine**: each metaheuristic best refined (``max_iter`` 100, what
   ``optimizer.refine: true`` does): its extra evaluations and seconds, and how many refined
   runs end within 1 % / 5 % (median total cost of those).

The optimum used for the gaps is the best of the multi-start and of every refined
metaheuristic result ("best known"), so a gap is never measured against a worse point.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from legcore.optimizers import Run, get_algorithm
from legcore.optimizers.refine import refine
from legcore.runner import prepare

ROOT = Path(__file__).resolve().parents[1]
CASES = {
    "flat": "000_swing_energy_flat.yaml",
    "obstacle": "000_swing_energy_obstacle.yaml",
    "pan": "001_path_placement_pan.yaml",
    "jar": "001_path_placement_jar.yaml",
    "gait": "003_quadruped_gait.yaml",
    "tracking": "004_path_tracking.yaml",
}


@dataclass
class AlgoRuns:
    """The runs of one optimiser on one case (F minimised; ``hist`` per run: rows of
    (n_evals, elapsed s, best F, best cv))."""

    label: str
    F: list[float]
    cv: list[float]
    hist: list[np.ndarray]
    evals: list[int]
    seconds: list[float]
    F_ref: list[float]
    cv_ref: list[float]
    ref_evals: list[int]
    ref_seconds: list[float]


def starts(problem: Any, rng: np.random.Generator, n_random: int) -> dict[str, np.ndarray]:
    """The multi-start points: the problem's reference points and random points of the box."""
    out: dict[str, np.ndarray] = {}
    if hasattr(problem, "coordinated_x"):
        out["coordinated"] = problem.coordinated_x()
    if hasattr(problem, "seed_x"):
        out["seed law"] = problem.seed_x()
        if hasattr(problem, "seed_max_V"):
            out["seed max V"] = problem.seed_x(problem.seed_max_V)
    out.update(problem.baselines())
    for k in range(n_random):
        out[f"random {k}"] = problem.snap(rng.uniform(problem.xl, problem.xu)[None])[0]
    return {k: np.clip(v, problem.xl, problem.xu) for k, v in out.items()}


def gradient_optimum(problem: Any, n_random: int, max_iter: int) -> dict[str, Any]:
    """Multi-start SLSQP refine; the best feasible value and the trace of cumulative cost."""
    points = starts(problem, np.random.default_rng(0), n_random)
    t0 = time.perf_counter()
    best_f, best_relaxed, evals = np.inf, np.inf, 0
    trace = []  # (cumulative evals, cumulative s, best feasible F so far)
    for x0 in points.values():
        r = refine(problem, x0, max_iter=max_iter)
        evals += r.n_evals
        if r.cv <= 0.0:
            best_f = min(best_f, r.f)
        if r.relaxed_f is not None and r.relaxed_cv is not None and r.relaxed_cv <= 0.0:
            best_relaxed = min(best_relaxed, r.relaxed_f)
        trace.append((evals, time.perf_counter() - t0, best_f))
    return {"f": best_f, "relaxed": best_relaxed, "evals": evals,
            "seconds": time.perf_counter() - t0, "trace": np.array(trace), "n_starts": len(trace)}


def run_algo(prepared: Any, kind: str, params: dict[str, Any], seeds: list[int],
             budget_evals: int | None, label: str) -> AlgoRuns:
    """``seeds`` runs of one optimiser (the example's termination, or ``budget_evals``), each
    best then refined."""
    from legcore.optimizers import MaxEvaluations

    problem = prepared.problem
    out = AlgoRuns(label, [], [], [], [], [], [], [], [], [])
    for seed in seeds:
        term = prepared.termination if budget_evals is None else MaxEvaluations(budget_evals)
        r = Run(problem, get_algorithm(kind, **params), term, seed=seed)
        while not r.done:
            r.step()
        res = r.result()
        out.F.append(float(res.F[0]))
        out.cv.append(float(res.cv))
        out.hist.append(np.array([(h.n_evals, h.elapsed, h.best_f[0], h.best_cv)
                                  for h in res.history]))
        out.evals.append(res.n_evals)
        out.seconds.append(res.elapsed)
        ref = refine(problem, np.asarray(res.x), max_iter=100)
        out.F_ref.append(ref.f)
        out.cv_ref.append(ref.cv)
        out.ref_evals.append(ref.n_evals)
        out.ref_seconds.append(ref.elapsed_s)
    return out


def gap(F: float, F_opt: float) -> float:
    """Relative gap in % to the optimum (positive = worse)."""
    return 100.0 * (F - F_opt) / abs(F_opt)


def time_to(hist: list[np.ndarray], F_opt: float, pct: float) -> tuple[str, str, int]:
    """Median evaluations and seconds to a feasible best within ``pct`` % of ``F_opt``."""
    ev, sec = [], []
    for h in hist:
        ok = (h[:, 3] <= 0.0) & (h[:, 2] <= F_opt + pct / 100.0 * abs(F_opt))
        if ok.any():
            k = int(np.argmax(ok))
            ev.append(h[k, 0])
            sec.append(h[k, 1])
    if not ev:
        return "—", "—", 0
    return f"{np.median(ev):,.0f}", f"{np.median(sec):.2f}", len(ev)


def mean_sd(values: list[float] | np.ndarray, digits: str = ".4g") -> str:
    a = np.asarray(values, dtype=float)
    if a.size == 0:
        return "— (none feasible)"
    return f"{a.mean():{digits}} ± {a.std(ddof=1) if a.size > 1 else 0.0:.2g}"


def summarise(case: str, label: str, F: list[float], cv: list[float], F_opt: float, sign: float,
              cost: tuple[str, str], reach: tuple[str, str]) -> tuple[str, ...]:
    """One table row: value and gap over the feasible runs only."""
    feas = [f for f, c in zip(F, cv, strict=True) if c <= 0.0]
    gaps = [gap(f, F_opt) for f in feas]
    return (case, label, mean_sd([sign * f for f in feas]), f"{len(feas)}/{len(F)}",
            mean_sd(gaps, "+.2f"), *cost, *reach)


def reach_after_refine(a: AlgoRuns, F_opt: float, pct: float) -> str:
    """Median total evaluations / seconds (run + refine) of the refined runs within ``pct`` %."""
    ok = [k for k, (f, c) in enumerate(zip(a.F_ref, a.cv_ref, strict=True))
          if c <= 0.0 and f <= F_opt + pct / 100.0 * abs(F_opt)]
    if not ok:
        return f"— (0/{len(a.F_ref)})"
    ev = np.median([a.evals[k] + a.ref_evals[k] for k in ok])
    sec = np.median([a.seconds[k] + a.ref_seconds[k] for k in ok])
    return f"{ev:,.0f} / {sec:.2f} s ({len(ok)}/{len(a.F_ref)})"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="3 seeds, 2 random starts")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--cases", nargs="*", default=list(CASES))
    args = ap.parse_args()
    n_seeds = 3 if args.quick else args.seeds
    n_random = 2 if args.quick else 6
    seeds = list(range(n_seeds))
    rows = []
    for case in args.cases:
        spec = yaml.safe_load((ROOT / "examples" / CASES[case]).read_text())
        spec["record"] = False
        prepared = prepare(spec)
        problem = prepared.problem
        sign = -1.0 if problem.objective_names == ("neg_score",) else 1.0  # reported value
        opt = gradient_optimum(problem, n_random, max_iter=300)
        ex = prepared.spec.optimizer
        assert ex is not None
        runs = [run_algo(prepared, ex.kind, dict(ex.params), seeds, None, ex.kind.upper())]
        budget = int(np.median(runs[0].evals))
        runs.append(run_algo(prepared, "hka", {}, seeds, budget, "HKA"))
        feas_ref = [f for a in runs for f, c in zip(a.F_ref, a.cv_ref, strict=True) if c <= 0]
        F_opt = min([opt["f"], *feas_ref])
        trace = opt["trace"]
        grad_tq = []
        for pct in (1.0, 5.0):
            ok = trace[:, 2] <= F_opt + pct / 100.0 * abs(F_opt)
            k = int(np.argmax(ok)) if ok.any() else -1
            grad_tq.append("—" if k < 0 else f"{trace[k, 0]:,.0f} / {trace[k, 1]:.2f} s")
        print(f"\n== {case}: {problem} ({CASES[case]})")
        print(f"gradient multi-start ({opt['n_starts']} starts): best {sign * opt['f']:.6g} on the "
              f"decision space, relaxed {sign * opt['relaxed']:.6g}, {opt['evals']:,} evals, "
              f"{opt['seconds']:.1f} s; to 1 %: {grad_tq[0]}, to 5 %: {grad_tq[1]} (evals / s)")
        print(f"best known (multi-start and refined metaheuristics): {sign * F_opt:.6g}; the "
              f"multi-start is {gap(opt['f'], F_opt):+.2f} % from it")
        rows.append((case, "gradient multi-start", f"{sign * opt['f']:.5g}",
                     f"{opt['n_starts']} starts", f"{gap(opt['f'], F_opt):+.2f}",
                     f"{opt['evals']:,}", f"{opt['seconds']:.2f}", grad_tq[0], grad_tq[1]))
        if problem.is_integer:
            rows.append((case, "gradient, relaxed (off the grid)", f"{sign * opt['relaxed']:.5g}",
                         "", f"{gap(opt['relaxed'], F_opt):+.2f}", "", "", "", ""))
        for a in runs:
            t1 = time_to(a.hist, F_opt, 1.0)
            t5 = time_to(a.hist, F_opt, 5.0)
            rows.append(summarise(
                case, a.label, a.F, a.cv, F_opt, sign,
                (f"{np.mean(a.evals):,.0f}", f"{np.mean(a.seconds):.2f}"),
                (f"{t1[0]} / {t1[1]} s ({t1[2]}/{len(a.F)})",
                 f"{t5[0]} / {t5[1]} s ({t5[2]}/{len(a.F)})")))
            rows.append(summarise(
                case, f"{a.label} + refine", a.F_ref, a.cv_ref, F_opt, sign,
                (f"+{np.mean(a.ref_evals):,.0f}", f"+{np.mean(a.ref_seconds):.2f}"),
                (reach_after_refine(a, F_opt, 1.0), reach_after_refine(a, F_opt, 5.0))))
    head = ("case", "method", "best (mean ± sd)", "feasible", "gap to optimum %", "evals",
            "s", "to 1 %: evals / s (seeds)", "to 5 %: evals / s (seeds)")
    print("\n| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in rows:
        print("| " + " | ".join(r) + " |")
    print(f"\n{n_seeds} seeds; best = score for seed 000 (max 10), T in s for seed 004, mean ± "
          "sd over the feasible runs; gap = (F − F*) / |F*| against the best known feasible "
          "value F* on the decision space; time-to-quality: median over the runs that get there "
          "(+ refine: run + refine), gradient: cumulative over the starts, reference points "
          "first.")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
