"""How a ``path_tracking`` decision vector x encodes the tool's time law (``params.speeds``).

- :class:`SegmentSpeeds` — seed 004's scheme (``"per_segment"``, ``"single"``): a cruise speed
  per segment (or one for all, m/s) joined by ramps, the start/stop ramp times t_a, t_d and the
  blend time t_b (s) (:func:`~legcore.studies.path_tracking.timelaw.build_time_law`).
- :class:`SpeedProfile` — ``"profile"``: the tool's speed (m/s) at fixed knots along the path,
  constant tangential acceleration between them
  (:func:`~legcore.studies.path_tracking.timelaw.profile_law`). It can represent the
  time-optimal profile on its knots (TOPP-RA's form), which the trapezoid laws cannot: they
  cruise at one speed per segment, while the fastest motion follows the joint limits as they
  change along the path.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from legcore.studies.path_tracking.timelaw import (
    RampShape,
    TimeLaw,
    build_time_law,
    profile_law,
)

__all__ = ["SegmentSpeeds", "SpeedProfile", "profile_knots"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class SegmentSpeeds:
    """Cruise speeds and ramps: x = (V_1 … V_n, t_a, t_d[, t_b]) (t_b only when n > 1), or
    with ``single`` x = (V, t_a, t_d). ``lengths`` (n,) m; ``shape`` the ramp shape."""

    lengths: FloatArray
    single: bool
    shape: RampShape

    @property
    def n_seg(self) -> int:
        return int(self.lengths.size)

    @property
    def variable_names(self) -> tuple[str, ...]:
        n = self.n_seg
        if self.single:
            return ("V", "t_a", "t_d")
        return tuple([f"V_{k + 1}" for k in range(n)] + ["t_a", "t_d"] + (["t_b"] if n > 1
                                                                         else []))

    def split(self, X: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """(B, n_var) → segment speeds V (B, n) m/s, t_a, t_d, t_b (B,) s."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        n = self.n_seg
        if self.single:
            V = np.repeat(X[:, :1], n, axis=1)
            return V, X[:, 1], X[:, 2], np.zeros(X.shape[0])
        t_b = X[:, n + 2] if n > 1 else np.zeros(X.shape[0])
        return X[:, :n], X[:, n], X[:, n + 1], t_b

    def law(self, X: FloatArray, shape: RampShape | None = None) -> TimeLaw:
        """The laws of a batch (``shape`` overrides the encoding's ramp shape)."""
        V, t_a, t_d, t_b = self.split(X)
        return build_time_law(self.lengths, V, t_a, t_d, t_b, shape or self.shape)

    def bounds(self, V_lo: float, V_caps: FloatArray, ramp_bounds: tuple[float, float]
               ) -> tuple[list[float], list[float]]:
        """The decision box: speeds in [``V_lo``, cap of their segment] (``V_caps`` (n,) m/s;
        the smallest for ``single``), ramp times in ``ramp_bounds`` (s)."""
        caps = [float(V_caps.min())] if self.single else [float(v) for v in V_caps]
        n_ramp = len(self.variable_names) - len(caps)
        return ([V_lo] * len(caps) + [ramp_bounds[0]] * n_ramp,
                caps + [ramp_bounds[1]] * n_ramp)

    def x_of(self, V: float, t_a: float, t_d: float, t_b: float) -> FloatArray:
        """One speed ``V`` on every segment with these ramp times, as a decision vector."""
        if self.single:
            return np.array([V, t_a, t_d])
        return np.array([V] * self.n_seg + [t_a, t_d] + ([t_b] if self.n_seg > 1 else []))

    def metrics(self, x: FloatArray) -> dict[str, float]:
        """What x says in its own terms: t_a, t_d, t_b (s) and each segment's V_k (m/s)."""
        V, t_a, t_d, t_b = (a[0] for a in self.split(x))
        out = {"t_a": float(t_a), "t_d": float(t_d), "t_b": float(t_b)}
        out |= {f"V_{k + 1}": float(v) for k, v in enumerate(V)}
        return out


def profile_knots(lengths: FloatArray, intervals: int) -> FloatArray:
    """Knots (M + 1,) m of a speed profile: about ``intervals`` equal intervals shared among
    the segments by length (at least 2 each), a knot on every join (where Q″ may jump)."""
    D = np.asarray(lengths, dtype=float)
    per = np.maximum(2, np.rint(intervals * D / D.sum()).astype(int))
    starts = np.concatenate([[0.0], np.cumsum(D)])
    parts = [starts[k] + np.linspace(0.0, D[k], per[k] + 1)[:-1] for k in range(D.size)]
    return np.concatenate([*parts, [starts[-1]]])


@dataclass(frozen=True, eq=False)
class SpeedProfile:
    """The tool's speed at the interior knots: x = (v_1 … v_{M−1}) m/s, with v_0 = v_M = 0
    (rest to rest). ``lengths`` (n,) m; ``knots`` (M + 1,) m (:func:`profile_knots`)."""

    lengths: FloatArray
    knots: FloatArray

    @property
    def variable_names(self) -> tuple[str, ...]:
        return tuple(f"v_{i}" for i in range(1, self.knots.size - 1))

    def speeds(self, X: FloatArray) -> FloatArray:
        """(B, n_var) → the speed at every knot (B, M + 1) m/s."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        z = np.zeros((X.shape[0], 1))
        return np.concatenate([z, X, z], axis=1)

    def law(self, X: FloatArray, shape: RampShape | None = None) -> TimeLaw:
        """The laws of a batch (always constant acceleration between knots: ``shape`` is not
        used)."""
        return profile_law(self.lengths, self.knots, self.speeds(X))

    def bounds(self, V_lo: float, caps: FloatArray) -> tuple[list[float], list[float]]:
        """The decision box: each knot's speed in [``V_lo``, its cap] (``caps`` (M + 1,) m/s,
        the fastest the joint speed limits allow there; at least ``V_lo``)."""
        inner = np.maximum(np.asarray(caps, dtype=float)[1:-1], V_lo)
        return [V_lo] * inner.size, inner.tolist()

    def x_of(self, law: TimeLaw) -> FloatArray:
        """The knot speeds (B, n_var) of other laws (B of them): each law's speed where it
        passes the interior knots — exact for a law with constant acceleration between
        consecutive knots, an interpolation of it otherwise."""
        B = law.T.shape[0]
        sig = np.broadcast_to(self.knots[1:-1], (B, self.knots.size - 2))
        return law.evaluate(law.time_at(sig))[1]

    def metrics(self, x: FloatArray) -> dict[str, float]:
        """The profile's peak speed (m/s)."""
        return {"v_peak": float(np.max(x)) if np.size(x) else 0.0}
