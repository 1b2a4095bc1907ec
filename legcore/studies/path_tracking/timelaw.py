"""Batched time laws along a composite path: segment cruise speeds joined by speed ramps.

The tool runs the whole path (total length L = Σ D_k, m) with an arc-length law σ(t) (m) whose
speed σ̇ (m/s) is a chain of *phases*, each a ramp from a start speed to an end speed:

    ramp_0 (0 → V_1, t_a) · cruise_1 (V_1) · ramp_1 (V_1 → V_2, t_b) · cruise_2 · … ·
    cruise_n (V_n) · ramp_n (V_n → 0, t_d)

- ``ramp_0`` lies at the start of segment 1 and ``ramp_n`` at the end of segment n, exactly as
  seed 004's acceleration / deceleration profiles (its eqs 19–33, 39–49);
- an interior ramp ``ramp_k`` (blend time t_b) is centred in distance on the join of segments
  k and k+1 (half of its distance on each side); with V_k = V_{k+1} it is plain cruising, so
  one speed on every segment reproduces the paper's concatenation (accel · constant · … · decel);
- every ramp is point-symmetric, so it covers (v_s + v_e)/2 · duration for both shapes:
  ``"linear"`` (constant tangential acceleration, the seed's trapezoid) or ``"cubic"``
  (v = v_s + Δv (3u² − 2u³), u = τ/duration: continuous acceleration, finite jerk).

All quantities are arrays over a batch of B candidate laws; evaluation takes times (B, K).
If the ramps ask for more distance than a segment has (``fit`` > 1), :func:`build_time_law`
shrinks all ramp durations of that candidate by one factor so that they fit (the problem
reports the original ``fit`` as a constraint): every law it returns is valid.

:func:`profile_law` builds the other kind of law, a *speed profile* over arc length: speeds
v_0 = 0, v_1 … v_{M−1}, v_M = 0 at fixed knots σ_0 = 0 < … < σ_M = L with a constant tangential
acceleration between two knots (σ̇² linear in σ: each interval is a ``"linear"`` ramp phase
from v_i to v_{i+1} of duration 2 (σ_{i+1} − σ_i) / (v_i + v_{i+1})). This is the form of a
time-optimal path parametrisation (TOPP-RA's piecewise-constant path acceleration), so it
can represent the time-optimal profile on its knots.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

__all__ = ["RampShape", "TimeLaw", "build_time_law", "profile_law", "segment_profiles"]

FloatArray = NDArray[np.float64]
RampShape = Literal["linear", "cubic"]

_FEW_PHASES = 32  # up to this many phase starts, a phase is found by direct comparison


@dataclass(frozen=True, eq=False)
class TimeLaw:
    """B arc-length laws over P = 2n + 1 phases (n segments).

    ``duration``, ``t_start`` (B, P) s; ``sigma_start`` (B, P) m; ``v_start``, ``v_end``
    (B, P) m/s; ``T`` (B,) s total time; ``lengths`` (n,) m segment lengths; ``fit`` (B, n)
    ramp distance asked of each segment over its length (as requested, before shrinking);
    ``shrink`` (B,) factor applied to all ramp durations (1 when they fit); ``shape``.
    Phase 2k is a ramp, phase 2k + 1 the cruise of segment k (0-based).
    """

    duration: FloatArray
    t_start: FloatArray
    sigma_start: FloatArray
    v_start: FloatArray
    v_end: FloatArray
    T: FloatArray
    lengths: FloatArray
    fit: FloatArray
    shrink: FloatArray
    shape: RampShape

    @property
    def n_phases(self) -> int:
        return int(self.duration.shape[1])

    def phase_of(self, t: FloatArray) -> NDArray[np.int64]:
        """Index (B, K) of the phase running at times ``t`` (B, K) s (later phase at a tie)."""
        return _count_at_or_below(self.t_start[:, 1:], t)

    def subset(self, rows: NDArray[np.bool_] | NDArray[np.int64]) -> TimeLaw:
        """The laws of the candidates ``rows`` (a mask or indices over B)."""
        pick = lambda a: a[rows]  # noqa: E731
        return TimeLaw(
            duration=pick(self.duration), t_start=pick(self.t_start),
            sigma_start=pick(self.sigma_start), v_start=pick(self.v_start),
            v_end=pick(self.v_end), T=pick(self.T), lengths=self.lengths, fit=pick(self.fit),
            shrink=pick(self.shrink), shape=self.shape)

    def evaluate(self, t: FloatArray) -> FloatArray:
        """σ, σ̇, σ̈, σ⃛ at times ``t`` (B, K) in [0, T] s → (4, B, K) (m, m/s, m/s², m/s³).

        At a phase boundary the later phase's values are returned (σ̈ of a linear ramp jumps;
        its jerk is a Dirac, not represented).
        """
        t = np.asarray(t, dtype=float)
        idx = self.phase_of(t)
        take = lambda a: np.take_along_axis(a, idx, axis=1)  # noqa: E731
        d = take(self.duration)
        tau = np.clip(t - take(self.t_start), 0.0, d)
        v0 = take(self.v_start)
        dv = take(self.v_end) - v0
        s0 = take(self.sigma_start)
        d_safe = np.where(d > 0.0, d, 1.0)
        u = tau / d_safe
        out = np.empty((4, *t.shape))
        if self.shape == "linear":
            out[0] = s0 + v0 * tau + 0.5 * dv * u * tau
            out[1] = v0 + dv * u
            out[2] = dv / d_safe
            out[3] = 0.0
        else:
            out[0] = s0 + v0 * tau + dv * d * (u**3 - 0.5 * u**4)
            out[1] = v0 + dv * (3.0 * u**2 - 2.0 * u**3)
            out[2] = dv * (6.0 * u - 6.0 * u**2) / d_safe
            out[3] = dv * (6.0 - 12.0 * u) / d_safe**2
        return out

    def sample_times(self, K: int, min_samples: int = 10) -> FloatArray:
        """K strictly increasing times (B, K) from 0 to T s, spread over the phases.

        Phase j takes the share w_j ∝ max(duration_j / T, length_j / L) of the samples — at
        least ``min_samples`` / K for every cruise of positive length and every ramp that
        changes the speed — so that neither the short hard ramps (where accelerations and
        torques peak) nor a fast stretch of a slow law are stepped over. Inside a phase the
        samples are cosine-spaced, t = t_j + duration_j (1 − cos πv)/2 for v in [0, 1), so they
        crowd at the phase boundaries, where σ̈ (hence τ) jumps; the trapezoid integrals of
        :mod:`legcore.energy` then converge quickly.
        """
        B, P = self.duration.shape
        L = float(self.lengths.sum())
        seg_len = np.diff(np.concatenate([self.sigma_start, np.full((B, 1), L)], axis=1), axis=1)
        w = np.maximum(self.duration / self.T[:, None], seg_len / L)
        changing = self.v_start != self.v_end
        cruise = np.zeros(P, dtype=bool)
        cruise[1::2] = True
        # phases shorter than 1e-9 T (round-off leftovers) get no samples of their own
        live = self.duration > 1e-9 * self.T[:, None]
        busy = live & (changing | (cruise & (seg_len > 0.0)))
        w = np.where(busy, np.maximum(w, min_samples / K), w)
        w = np.where(live, w, 0.0)
        w /= w.sum(axis=1, keepdims=True)
        U = np.concatenate([np.zeros((B, 1)), np.cumsum(w, axis=1)], axis=1)
        U[:, -1] = 1.0
        u = np.broadcast_to(np.linspace(0.0, 1.0, K), (B, K))
        # phase of each u: the last one starting at or before u (zero-share phases have an
        # empty interval [U_j, U_j+1) and are skipped; the last ramp always has a share)
        idx = _count_at_or_below(U[:, 1:P], u)
        take = lambda a: np.take_along_axis(a, idx, axis=1)  # noqa: E731
        v = np.clip((u - take(U[:, :-1])) / take(np.where(w > 0.0, w, 1.0)), 0.0, 1.0)
        t = take(self.t_start) + take(self.duration) * 0.5 * (1.0 - np.cos(np.pi * v))
        t = np.minimum(t, self.T[:, None])
        t[:, 0] = 0.0
        t[:, -1] = self.T
        return t

    def time_at(self, sigma: FloatArray, iterations: int = 80) -> FloatArray:
        """Times (B, M) s at which the laws reach arc lengths ``sigma`` (B, M) m (bisection;
        σ(t) is non-decreasing). Used for segment times in reports, not in the batch loop."""
        sigma = np.asarray(sigma, dtype=float)
        lo = np.zeros_like(sigma)
        hi = np.broadcast_to(self.T[:, None], sigma.shape).copy()
        for _ in range(iterations):
            mid = 0.5 * (lo + hi)
            below = self.evaluate(mid)[0] < sigma
            lo = np.where(below, mid, lo)
            hi = np.where(below, hi, mid)
        return 0.5 * (lo + hi)

    def segment_times(self) -> FloatArray:
        """Duration (B, n) s spent on each segment (the paper's T_1 … T_n)."""
        ends = np.cumsum(self.lengths)[:-1]
        B = self.T.shape[0]
        inner = self.time_at(np.broadcast_to(ends, (B, ends.size)))
        t_join = np.concatenate([np.zeros((B, 1)), inner, self.T[:, None]], axis=1)
        return np.diff(t_join, axis=1)


def build_time_law(
    lengths: FloatArray,
    V: FloatArray,
    t_a: FloatArray,
    t_d: FloatArray,
    t_b: FloatArray,
    shape: RampShape = "linear",
) -> TimeLaw:
    """Time laws for B candidates on a path of n segments.

    ``lengths`` (n,) m; ``V`` (B, n) cruise speed per segment (m/s, > 0); ``t_a``, ``t_d``
    (B,) s start/stop ramp times (> 0); ``t_b`` (B,) s blend time of the interior ramps (≥ 0;
    unused when n = 1).
    """
    D = np.asarray(lengths, dtype=float)
    V = np.atleast_2d(np.asarray(V, dtype=float))
    B, n = V.shape
    if D.shape != (n,):
        raise ValueError(f"V: expected one speed per segment ({D.size}), got shape {V.shape}")
    if shape not in ("linear", "cubic"):
        raise ValueError(f"shape: expected 'linear' or 'cubic', got {shape!r}")
    t_a, t_d, t_b = (np.broadcast_to(np.asarray(x, dtype=float), (B,)) for x in (t_a, t_d, t_b))
    # ramps j = 0..n: speeds and requested durations
    zeros = np.zeros((B, 1))
    v_s = np.concatenate([zeros, V], axis=1)  # (B, n+1)
    v_e = np.concatenate([V, zeros], axis=1)
    dur = np.concatenate([t_a[:, None], np.repeat(t_b[:, None], n - 1, axis=1), t_d[:, None]], 1)
    dist = 0.5 * (v_s + v_e) * dur  # (B, n+1)
    # distance each segment gives to ramps: ramp 0 -> segment 0, ramp n -> segment n-1,
    # interior ramp j -> half to segment j-1, half to segment j
    share = np.zeros((n + 1, n))
    share[0, 0] = 1.0
    share[n, n - 1] += 1.0
    for j in range(1, n):
        share[j, j - 1] = 0.5
        share[j, j] = 0.5
    fit = (dist @ share) / D  # (B, n)
    shrink = np.minimum(1.0, 1.0 / np.max(fit, axis=1))
    dur = dur * shrink[:, None]
    dist = dist * shrink[:, None]
    cruise_len = np.maximum(D - dist @ share, 0.0)  # (B, n)
    cruise_dur = cruise_len / V
    P = 2 * n + 1
    duration = np.empty((B, P))
    duration[:, 0::2] = dur
    duration[:, 1::2] = cruise_dur
    v_start = np.empty((B, P))
    v_end = np.empty((B, P))
    v_start[:, 0::2] = v_s
    v_end[:, 0::2] = v_e
    v_start[:, 1::2] = V
    v_end[:, 1::2] = V
    lengths_ph = np.empty((B, P))
    lengths_ph[:, 0::2] = dist
    lengths_ph[:, 1::2] = cruise_len
    t_start = np.concatenate([np.zeros((B, 1)), np.cumsum(duration, axis=1)[:, :-1]], axis=1)
    sigma_start = np.concatenate([np.zeros((B, 1)), np.cumsum(lengths_ph, axis=1)[:, :-1]], 1)
    T = t_start[:, -1] + duration[:, -1]
    return TimeLaw(
        duration=duration,
        t_start=t_start,
        sigma_start=sigma_start,
        v_start=v_start,
        v_end=v_end,
        T=T,
        lengths=D.copy(),
        fit=fit,
        shrink=shrink,
        shape=shape,
    )


def profile_law(lengths: FloatArray, knots: FloatArray, v: FloatArray) -> TimeLaw:
    """Speed profiles of B candidates as laws (module docstring): ``knots`` (M + 1,) m from 0
    to L = Σ ``lengths`` (strictly increasing), ``v`` (B, M + 1) m/s the speed at each knot
    (≥ 0; v_0 = v_M = 0 for rest to rest; two consecutive zeros are refused: the tool would
    never leave that interval). One ``"linear"`` phase per interval; ``fit`` is 0 (no ramp
    asks for distance) and ``shrink`` 1."""
    D = np.asarray(lengths, dtype=float)
    s = np.asarray(knots, dtype=float)
    v = np.atleast_2d(np.asarray(v, dtype=float))
    B = v.shape[0]
    if v.shape[1] != s.size or s.size < 2:
        raise ValueError(f"v: expected {s.size} knot speeds per candidate, got {v.shape}")
    if not np.all(np.diff(s) > 0.0) or abs(s[-1] - D.sum()) > 1e-9 * max(1.0, D.sum()):
        raise ValueError("knots: must increase strictly from 0 to the path length")
    ds = np.diff(s)
    pair = v[:, :-1] + v[:, 1:]
    if np.any(pair <= 0.0) or np.any(v < 0.0):
        raise ValueError("v: knot speeds must be ≥ 0, and never 0 at two knots in a row")
    duration = 2.0 * ds / pair
    t_start = np.concatenate([np.zeros((B, 1)), np.cumsum(duration, axis=1)[:, :-1]], axis=1)
    return TimeLaw(
        duration=duration,
        t_start=t_start,
        sigma_start=np.broadcast_to(s[:-1], (B, ds.size)).copy(),
        v_start=v[:, :-1].copy(),
        v_end=v[:, 1:].copy(),
        T=t_start[:, -1] + duration[:, -1],
        lengths=D.copy(),
        fit=np.zeros((B, D.size)),
        shrink=np.ones(B),
        shape="linear",
    )


def _count_at_or_below(starts: FloatArray, t: FloatArray) -> NDArray[np.int64]:
    """For each row b, how many of ``starts[b]`` (B, P, non-decreasing) are ≤ each ``t[b]``
    (B, K). A few phases: one comparison per phase (exact). Many (a speed profile): one
    ``searchsorted`` over the rows laid end to end, each row shifted by its index × a span
    larger than any value so that rows never mix (exact up to the rounding of that shift,
    ~B · T · 1e-16 s)."""
    B = starts.shape[0]
    if starts.shape[1] <= _FEW_PHASES:
        return np.sum(t[..., None] >= starts[:, None, :], axis=-1).astype(np.int64)
    lo = min(float(starts.min()), float(t.min()))
    span = max(float(starts.max()), float(t.max())) - lo + 1.0
    shift = (np.arange(B) * span)[:, None]
    flat = ((starts - lo) + shift).ravel()
    pos = np.searchsorted(flat, ((t - lo) + shift).ravel(), side="right").reshape(t.shape)
    return (pos - (np.arange(B) * starts.shape[1])[:, None]).astype(np.int64)


def segment_profiles(V: FloatArray) -> list[str]:
    """Per segment of cruise speeds ``V`` (n,) m/s, its pieces of the speed law: accel/decel at
    the ends, blend-in/out where the cruise speed changes, constant while cruising (seed 004
    names its s_k this way)."""
    out = []
    n = len(V)
    for k in range(n):
        parts = []
        if k == 0:
            parts.append("accel")
        elif V[k - 1] != V[k]:
            parts.append("blend-in")
        parts.append("constant")
        if k == n - 1:
            parts.append("decel")
        elif V[k + 1] != V[k]:
            parts.append("blend-out")
        out.append(" + ".join(parts))
    return out
