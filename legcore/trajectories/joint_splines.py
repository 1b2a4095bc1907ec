"""Joint-space trajectories through via points, vectorised over a batch.

A batch of B trajectories of n joints passes through K_via via points at common
times ``t_via`` (K_via,), starting and ending at rest:

- ``"cubic"``: C² cubic spline, clamped (q̇ = 0 at both ends); jerk is piecewise
  constant.
- ``"quintic"``: C⁴ quintic spline with q̇ = q̈ = 0 at both ends.

One scipy spline object holds the whole batch (the via-point axis is axis 1 of
``q_via`` (B, K_via, n)); there is no loop over B. With two via points the cubic is
the rest-to-rest Hermite q0 + Δq (3τ² − 2τ³) and the quintic q0 + Δq (10τ³ − 15τ⁴ + 6τ⁵).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import BSpline, CubicSpline, make_interp_spline

from legcore.trajectories.sampling import JointSample, time_grid

__all__ = ["ViaPointSpline"]


@dataclass(frozen=True, eq=False)
class ViaPointSpline:
    """Rest-to-rest spline through via points ``q_via`` (B, K_via, n) at ``t_via`` (K_via,) s.

    ``kind`` is "cubic" (clamped) or "quintic" (zero velocity and acceleration at the
    ends). Joint values are rad (or m); times s, strictly increasing.
    """

    t_via: NDArray[np.float64]
    q_via: NDArray[np.float64]
    kind: Literal["cubic", "quintic"] = "cubic"
    _spline: CubicSpline | BSpline = field(init=False, repr=False)

    def __post_init__(self) -> None:
        t_via = np.array(self.t_via, dtype=float)
        q_via = np.array(self.q_via, dtype=float)
        if t_via.ndim != 1 or t_via.shape[0] < 2:
            raise ValueError(f"t_via must be a 1-D array of >= 2 times, got shape {t_via.shape}")
        if not np.all(np.isfinite(t_via)) or np.any(np.diff(t_via) <= 0.0):
            raise ValueError("t_via must be finite and strictly increasing")
        if q_via.ndim != 3 or q_via.shape[1] != t_via.shape[0]:
            raise ValueError(
                f"q_via must have shape (B, K_via={t_via.shape[0]}, n), got {q_via.shape}"
            )
        if not np.all(np.isfinite(q_via)):
            raise ValueError("q_via must be finite")
        if self.kind == "cubic":
            spline: CubicSpline | BSpline = CubicSpline(t_via, q_via, axis=1, bc_type="clamped")
        elif self.kind == "quintic":
            zero = np.zeros((q_via.shape[0], q_via.shape[2]))
            ends = [(1, zero), (2, zero)]
            spline = make_interp_spline(t_via, q_via, k=5, bc_type=(ends, ends), axis=1)
        else:
            raise ValueError(f"kind must be 'cubic' or 'quintic', got {self.kind!r}")
        for arr in (t_via, q_via):
            arr.setflags(write=False)
        object.__setattr__(self, "t_via", t_via)
        object.__setattr__(self, "q_via", q_via)
        object.__setattr__(self, "_spline", spline)

    @property
    def T(self) -> float:
        """Duration t_via[-1] − t_via[0] (s)."""
        return float(self.t_via[-1] - self.t_via[0])

    def evaluate(self, t: ArrayLike) -> JointSample:
        """q, qd, qdd, qddd at times t (K,) within [t_via[0], t_via[-1]], each (B, K, n)."""
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        if tt.ndim != 1:
            raise ValueError(f"t must be a 1-D array of times, got shape {tt.shape}")
        t0, t1 = float(self.t_via[0]), float(self.t_via[-1])
        tol = 1e-9 * max(1.0, abs(t0), abs(t1))
        if tt.size and (not np.all(np.isfinite(tt)) or tt.min() < t0 - tol or tt.max() > t1 + tol):
            raise ValueError(f"t must lie in [{t0}, {t1}] s")
        tt = np.clip(tt, t0, t1)
        sp = self._spline
        return JointSample(t=tt, q=sp(tt), qd=sp(tt, 1), qdd=sp(tt, 2), qddd=sp(tt, 3))

    def sample(self, dt: float) -> JointSample:
        """Samples at t_via[0] + k dt (the end only if the duration is a multiple of dt)."""
        return self.evaluate(time_grid(self.T, dt, t0=float(self.t_via[0])))
