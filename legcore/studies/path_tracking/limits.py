"""Joint limits of a ``path_tracking`` motion between the optimiser's samples.

The evaluation samples every candidate law at K instants (``TimeLaw.sample_times``). A joint
speed or torque peaks smoothly between two samples (the sampled peak is short by O(1/K²)), but
a joint acceleration *jumps* where a linear ramp starts or ends (σ̈ does) and where two segments
join (the path's curvature, so q″, does): the regular samples only approach those one-sided
limits. So, for a task whose ``limit_check`` > 1:

- :func:`edge_times` — the instants just before every phase boundary and on both sides of
  every join, where every candidate is also evaluated;
- :func:`dense_limits` — the limit columns of G with those peaks and, for a candidate within
  a few % of a limit (``_near``), its peaks over ``limit_check`` × K samples;
- :func:`limit_violations` — what a motion breaks on that dense resampling (at least 10 × K
  samples and the edges), per joint, with its peak and limit in rad/s, rad/s² or N·m.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from legcore.studies.path_tracking.contract import TrackingProblem
from legcore.studies.path_tracking.timelaw import RampShape, TimeLaw
from legcore.studies.task import Violation

__all__ = ["DENSE_CHECK", "dense_limits", "edge_times", "limit_violations"]

FloatArray = NDArray[np.float64]

#: :func:`limit_violations` checks at least this × ``n_samples`` samples.
DENSE_CHECK = 10


def _near(K: int) -> float:
    """Limit columns within this of 0 (G, a fraction of the limit) at K samples are checked
    again densely: 2 % at 400 samples, growing as the sampling error (1/K²), at most 50 %."""
    return min(0.5, 0.02 * (400.0 / K) ** 2)


def edge_times(problem: TrackingProblem, law: TimeLaw) -> FloatArray:
    """(B, E) instants where the joint accelerations jump (s): just before every phase
    boundary of the law (a linear ramp's σ̈ jumps there) and just before and after every
    join of two segments (the path's curvature, so q″, jumps there) — the one-sided
    limits the regular samples only approach."""
    B = law.T.shape[0]
    eps = 1e-9 * law.T[:, None]
    parts = [law.t_start[:, 1:] - eps]
    ends = np.cumsum(problem.path.lengths)[:-1]
    if ends.size:
        tj = law.time_at(np.broadcast_to(ends, (B, ends.size)))
        parts += [tj - eps, tj + eps]
    return np.clip(np.concatenate(parts, axis=1), 0.0, law.T[:, None])


def dense_limits(problem: TrackingProblem, X: FloatArray | TimeLaw, G: FloatArray,
                 factor: int, shape: RampShape | None = None, every: bool = False
                 ) -> FloatArray:
    """``G`` (B, n_constr) of decision vectors ``X`` (or of time laws) with the joint-limit
    columns also counting the peaks at :func:`edge_times` (every candidate) and, for the
    candidates near a limit (every candidate with ``every``), over ``factor`` × ``n_samples``
    samples and the edges."""
    law = X if isinstance(X, TimeLaw) else problem.time_law(np.atleast_2d(X), shape)
    nl = 3 * problem.robot.nq
    G = G.copy()
    edges = problem.simulate(law, full=False, samples=0)["G"]
    G[:, :nl] = np.maximum(G[:, :nl], edges[:, :nl])
    peak = G[:, :nl].max(axis=1)
    near = np.ones(G.shape[0], dtype=bool) if every else np.abs(peak) <= _near(
        problem.n_samples)
    if not near.any():
        return G
    dense = problem.simulate(law.subset(near), full=False,
                             samples=factor * problem.n_samples, extra_times=True)["G"]
    G[near, :nl] = np.maximum(G[near, :nl], dense[:, :nl])
    return G


def limit_violations(problem: TrackingProblem, x: FloatArray | TimeLaw,
                     shape: RampShape | None = None) -> tuple[Violation, ...]:
    """What the motion of ``x`` (with the ramp ``shape``; None: ``params.ramp``) or of one
    time law breaks, on its samples, at least 10 × ``n_samples`` samples and the
    :func:`edge_times`, each with its size in the limit's units (module docstring)."""
    law = x if isinstance(x, TimeLaw) else problem.time_law(
        np.asarray(x, dtype=float).reshape(1, -1), shape)
    factor = max(problem.limit_check, DENSE_CHECK)
    G = dense_limits(problem, law, problem.simulate(law, full=False)["G"], factor,
                     every=True)[0]
    r, n = problem.robot, problem.robot.nq
    K = factor * problem.n_samples
    limits = (("qd_max", "speed", r.qd_max, "rad/s"),
              ("qdd_max", "acceleration", problem.qdd_max, "rad/s²"),
              ("tau_max", "torque", r.tau_max, "N·m"))
    out: list[Violation] = []
    for k, (key, what, lim, unit) in enumerate(limits):
        for j in range(n):
            g = float(G[k * n + j])
            if g > 0.0:
                name = str(r.model.names[j + 1])
                out.append(Violation(
                    f"{key}.q{j + 1}", float(g * lim[j]), unit,
                    f"joint {name}: peak {what} {(1.0 + g) * lim[j]:.4g} {unit}, "
                    f"{100 * g:.3g} % over its limit {lim[j]:.4g} {unit} (checked on "
                    f"{K} samples)"))
    g = float(G[3 * n])
    if g > 0.0:
        out.append(Violation("ramps_fit", g, "", f"the speed ramps ask {100 * g:.3g} % more "
                             f"distance than their segments have (the law shrinks them)"))
    if problem.params.T_max is not None and G[3 * n + 1] > 0.0:
        T = (1.0 + float(G[3 * n + 1])) * problem.params.T_max
        out.append(Violation("T_max", T - problem.params.T_max, "s",
                             f"cycle time {T:.4g} s over the cap T_max = "
                             f"{problem.params.T_max:g} s"))
    return tuple(out)
