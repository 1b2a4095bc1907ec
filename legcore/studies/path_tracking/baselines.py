"""The baselines of a ``path_tracking`` run, its front in readable form and its reference
optimum.

- ``time_optimal`` — the physical minimum (TOPP-RA, :mod:`legcore.studies.path_tracking.optimal`):
  the shortest cycle time any time law can have on this path under these limits;
- ``seed`` — the paper's own law (one speed V, t_a, t_d, linear ramps);
- ``seed_max_V`` — the same scheme at the largest single V that keeps every limit.

Baselines are time laws, not decision vectors: each is decoded by
:meth:`TrackingProblem.decode_law` with its violations checked here (on a dense resampling),
and carries a decision vector only where it has one in the problem's encoding.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore.studies.path_tracking import limits
from legcore.studies.path_tracking.contract import TrackingProblem
from legcore.studies.path_tracking.encodings import SegmentSpeeds
from legcore.studies.path_tracking.timelaw import TimeLaw
from legcore.studies.study import Solution

__all__ = ["baseline_solutions", "extras", "reference_optimum", "seed_max_V"]

FloatArray = NDArray[np.float64]


def seed_max_V(problem: TrackingProblem) -> float:
    """Largest single V (m/s) for which the seed's scheme (t_a, t_d of ``params``, linear
    ramps) satisfies every constraint; found by batched scans of the V box (nan: none)."""
    assert problem.params.V_bounds is not None
    lo, hi = problem.params.V_bounds
    best = float("nan")
    for _ in range(3):
        Vs = np.linspace(lo, hi, 41)
        law = problem.seed_law(Vs)
        G = problem.simulate(law, full=False)["G"]
        if problem.limit_check > 1:
            G = limits.dense_limits(problem, law, G, problem.limit_check)
        ok = np.all(G <= 0.0, axis=1)
        if not ok.any():
            break
        i = int(np.flatnonzero(ok).max())
        best = float(Vs[i])
        if i == Vs.size - 1:
            break
        lo, hi = Vs[i], Vs[i + 1]
    return best


def _seed_solution(problem: TrackingProblem, V: float) -> Solution:
    """The seed's law at speed ``V`` decoded, with its violations."""
    p = problem.params
    trapezoid: SegmentSpeeds = problem.trapezoid
    x = trapezoid.x_of(V, p.t_a, p.t_d, p.ramp_bounds[0])
    law = trapezoid.law(x[None, :], "linear")
    own = x if problem.encoding is trapezoid else None
    sol = problem.decode_law(law, own, trapezoid.metrics(x), "linear")
    return _with_violations(problem, sol, law)


def _with_violations(problem: TrackingProblem, sol: Solution, law: TimeLaw) -> Solution:
    """``sol`` with what its ``law`` violates (a dense resampling, as every answer)."""
    return dataclasses.replace(sol, violations=limits.limit_violations(problem, law))


def baseline_solutions(problem: TrackingProblem) -> dict[str, Solution]:
    """``time_optimal`` (when a profile exists), ``seed`` and ``seed_max_V`` (when the seed's
    scheme is feasible at some V)."""
    out: dict[str, Solution] = {}
    best = problem.time_optimal
    if best is not None:
        sol = problem.decode_law(best.law, None, {"v_peak": float(best.speed.max()),
                                             "limit_scale": best.scale})
        out["time_optimal"] = _with_violations(problem, sol, best.law)
    assert problem.params.V is not None
    out["seed"] = _seed_solution(problem, problem.params.V)
    v = problem.seed_max_V
    if math.isfinite(v):
        out["seed_max_V"] = _seed_solution(problem, v)
    return out


def reference_optimum(problem: TrackingProblem) -> dict[str, Any] | None:
    """The best any answer can do on a single ``time`` objective: the physical minimum's
    cycle time (s), with what it is; None for other objectives or when no profile exists."""
    best = problem.time_optimal
    if problem.objective_names != ("time",) or best is None:
        return None
    return {"objective": "time", "value": best.T, "kind": "physical minimum",
            "method": f"TOPP-RA, {best.grid.size - 1} intervals, limits × {best.scale:.6g}"}


def extras(problem: TrackingProblem, front_X: FloatArray, front_F: FloatArray
           ) -> dict[str, Any]:
    """The front in readable form with the % change of each objective against the seed law
    (only when that law is feasible on this arm: else None, and ``change_pct_reason`` says
    which limits it breaks), and the physical minimum (``time_optimal``: T s, its grid and
    limit scale, the raw TOPP-RA T at the limits themselves)."""
    seed = problem.objectives(problem.simulate(problem.seed_law()))[0]
    broken = problem.seed_violations()
    rows = []
    for x, f in zip(np.atleast_2d(front_X), np.atleast_2d(front_F), strict=True):
        row: dict[str, Any] = {
            name: float(v) for name, v in zip(problem.variable_names, x, strict=True)}
        row |= {name: float(v) for name, v in zip(problem.objective_names, f, strict=True)}
        row |= {f"{name}_change_pct": None if broken else float(100.0 * (v / s - 1.0))
                for name, v, s in zip(problem.objective_names, f, seed, strict=True)}
        rows.append(row)
    rows.sort(key=lambda r: r[problem.objective_names[0]])
    out: dict[str, Any] = {
        "seed_objectives": dict(zip(problem.objective_names, seed.tolist(), strict=True)),
        "seed_feasible": not broken,
        "seed_max_V": problem.seed_max_V,
        "front": rows,
    }
    best = problem.time_optimal
    out["time_optimal"] = None if best is None else best.as_dict()
    if best is None:
        out["time_optimal_reason"] = (
            "no time-optimal profile: the limits cannot be kept on this path at any speed "
            "(a torque limit below what gravity alone asks somewhere on it)")
    if broken:
        out["change_pct_reason"] = (
            "no % change: the reference (the paper's time law) is infeasible on "
            f"{problem.robot.name}: " + "; ".join(v.text for v in broken))
    return out
