"""Normalised velocity profiles s(t) in [0, 1] (seed 004, section II and IV).

A profile is a time law: it maps time t in [0, T] (s) to the normalised path
parameter s(t) (dimensionless, s(0) = 0, s(T) = 1). Every profile here is a
piecewise polynomial in t, so s, ṡ (1/s), s̈ (1/s²) and s⃛ (1/s³) are exact and
evaluated on whole arrays of t at once.

At a breakpoint where a derivative jumps (e.g. s̈ at the end of a trapezoid's
ramp) the value of the piece starting there is returned; at t = T the value of
the last piece. Jumps of s̈ mean a Dirac in s⃛, which is not represented: s⃛ is
the piecewise (almost-everywhere) jerk.

Seed 004 profiles (one class each):

- ``ConstantProfile``     ṡ = 1/T                                    (eqs 1–3, 34–38)
- ``TrapezoidalProfile``  ramp up t_a, cruise, ramp down t_d         (eqs 4–13)
- ``AccelProfile``        ramp up t_a then cruise (first segment)    (eqs 25–33)
- ``DecelProfile``        cruise then ramp down t_d (last segment)   (eqs 39–49)

plus two smoother rest-to-rest laws:

- ``QuinticProfile``      s = 10τ³ − 15τ⁴ + 6τ⁵, τ = t/T (zero ṡ, s̈ at both ends)
- ``SCurveProfile``       trapezoid whose corners are jerk-limited ramps of
                          duration t_j (7 phases; continuous s̈)

Segment time from a path length D (m) and a tool speed V (m/s): ``segment_time``
(eqs 19–24); every trapezoid-family class also has ``from_distance``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import PPoly

__all__ = [
    "AccelProfile",
    "ConstantProfile",
    "DecelProfile",
    "Profile",
    "QuinticProfile",
    "SCurveProfile",
    "TrapezoidalProfile",
    "segment_time",
]

#: Relative tolerance on t outside [0, T] that is silently clipped (float round-off).
_T_TOL = 1e-9


def _check_positive(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return value


def _check_nonnegative(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or value < 0.0:
        raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    return value


def segment_time(D: float, V: float, t_a: float = 0.0, t_d: float = 0.0) -> float:
    """Duration T (s) of a segment of length D (m) run at cruise tool speed V (m/s).

    The area under the tool-speed curve equals D (seed 004 eqs 19–24):
    ``T = D/V + (t_a + t_d)/2``. With ``t_a = t_d = 0`` this is the constant profile
    (eq 22, T = D/V); with only ``t_a`` the acceleration profile (eq 20,
    T = (V t_a + 2D)/(2V)); with only ``t_d`` the deceleration profile (eq 24); with
    both the full trapezoid. The same T holds for the S-curve with the same ramps.

    Raises ValueError if D is too short to reach V, i.e. ``D < V (t_a + t_d)/2``.
    """
    D = _check_positive("D", D)
    V = _check_positive("V", V)
    t_a = _check_nonnegative("t_a", t_a)
    t_d = _check_nonnegative("t_d", t_d)
    if D < V * (t_a + t_d) / 2.0 * (1.0 - 1e-12):
        raise ValueError(
            f"D={D} m is too short to reach V={V} m/s with t_a={t_a} s and t_d={t_d} s: "
            f"need D >= V (t_a + t_d)/2 = {V * (t_a + t_d) / 2.0} m"
        )
    return D / V + (t_a + t_d) / 2.0


def _jerk_pieces(
    pieces: list[tuple[float, float, float]], sd0: float = 0.0
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Breakpoints and cubic PPoly coefficients from (duration, s̈ at start, s⃛) pieces.

    s and ṡ are carried continuously from s(0) = 0, ṡ(0) = sd0 (1/s); s̈ is given
    per piece so trapezoids (jumps in s̈) and S-curves (continuous s̈) use the same
    builder. Pieces shorter than 1e-12 of the total (round-off) are dropped.
    Returns ``x`` (m+1,) and ``c`` (4, m).
    """
    min_d = 1e-12 * sum(d for d, _, _ in pieces)
    x = [0.0]
    cols = []
    s = 0.0
    sd = sd0
    for d, a, j in pieces:
        if d <= min_d:
            continue
        cols.append((j / 6.0, a / 2.0, sd, s))
        s = s + sd * d + a * d**2 / 2.0 + j * d**3 / 6.0
        sd = sd + a * d + j * d**2 / 2.0
        x.append(x[-1] + d)
    return np.asarray(x), np.asarray(cols).T


class Profile(ABC):
    """Time law s(t): [0, T] -> [0, 1], a piecewise polynomial in t.

    Subclasses are frozen dataclasses with a field ``T`` (duration, s) and define
    ``_pieces()``. Methods take t (s) of any shape and return arrays of that shape;
    ``derivatives`` stacks all four, shape ``(4, *t.shape)``.
    """

    T: float

    @abstractmethod
    def _pieces(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Breakpoints x (m+1,) from 0 to T and PPoly coefficients c (k, m)."""

    @cached_property
    def _ppolys(self) -> tuple[PPoly, PPoly, PPoly, PPoly]:
        x, c = self._pieces()
        x = x.copy()
        x[-1] = self.T  # exact end despite round-off in the accumulated durations
        if c.shape[0] < 4:  # pad to cubic so every derivative up to 3 exists
            c = np.vstack([np.zeros((4 - c.shape[0], c.shape[1])), c])
        pp = PPoly(c, x, extrapolate=True)
        return pp, pp.derivative(1), pp.derivative(2), pp.derivative(3)

    @property
    def breakpoints(self) -> NDArray[np.float64]:
        """Times (s) where the polynomial piece changes, including 0 and T, shape (m+1,)."""
        return self._ppolys[0].x.copy()

    def _time(self, t: ArrayLike) -> NDArray[np.float64]:
        t = np.asarray(t, dtype=float)
        tol = _T_TOL * max(1.0, self.T)
        if t.size and (not np.all(np.isfinite(t)) or t.min() < -tol or t.max() > self.T + tol):
            raise ValueError(
                f"t must lie in [0, T] = [0, {self.T}] s, got values in "
                f"[{np.nanmin(t)}, {np.nanmax(t)}]"
            )
        return np.clip(t, 0.0, self.T)

    def s(self, t: ArrayLike) -> NDArray[np.float64]:
        """Normalised position s(t) (dimensionless), same shape as t."""
        return self._ppolys[0](self._time(t))

    def sd(self, t: ArrayLike) -> NDArray[np.float64]:
        """ṡ(t) (1/s), same shape as t."""
        return self._ppolys[1](self._time(t))

    def sdd(self, t: ArrayLike) -> NDArray[np.float64]:
        """s̈(t) (1/s²), same shape as t."""
        return self._ppolys[2](self._time(t))

    def sddd(self, t: ArrayLike) -> NDArray[np.float64]:
        """s⃛(t) (1/s³), same shape as t (piecewise value, Diracs not represented)."""
        return self._ppolys[3](self._time(t))

    def derivatives(self, t: ArrayLike) -> NDArray[np.float64]:
        """Stack (s, ṡ, s̈, s⃛) at t, shape ``(4, *t.shape)``."""
        tt = self._time(t)
        return np.stack([pp(tt) for pp in self._ppolys])


@dataclass(frozen=True)
class ConstantProfile(Profile):
    """Constant velocity ṡ = v = 1/T, s = t/T (seed 004 eqs 1–3, 34–38).

    Starting from rest it needs an infinite acceleration; use it to continue a
    previous segment at the same tool speed.
    """

    T: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "T", _check_positive("T", self.T))

    @classmethod
    def from_distance(cls, D: float, V: float) -> ConstantProfile:
        """Profile running a length D (m) at tool speed V (m/s): T = D/V (eq 22)."""
        return cls(segment_time(D, V))

    @property
    def v(self) -> float:
        """Cruise value of ṡ (1/s): 1/T (eq 36)."""
        return 1.0 / self.T

    def _pieces(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        return _jerk_pieces([(self.T, 0.0, 0.0)], sd0=self.v)


@dataclass(frozen=True)
class TrapezoidalProfile(Profile):
    """Trapezoidal velocity: ramp up over t_a, cruise at v, ramp down over t_d.

    ``v = 2/(2T − t_a − t_d)`` (seed 004 eq 13). ``s = v t²/(2 t_a)`` on the first
    ramp, ``v t − v t_a/2`` while cruising, ``−v t²/(2 t_d) + v T t/t_d + 1 − v T²/(2 t_d)``
    on the last ramp (eq 11 with t_a in the first piece; the paper prints t_d there).
    t_a = 0 or t_d = 0 are allowed (no ramp on that side); needs t_a + t_d <= T.
    """

    T: float
    t_a: float
    t_d: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "T", _check_positive("T", self.T))
        object.__setattr__(self, "t_a", _check_nonnegative("t_a", self.t_a))
        object.__setattr__(self, "t_d", _check_nonnegative("t_d", self.t_d))
        if self.t_a + self.t_d > self.T * (1.0 + 1e-12):
            raise ValueError(f"t_a + t_d = {self.t_a + self.t_d} s must not exceed T = {self.T} s")

    @classmethod
    def from_distance(cls, D: float, V: float, t_a: float, t_d: float) -> TrapezoidalProfile:
        """Profile running a length D (m) at cruise tool speed V (m/s), T from eqs 19–24."""
        return cls(segment_time(D, V, t_a, t_d), t_a, t_d)

    @property
    def v(self) -> float:
        """Cruise value of ṡ (1/s): 2/(2T − t_a − t_d) (eq 13)."""
        return 2.0 / (2.0 * self.T - self.t_a - self.t_d)

    def _pieces(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        v = self.v
        a_up = v / self.t_a if self.t_a > 0 else 0.0
        a_dn = -v / self.t_d if self.t_d > 0 else 0.0
        cruise = max(self.T - self.t_a - self.t_d, 0.0)
        pieces = [(self.t_a, a_up, 0.0), (cruise, 0.0, 0.0), (self.t_d, a_dn, 0.0)]
        # with t_a = 0 the profile starts already at cruise speed
        return _jerk_pieces(pieces, sd0=v if self.t_a == 0.0 else 0.0)


@dataclass(frozen=True)
class AccelProfile(Profile):
    """Trapezoidal acceleration profile: ramp up over t_a then cruise to T.

    First segment of a concatenation (seed 004 eqs 25–33): ``v = 2/(2T − t_a)``,
    ``s = v t²/(2 t_a)`` for t < t_a, ``s = v t − v t_a/2`` after. Ends at ṡ(T) = v.
    """

    T: float
    t_a: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "T", _check_positive("T", self.T))
        object.__setattr__(self, "t_a", _check_positive("t_a", self.t_a))
        if self.t_a > self.T * (1.0 + 1e-12):
            raise ValueError(f"t_a = {self.t_a} s must not exceed T = {self.T} s")

    @classmethod
    def from_distance(cls, D: float, V: float, t_a: float) -> AccelProfile:
        """Profile for a length D (m) reaching tool speed V (m/s): T = (V t_a + 2D)/(2V) (eq 20)."""
        return cls(segment_time(D, V, t_a=t_a), t_a)

    @property
    def v(self) -> float:
        """Cruise value of ṡ (1/s): 2/(2T − t_a) (eq 27)."""
        return 2.0 / (2.0 * self.T - self.t_a)

    def _pieces(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        return _jerk_pieces([(self.t_a, self.v / self.t_a, 0.0), (self.T - self.t_a, 0.0, 0.0)])


@dataclass(frozen=True)
class DecelProfile(Profile):
    """Trapezoidal deceleration profile: cruise then ramp down over the last t_d.

    Last segment of a concatenation (seed 004 eqs 39–49): ``v = 2/(2T − t_d)``,
    ``s = v t`` for t < T − t_d, ``s = −v t²/(2 t_d) + v T t/t_d + 1 − v T²/(2 t_d)``
    after. Starts at ṡ(0) = v, ends at rest.
    """

    T: float
    t_d: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "T", _check_positive("T", self.T))
        object.__setattr__(self, "t_d", _check_positive("t_d", self.t_d))
        if self.t_d > self.T * (1.0 + 1e-12):
            raise ValueError(f"t_d = {self.t_d} s must not exceed T = {self.T} s")

    @classmethod
    def from_distance(cls, D: float, V: float, t_d: float) -> DecelProfile:
        """Profile for a length D (m) leaving tool speed V (m/s): T = (V t_d + 2D)/(2V) (eq 24)."""
        return cls(segment_time(D, V, t_d=t_d), t_d)

    @property
    def v(self) -> float:
        """Cruise value of ṡ (1/s): 2/(2T − t_d) (eq 41)."""
        return 2.0 / (2.0 * self.T - self.t_d)

    def _pieces(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        v = self.v
        pieces = [(self.T - self.t_d, 0.0, 0.0), (self.t_d, -v / self.t_d, 0.0)]
        return _jerk_pieces(pieces, sd0=v)


@dataclass(frozen=True)
class QuinticProfile(Profile):
    """Rest-to-rest quintic: s = 10τ³ − 15τ⁴ + 6τ⁵ with τ = t/T.

    ṡ = s̈ = 0 at both ends; peak ṡ = 15/(8T) at t = T/2.
    """

    T: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "T", _check_positive("T", self.T))

    def _pieces(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        T = self.T
        c = np.array([[6.0 / T**5], [-15.0 / T**4], [10.0 / T**3], [0.0], [0.0], [0.0]])
        return np.array([0.0, T]), c


@dataclass(frozen=True)
class SCurveProfile(Profile):
    """Jerk-limited (S-curve) trapezoid: 7 phases with continuous s̈.

    The acceleration ramp of duration t_a is itself a trapezoid in s̈: jerk +J_a for
    t_j, constant s̈ = A_a for t_a − 2 t_j, jerk −J_a for t_j; likewise the
    deceleration ramp of duration t_d. Each ramp is point-symmetric, so it covers
    v t_a/2 and the cruise value is ``v = 2/(2T − t_a − t_d)`` exactly as for
    ``TrapezoidalProfile`` (same ``segment_time``). ``A_a = v/(t_a − t_j)``,
    ``J_a = A_a/t_j``. t_j = 0 gives the plain trapezoid; t_j = t_a/2 has no
    constant-acceleration phase. t_a = 0 (or t_d = 0) means no ramp on that side,
    so S-curve acceleration-only / deceleration-only segments are the cases
    t_d = 0 / t_a = 0. Needs t_a + t_d <= T and t_j <= t_a/2, t_d/2 for each ramp
    present.
    """

    T: float
    t_a: float
    t_d: float
    t_j: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "T", _check_positive("T", self.T))
        object.__setattr__(self, "t_a", _check_nonnegative("t_a", self.t_a))
        object.__setattr__(self, "t_d", _check_nonnegative("t_d", self.t_d))
        object.__setattr__(self, "t_j", _check_nonnegative("t_j", self.t_j))
        if self.t_a + self.t_d > self.T * (1.0 + 1e-12):
            raise ValueError(f"t_a + t_d = {self.t_a + self.t_d} s must not exceed T = {self.T} s")
        for name, ramp in (("t_a", self.t_a), ("t_d", self.t_d)):
            if ramp > 0.0 and self.t_j > ramp / 2.0 * (1.0 + 1e-12):
                raise ValueError(f"t_j = {self.t_j} s must not exceed {name}/2 = {ramp / 2.0} s")

    @classmethod
    def from_distance(cls, D: float, V: float, t_a: float, t_d: float, t_j: float) -> SCurveProfile:
        """Profile for a length D (m) at cruise tool speed V (m/s); T as for the trapezoid."""
        return cls(segment_time(D, V, t_a, t_d), t_a, t_d, t_j)

    @property
    def v(self) -> float:
        """Cruise value of ṡ (1/s): 2/(2T − t_a − t_d)."""
        return 2.0 / (2.0 * self.T - self.t_a - self.t_d)

    def _ramp(self, ramp: float, sign: float) -> list[tuple[float, float, float]]:
        if ramp == 0.0:
            return []
        t_j = self.t_j
        A = sign * self.v / (ramp - t_j)
        if t_j == 0.0:
            return [(ramp, A, 0.0)]
        J = A / t_j
        return [(t_j, 0.0, J), (ramp - 2.0 * t_j, A, 0.0), (t_j, A, -J)]

    @property
    def jerk_max(self) -> float:
        """Largest |s⃛| (1/s³) over both ramps; inf when t_j = 0 and a ramp exists."""
        ramps = [r for r in (self.t_a, self.t_d) if r > 0.0]
        if not ramps:
            return 0.0
        if self.t_j == 0.0:
            return math.inf
        return max(self.v / ((r - self.t_j) * self.t_j) for r in ramps)

    def _pieces(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        cruise = max(self.T - self.t_a - self.t_d, 0.0)
        pieces = self._ramp(self.t_a, 1.0) + [(cruise, 0.0, 0.0)] + self._ramp(self.t_d, -1.0)
        return _jerk_pieces(pieces, sd0=self.v if self.t_a == 0.0 else 0.0)
