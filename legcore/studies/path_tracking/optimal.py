"""The time-optimal motion along a ``path_tracking`` path, as a baseline and as a start.

:func:`legcore.studies.path_tracking.topp.time_optimal` (TOPP-RA) keeps the limits at its
gridpoints. Here its profile is made to keep them *everywhere*: it is checked on a dense
resampling (at least 10 × ``n_samples`` samples and both sides of every knot and join,
:func:`~legcore.studies.path_tracking.limits.dense_limits`) and, while some limit is exceeded
by a fraction g, TOPP-RA is solved again with every limit × 1 / (1 + 1.5 g) (a few rounds;
typically 1e-4–1e-3 below the limits). Then:

- :func:`physical_minimum` — on a fine grid (``FINE_INTERVALS`` over the path, a gridpoint on
  every join): the shortest cycle time T* any time law can have on this path under these
  limits, to the grid's resolution — every run's ``time_optimal`` baseline and the reference
  of its optimality gap;
- :func:`initial_points` — on the knots of a ``speeds="profile"`` encoding: the time-optimal
  profile *that encoding* can represent, with slower copies of it and the seed law, where the
  population starts.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from legcore.studies.path_tracking import limits
from legcore.studies.path_tracking.contract import PhysicalMinimum, TrackingProblem
from legcore.studies.path_tracking.encodings import SpeedProfile, profile_knots
from legcore.studies.path_tracking.timelaw import TimeLaw, profile_law
from legcore.studies.path_tracking.topp import time_optimal

__all__ = ["FINE_INTERVALS", "feasible_profile", "initial_points",
           "knot_speed_caps", "physical_minimum"]

FloatArray = NDArray[np.float64]

#: Grid intervals over the whole path for the physical minimum (TOPP-RA's T falls as the grid
#: is refined: on seed 004's capsule 3.4473 s at 64, 3.3964 at 128, 3.3622 at 1000, 3.3596
#: at 3000 intervals).
FINE_INTERVALS = 2000
_ROUNDS = 8  # tightenings at most
_SLOWER = (0.8, 0.6, 0.4, 0.25, 0.15)  # speed factors of the slower starting copies


def _overshoot(problem: TrackingProblem, law: TimeLaw) -> float:
    """The largest fraction by which the motion of ``law`` exceeds a joint limit on a dense
    resampling (≤ 0: none)."""
    factor = max(problem.limit_check, limits.DENSE_CHECK)
    G = limits.dense_limits(problem, law, problem.simulate(law, full=False)["G"], factor,
                            every=True)
    return float(G[0, : 3 * problem.robot.nq].max())


def feasible_profile(problem: TrackingProblem, grid: FloatArray) -> PhysicalMinimum | None:
    """TOPP-RA's profile on ``grid`` (m) tightened until it keeps every limit on a dense
    resampling (module docstring); None when no profile exists or none is found."""
    r = problem.robot
    scale, first = 1.0, None
    lengths = problem.path.lengths
    for _ in range(_ROUNDS):
        res = time_optimal(r, problem.joints, grid, r.qd_max, problem.qdd_max, r.tau_max,
                           scale)
        if res is None:
            return None
        first = res.T if first is None else first
        law = profile_law(lengths, grid, res.speed[None, :])
        over = _overshoot(problem, law)
        if over <= 0.0:
            return PhysicalMinimum(grid=grid, speed=res.speed, T=res.T, scale=scale,
                                   T_at_limits=first, law=law)
        scale /= 1.0 + 1.5 * over + 1e-9
    return None


def physical_minimum(problem: TrackingProblem) -> PhysicalMinimum | None:
    """The physical minimum of ``problem``'s path: :func:`feasible_profile` on
    ``FINE_INTERVALS`` intervals (a gridpoint on every join)."""
    return feasible_profile(problem, profile_knots(problem.path.lengths, FINE_INTERVALS))


def knot_speed_caps(problem: TrackingProblem, knots: FloatArray) -> FloatArray:
    """The fastest tool speed (M + 1,) m/s at each knot at which every joint keeps its speed
    limit, on both sides of the knot (at most 10 × ``V_bounds[1]``)."""
    assert problem.params.V_bounds is not None
    jp = problem.joints
    L = jp.length
    dq = np.maximum(np.abs(jp.poly(knots, 1)),
                    np.abs(jp.poly(np.maximum(knots - 1e-12 * L, 0.0), 1)))
    with np.errstate(divide="ignore"):
        v = np.min(problem.robot.qd_max / dq, axis=1)
    return np.minimum(v, 10.0 * problem.params.V_bounds[1])


def initial_points(problem: TrackingProblem) -> FloatArray:
    """Starting decision vectors (k, n_var) of a speed-profile encoding: the time-optimal
    profile on its knots (:func:`feasible_profile`), slower copies of it (speeds × 0.8 …
    0.15: accelerations × their square) and the seed law's speeds at the knots, each inside
    the decision box."""
    enc = problem.encoding
    assert isinstance(enc, SpeedProfile)
    rows = []
    best = feasible_profile(problem, enc.knots)
    if best is not None:
        x0 = best.speed[1:-1]
        rows += [x0] + [c * x0 for c in _SLOWER]
    rows.append(enc.x_of(problem.seed_law())[0])
    return np.clip(np.array(rows), problem.xl, problem.xu)
