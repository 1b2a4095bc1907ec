"""Baselines of the ``swing_energy`` study: the comparison trajectories of seed 000 Tables 2–5.

Every baseline is characterised like the GA's solutions — 10 intermediate via points on the
resolution grid, the same clamped cubic spline (the seed: "10 intermediate points in all the
exercises presented") — and decoded with the same metric table.

Constructions (deterministic, exact for their criterion up to the via-point characterisation):

- ``calderon2008_parabolic``: the foot follows a parabola in the vertical plane of the
  start→end chord, apex ``step_height`` (0.065 m) above it at mid-stride,
  ``p(s) = p_s + (p_e − p_s) s + ẑ 4 h s (1 − s)``; via point j is the IK of
  ``p(j/(K_via + 1))`` (:func:`legcore.ik.solve` along the path from the start posture: the
  closed form where the leg has one, else numerical), rounded to the grid.
- ``shankar_kaur2011_min_distance``: the shortest foot path — the straight chord on flat
  ground; with boxes, the taut string over them in the chord's vertical plane (start → each
  crossed box's near top edge → far top edge → end, the boxes grown by their margins). Via
  points at equal path-length fractions, IK, grid. If the spline between via points dips into
  the ground or a box, the path is raised 1 mm at a time until it clears (at most 50 mm).

GA baselines (the study's GA with the literature's criterion instead of the score; same
encoding, constraints and operators; ``baseline_pop_size`` × ``baseline_generations`` with the
fixed seed ``baseline_seed``; Deb's feasibility rule):

- ``tian_collins2004_min_displacement``: minimise θ_T = Σ_i θ_{i,T} (eq 4).
- ``solteiro2007_multi_criteria``: minimise the mean of five normalised criteria
  (:func:`multi_criteria`): θ_T, D, peak foot speed, Σ_i peak joint speed and the mechanical
  energy, each divided by the parabolic baseline's value (Solteiro et al. optimise these jointly
  with a MOEA; the seed gives no weights — equal weights on values normalised by the robot's
  default swing is our choice).
- ``perez2010_min_energy``: minimise the mechanical energy Σ∫|τω|dt itself.

Gradient baseline (beyond the papers; issue 19):

- ``gradient_min_energy``: the same minimum-energy problem — the same via points, samples,
  spline and constraints — solved by a gradient method: SLSQP on the continuous via points with
  batched finite differences, then a ±1-step climb on the grid
  (:func:`legcore.optimizers.refine.refine`), from each of the coordinated motion, Pérez's GA
  optimum and every other baseline the job lists, the best end point kept (the minimum-energy
  swings lie in different basins: on seed 000's flat case the best start is the shortest foot
  path, with the box the minimum-displacement GA's optimum). A multi-start local optimum, not a
  certificate of the global one: the reference the metaheuristics' least energy is measured
  against. Not among the defaults (it costs ~10⁴ evaluations per start): list it in
  ``baselines``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore.ik import solve
from legcore.kinematics import fk
from legcore.optimizers import MaxGenerations, get_algorithm, minimize
from legcore.problems.base import Problem
from legcore.result_cache import cached, code_version, content_key
from legcore.studies.study import Solution
from legcore.studies.swing_energy.contract import SwingProblem
from legcore.studies.swing_energy.params import BASELINES

__all__ = [
    "MULTI_TERMS",
    "compute_baselines",
    "ga_baseline_criteria",
    "min_distance_via",
    "multi_criteria",
    "parabolic_via",
    "reference_values",
]

FloatArray = NDArray[np.float64]

#: The five terms of the Solteiro-style criterion (keys of the ``refs`` normalisers).
MULTI_TERMS = ("theta_total", "path_length", "foot_speed_max", "joint_speed_sum", "energy")

_REF_FLOOR = {"theta_total": 1e-3, "path_length": 1e-3, "foot_speed_max": 1e-3,
              "joint_speed_sum": 1e-3, "energy": 1e-4}
_RAISE_STEP = 0.001  # m, per retry of the min-distance construction
_GRADIENT_ITER = 100  # SLSQP iterations of ``gradient_min_energy``, per start
_RAISE_MAX = 50


def multi_criteria(
    refs: dict[str, float], *, q: FloatArray, qd: FloatArray, D: FloatArray,
    v_foot: FloatArray, E: FloatArray,
) -> FloatArray:
    """Mean of the five normalised criteria (B,): θ_T, D, max foot speed, Σ_i max|q̇_i|, E.

    ``q``, ``qd`` (B, K, 3) rad, rad/s; ``D`` (B,) m; ``v_foot`` (B,) m/s; ``E`` (B,) J; ``refs``
    maps each of :data:`MULTI_TERMS` to its normaliser (same unit).
    """
    theta = np.sum(np.abs(np.diff(q, axis=-2)), axis=(-2, -1))
    omega = np.max(np.abs(qd), axis=-2).sum(axis=-1)
    values = (theta, D, v_foot, omega, E)
    total = np.zeros_like(theta)
    for key, v in zip(MULTI_TERMS, values, strict=True):
        total = total + v / refs[key]
    return total / len(MULTI_TERMS)


def _ik_via(problem: SwingProblem, p: FloatArray) -> FloatArray | None:
    """Via points (n_via, n) rad on the grid for foot targets p (n_via, 3); None if any fails."""
    sol = solve(problem.robot, p, "position", q0=problem.q_start, rest=problem.q_start,
                path=True)
    if not np.all(sol.reachable):
        return None
    return np.rint(sol.q / problem.res) * problem.res


def parabolic_via(problem: SwingProblem, height: float | None = None) -> FloatArray | None:
    """Via points (n_via, n) rad of the parabolic swing (module docstring), None if the IK fails."""
    h = float(problem.params.step_height or 0.0) if height is None else float(height)
    s = np.arange(1, problem.n_via + 1) / (problem.n_via + 1)
    p = (problem.foot_start + np.outer(s, problem.foot_end - problem.foot_start)
         + np.outer(4.0 * h * s * (1.0 - s), [0.0, 0.0, 1.0]))
    return _ik_via(problem, p)


def _upper_hull(pts: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """Upper convex hull of points (u, z) sorted by u (the taut string over them)."""
    hull: list[tuple[float, float]] = []
    for p in sorted(pts):
        while len(hull) >= 2:
            (u1, z1), (u2, z2) = hull[-2], hull[-1]
            if (u2 - u1) * (p[1] - z1) - (z2 - z1) * (p[0] - u1) >= 0.0:  # hull[-1] not above
                hull.pop()
            else:
                break
        hull.append(p)
    return hull


def _taut_path(problem: SwingProblem, grow: float, lift: float) -> FloatArray:
    """Foot targets (n_via, 3) at equal path-length fractions of the shortest start→end path in
    the chord's vertical plane over the box grown by ``margin + grow``; interior raised ``lift``."""
    ps, pe = problem.foot_start, problem.foot_end
    chord = pe - ps
    L = float(np.hypot(chord[0], chord[1]))
    pts = [(0.0, float(ps[2])), (1.0, float(pe[2]))]
    for box, margin in zip(problem.boxes, problem.margins, strict=True):
        if L <= 0.0:
            break
        c = np.asarray(box.center)
        h = np.asarray(box.half_size) + margin + grow
        s_in, s_out = 0.0, 1.0
        hit = True
        for ax in range(2):  # where the chord's horizontal projection crosses the footprint
            d = chord[ax]
            if abs(d) < 1e-15:
                hit &= abs(ps[ax] - c[ax]) <= h[ax]
                continue
            t1, t2 = sorted(((c[ax] - h[ax] - ps[ax]) / d, (c[ax] + h[ax] - ps[ax]) / d))
            s_in, s_out = max(s_in, t1), min(s_out, t2)
        if hit and s_in < s_out:
            top = float(c[2] + h[2])
            pts += [(s_in, top), (s_out, top)]
    hull = _upper_hull(pts)
    u = np.array([p[0] for p in hull])
    z = np.array([p[1] for p in hull])
    seg = np.hypot(np.diff(u) * L, np.diff(z))
    arc = np.concatenate([[0.0], np.cumsum(seg)])
    target = arc[-1] * np.arange(1, problem.n_via + 1) / (problem.n_via + 1)
    s = np.interp(target, arc, u)
    zz = np.interp(target, arc, z) + lift
    p = ps + np.outer(s, chord)
    p[:, 2] = zz
    return p


def min_distance_via(problem: SwingProblem) -> FloatArray | None:
    """Via points (n_via, n) rad of the shortest foot path that the decoded trajectory keeps
    feasible (module docstring); None if no such path is found."""
    grow = lift = 0.0
    for _ in range(_RAISE_MAX + 1):
        via = _ik_via(problem, _taut_path(problem, grow, lift))
        if via is None:
            return None
        _, G = problem.evaluate(problem.encode(via)[None])
        bad = dict(zip(problem.constraint_names, G[0] > 0.0, strict=True))
        if not any(bad.values()):
            return via
        lift += _RAISE_STEP if bad.get("ground", False) else 0.0
        grow += _RAISE_STEP if bad.get("obstacle", False) else 0.0
    return None


def reference_values(problem: SwingProblem, via: FloatArray | None) -> dict[str, float]:
    """Normalisers of :func:`multi_criteria`: the values of the trajectory through ``via`` (the
    parabolic swing), floored at small positive numbers; the coordinated motion if None."""
    x = problem.coordinated_x() if via is None else problem.encode(via)
    q, qd, qdd = problem.trajectories(x[None], (0, 1, 2))
    foot = fk(problem.robot, q)[..., :3, 3]
    step = np.linalg.norm(np.diff(foot, axis=-2), axis=-1)
    vals = {
        "theta_total": float(np.sum(np.abs(np.diff(q, axis=-2)))),
        "path_length": float(step.sum()),
        "foot_speed_max": float(np.max(step / np.diff(problem.t))),
        "joint_speed_sum": float(np.max(np.abs(qd[0]), axis=0).sum()),
        "energy": float(problem.energy(q, qd, qdd)[0]),
    }
    return {k: max(v, _REF_FLOOR[k]) for k, v in vals.items()}


def _ga_baseline(problem: SwingProblem, criterion: str, refs: dict[str, float],
                 label: str) -> Solution:
    p = problem.params
    sub = problem.variant(criterion, refs)
    assert isinstance(sub, Problem)

    def optimise() -> dict[str, Any]:
        algo = get_algorithm("ga", pop_size=p.baseline_pop_size, mutation_rate=0.03, elitism=2)
        res = minimize(sub, algo, MaxGenerations(p.baseline_generations), seed=p.baseline_seed)
        return {"x": [float(v) for v in res.x], "n_evals": int(res.n_evals)}

    found = cached(_ga_key(problem, criterion, refs), optimise)
    sol = sub.solution(np.asarray(found["x"], dtype=float), label=label)
    sol.extra["optimizer"] = {"kind": "ga", "pop_size": p.baseline_pop_size,
                              "generations": p.baseline_generations, "seed": p.baseline_seed,
                              "penalty": None, "n_evals": found["n_evals"]}
    return sol


def _ga_key(problem: SwingProblem, criterion: str, refs: dict[str, float]) -> str:
    """Content hash of a GA baseline: robot, tool frame, study parameters, criterion,
    normalisers, numpy version and legcore's code (``legcore.result_cache``: the optimum is
    reused across processes when ``LEGOPT_CACHE_DIR`` is set)."""
    robot = problem.robot
    return content_key("swing_energy_ga_baseline", [
        robot.spec.model_dump_json(), str(robot.tool_frame), problem.params.model_dump_json(),
        criterion, {k: float(v) for k, v in sorted(refs.items())}, np.__version__,
        code_version(),
    ])


def ga_baseline_criteria(params: Any) -> list[str]:
    """The criteria of the GA baselines ``params.baselines`` asks for (the problems are
    ``problem.variant(criterion, refs)``), sorted."""
    criteria = {BASELINES[name][0] for name in params.baselines}
    if "energy_gradient" in criteria:  # refines the minimum-energy problem's GA optimum
        criteria |= {"energy"}
    criteria -= {"parabolic", "foot_distance", "energy_gradient"}
    return sorted(criteria)


def compute_baselines(problem: SwingProblem) -> dict[str, Solution]:
    """All baselines listed in ``problem.params.baselines``, by name (module docstring).

    A construction whose IK fails for a user's start/end (or that cannot be made feasible) is
    left out; the GA baselines always exist.
    """
    par = parabolic_via(problem)
    refs = reference_values(problem, par)
    out: dict[str, Solution] = {}
    for name in problem.params.baselines:
        criterion, label = BASELINES[name]
        if criterion in ("parabolic", "foot_distance"):
            via = par if criterion == "parabolic" else min_distance_via(problem)
            if via is None:
                continue
            sol = problem.solution(problem.encode(via), label=label)
            sol.extra["criterion"] = f"{criterion} (construction)"
            out[name] = sol
        elif criterion != "energy_gradient":
            out[name] = _ga_baseline(problem, criterion, refs, label)
    for name in problem.params.baselines:  # after the others: they are its starts
        criterion, label = BASELINES[name]
        if criterion == "energy_gradient":
            out[name] = _gradient_baseline(problem, refs, label, dict(out))
    return out


def _gradient_baseline(problem: SwingProblem, refs: dict[str, float], label: str,
                       others: dict[str, Solution]) -> Solution:
    """``gradient_min_energy`` (module docstring): SLSQP + grid climb on the minimum-energy
    problem from the coordinated motion, Pérez's GA optimum and each of ``others`` (the
    job's other baselines), the best end point by the feasibility rule; cached like the GA
    baselines."""
    from legcore.optimizers.refine import best_index, refine
    sub = problem.variant("energy", refs)
    assert isinstance(sub, Problem)
    starts = {"the coordinated motion": sub.coordinated_x()}
    if "perez2010_min_energy" not in others:
        starts["perez2010_min_energy"] = np.asarray(
            _ga_baseline(problem, "energy", refs, "").x, dtype=float)
    starts |= {k: np.asarray(v.x, dtype=float) for k, v in others.items() if v.x is not None}

    def solve() -> dict[str, Any]:
        runs = [refine(sub, x, max_iter=_GRADIENT_ITER) for x in starts.values()]
        i = best_index(np.array([r.f for r in runs]), np.array([r.cv for r in runs]))
        return {"x": [float(v) for v in runs[i].x], "start": list(starts)[i],
                "n_evals": int(sum(r.n_evals for r in runs)),
                "ends": {k: [float(r.f), float(r.cv)] for k, r in zip(starts, runs, strict=True)}}

    key = _ga_key(problem, "energy_gradient:" + ",".join(starts), refs)
    found = cached(key, solve)
    sol = sub.solution(np.asarray(found["x"], dtype=float), label=label)
    sol.extra["criterion"] = "energy (gradient: SLSQP on the via points, then the grid climb)"
    sol.extra["optimizer"] = {"kind": "slsqp", "max_iter": _GRADIENT_ITER,
                              "best_start": found["start"], "n_evals": found["n_evals"],
                              "ends": found["ends"]}
    return sol
