"""Cartesian paths made of lines and arcs in a plane in 3D (seed 004, sections III and V).

Geometry is written in 2D plane coordinates w = (u, v) (m) as in the paper; a
``Plane`` (origin + two orthonormal in-plane axes) places it in the world:
``p = origin + u e1 + v e2``. Each ``Segment`` pairs a curve with its own time law
(a profile from ``profiles``); a ``CompositePath`` runs its segments one after the
other. Positions and their analytic time derivatives come from the chain rule
through s(t) (``sampling.compose_time_law``).

- ``Line``: w(s) = w_i (1 − s) + w_f s                                       (eq 14)
- ``Arc``:  u = r cos(φ s + β) + u_c, v = r sin(φ s + β) + v_c, φ > 0 CCW     (eq 17)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.trajectories.profiles import (
    AccelProfile,
    ConstantProfile,
    DecelProfile,
    Profile,
    TrapezoidalProfile,
)
from legcore.trajectories.sampling import PathSample, compose_time_law, time_grid

__all__ = [
    "Arc",
    "CompositePath",
    "Line",
    "PlanarCurve",
    "Plane",
    "Segment",
    "capsule_path",
    "constant_speed_path",
]

#: Gap (m) allowed between the end of one segment and the start of the next.
JOIN_TOL = 1e-6


def _vector(name: str, value: ArrayLike, size: int) -> NDArray[np.float64]:
    arr = np.array(value, dtype=float)
    if arr.shape != (size,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be {size} finite numbers, got {value!r}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Plane:
    """An affine plane in 3D: ``origin`` (3,) m and orthonormal axes ``e1``, ``e2`` (3,).

    In-plane coordinates (u, v) map to ``origin + u e1 + v e2``; the normal is e1 × e2.
    """

    origin: NDArray[np.float64]
    e1: NDArray[np.float64]
    e2: NDArray[np.float64]

    def __post_init__(self) -> None:
        for name in ("origin", "e1", "e2"):
            object.__setattr__(self, name, _vector(name, getattr(self, name), 3))
        if abs(np.linalg.norm(self.e1) - 1.0) > 1e-9 or abs(np.linalg.norm(self.e2) - 1.0) > 1e-9:
            raise ValueError("e1 and e2 must be unit vectors")
        if abs(float(self.e1 @ self.e2)) > 1e-9:
            raise ValueError("e1 and e2 must be orthogonal")

    @classmethod
    def xy(cls, z: float = 0.0) -> Plane:
        """The horizontal plane at height z (m): u = x, v = y."""
        return cls(np.array([0.0, 0.0, float(z)]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0]))

    @property
    def normal(self) -> NDArray[np.float64]:
        """Unit normal e1 × e2, shape (3,)."""
        return np.cross(self.e1, self.e2)

    def to_world(self, w: ArrayLike) -> NDArray[np.float64]:
        """Points (..., 2) in plane coordinates (m) -> (..., 3) world points (m)."""
        w = np.asarray(w, dtype=float)
        return self.origin + w[..., :1] * self.e1 + w[..., 1:2] * self.e2

    def to_world_vectors(self, w: ArrayLike) -> NDArray[np.float64]:
        """Free vectors (..., 2) in plane coordinates -> (..., 3) in the world (no origin)."""
        w = np.asarray(w, dtype=float)
        return w[..., :1] * self.e1 + w[..., 1:2] * self.e2


class PlanarCurve(Protocol):
    """A curve w(s), s in [0, 1], in plane coordinates (m)."""

    @property
    def length(self) -> float: ...

    @property
    def start(self) -> NDArray[np.float64]: ...

    @property
    def end(self) -> NDArray[np.float64]: ...

    def derivatives(self, s: NDArray[np.float64]) -> NDArray[np.float64]:
        """w, dw/ds, d²w/ds², d³w/ds³ at s (K,), shape (4, K, 2)."""
        ...


@dataclass(frozen=True, eq=False)
class Line:
    """Straight line w(s) = w_i (1 − s) + w_f s from ``w_i`` to ``w_f`` (2,) m (eq 14)."""

    w_i: NDArray[np.float64]
    w_f: NDArray[np.float64]

    def __post_init__(self) -> None:
        object.__setattr__(self, "w_i", _vector("w_i", self.w_i, 2))
        object.__setattr__(self, "w_f", _vector("w_f", self.w_f, 2))
        if self.length == 0.0:
            raise ValueError("w_i and w_f must differ (a line needs a length > 0)")

    @property
    def length(self) -> float:
        """Length (m)."""
        return float(np.linalg.norm(self.w_f - self.w_i))

    @property
    def start(self) -> NDArray[np.float64]:
        return self.w_i

    @property
    def end(self) -> NDArray[np.float64]:
        return self.w_f

    def derivatives(self, s: NDArray[np.float64]) -> NDArray[np.float64]:
        """w, w', w'', w''' at s (K,), shape (4, K, 2)."""
        s = np.asarray(s, dtype=float)[:, None]
        dw = self.w_f - self.w_i
        out = np.zeros((4, s.shape[0], 2))
        out[0] = self.w_i * (1.0 - s) + self.w_f * s
        out[1] = dw
        return out


@dataclass(frozen=True, eq=False)
class Arc:
    """Circular arc of radius ``r`` (m) about ``center`` (2,) m (eq 17).

    Starts at angle ``beta`` (rad) and sweeps ``phi`` (rad, > 0 counter-clockwise
    about the plane normal, < 0 clockwise): w(s) = center + r (cos(φ s + β), sin(φ s + β)).
    """

    center: NDArray[np.float64]
    r: float
    beta: float
    phi: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _vector("center", self.center, 2))
        for name in ("r", "beta", "phi"):
            value = float(getattr(self, name))
            if not math.isfinite(value):
                raise ValueError(f"{name} must be finite, got {value!r}")
            object.__setattr__(self, name, value)
        if self.r <= 0.0:
            raise ValueError(f"r must be > 0 m, got {self.r}")
        if self.phi == 0.0:
            raise ValueError("phi must be non-zero (an arc needs a sweep)")

    @property
    def length(self) -> float:
        """Arc length r |φ| (m)."""
        return self.r * abs(self.phi)

    @property
    def start(self) -> NDArray[np.float64]:
        return self.derivatives(np.zeros(1))[0, 0]

    @property
    def end(self) -> NDArray[np.float64]:
        return self.derivatives(np.ones(1))[0, 0]

    def derivatives(self, s: NDArray[np.float64]) -> NDArray[np.float64]:
        """w, w', w'', w''' at s (K,), shape (4, K, 2)."""
        ang = self.phi * np.asarray(s, dtype=float) + self.beta
        cs = np.stack([np.cos(ang), np.sin(ang)], axis=-1)  # (K, 2)
        perp = np.stack([-np.sin(ang), np.cos(ang)], axis=-1)  # d cs / d ang
        r, phi = self.r, self.phi
        return np.stack(
            [
                self.center + r * cs,
                r * phi * perp,
                -r * phi**2 * cs,
                -r * phi**3 * perp,
            ]
        )


@dataclass(frozen=True)
class Segment:
    """One piece of a composite path: a planar curve run with its own time law."""

    curve: Line | Arc | PlanarCurve
    profile: Profile

    @property
    def T(self) -> float:
        """Duration (s) = profile.T."""
        return self.profile.T


@dataclass(frozen=True, eq=False)
class CompositePath:
    """Segments run one after the other in a plane; total duration T = Σ T_k (s).

    Segment k runs on [t_breaks[k], t_breaks[k+1]] with its local time starting at 0
    (seed 004's "second option"). Consecutive segments must join in position (to
    ``JOIN_TOL``); continuity of velocity is up to the chosen profiles.
    """

    segments: tuple[Segment, ...]
    plane: Plane = field(default_factory=Plane.xy)

    def __post_init__(self) -> None:
        segs = tuple(self.segments)
        if not segs:
            raise ValueError("segments must hold at least one Segment")
        for k, seg in enumerate(segs):
            if not isinstance(seg, Segment):
                raise ValueError(f"segments[{k}] must be a Segment, got {type(seg).__name__}")
        for k in range(len(segs) - 1):
            gap = float(np.linalg.norm(segs[k].curve.end - segs[k + 1].curve.start))
            if gap > JOIN_TOL:
                raise ValueError(
                    f"segments[{k + 1}] starts {gap:.3g} m away from the end of segments[{k}]"
                )
        object.__setattr__(self, "segments", segs)

    @property
    def durations(self) -> NDArray[np.float64]:
        """Segment durations T_k (s), shape (n_seg,)."""
        return np.array([seg.T for seg in self.segments])

    @property
    def lengths(self) -> NDArray[np.float64]:
        """Segment lengths D_k (m), shape (n_seg,)."""
        return np.array([seg.curve.length for seg in self.segments])

    @property
    def t_breaks(self) -> NDArray[np.float64]:
        """Segment start times and the end time (s), shape (n_seg + 1,)."""
        return np.concatenate([[0.0], np.cumsum(self.durations)])

    @property
    def T(self) -> float:
        """Total duration (s)."""
        return float(self.durations.sum())

    def evaluate(self, t: ArrayLike) -> PathSample:
        """Position and analytic derivatives at times t (K,) in [0, T] (s)."""
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        if tt.ndim != 1:
            raise ValueError(f"t must be a 1-D array of times, got shape {tt.shape}")
        breaks = self.t_breaks
        T = breaks[-1]
        tol = 1e-9 * max(1.0, T)
        if tt.size and (not np.all(np.isfinite(tt)) or tt.min() < -tol or tt.max() > T + tol):
            raise ValueError(f"t must lie in [0, T] = [0, {T}] s")
        tt = np.clip(tt, 0.0, T)
        idx = np.clip(np.searchsorted(breaks, tt, side="right") - 1, 0, len(self.segments) - 1)
        out = np.empty((4, tt.shape[0], 3))
        for k, seg in enumerate(self.segments):
            mask = idx == k
            if not mask.any():
                continue
            tau = np.clip(tt[mask] - breaks[k], 0.0, seg.T)
            sdot = seg.profile.derivatives(tau)  # (4, m)
            g = seg.curve.derivatives(sdot[0])  # (4, m, 2) in plane coordinates
            gw = np.concatenate([self.plane.to_world(g[:1]), self.plane.to_world_vectors(g[1:])])
            out[:, mask] = compose_time_law(gw, sdot)
        return PathSample(t=tt, p=out[0], pd=out[1], pdd=out[2], pddd=out[3])

    def sample(self, dt: float) -> PathSample:
        """Samples on the uniform grid ``time_grid(T, dt)`` (the end only if T/dt is whole)."""
        return self.evaluate(time_grid(self.T, dt))


def constant_speed_path(
    curves: Sequence[Line | Arc | PlanarCurve],
    V: float,
    t_a: float,
    t_d: float,
    plane: Plane | None = None,
) -> CompositePath:
    """Concatenate curves run at one cruise tool speed V (m/s), as in seed 004 section V.

    The first segment accelerates over t_a (``AccelProfile``), middle segments keep V
    (``ConstantProfile``), the last decelerates over t_d (``DecelProfile``); a single
    curve gets a full ``TrapezoidalProfile``. Segment times follow eqs 19–24, so the
    tool speed is continuous (= V) at every join.
    """
    curves = list(curves)
    if not curves:
        raise ValueError("curves must hold at least one Line or Arc")
    if len(curves) == 1:
        profiles: list[Profile] = [TrapezoidalProfile.from_distance(curves[0].length, V, t_a, t_d)]
    else:
        profiles = [AccelProfile.from_distance(curves[0].length, V, t_a)]
        profiles += [ConstantProfile.from_distance(c.length, V) for c in curves[1:-1]]
        profiles.append(DecelProfile.from_distance(curves[-1].length, V, t_d))
    segments = tuple(Segment(c, p) for c, p in zip(curves, profiles, strict=True))
    return CompositePath(segments, Plane.xy() if plane is None else plane)


def capsule_path(
    *,
    center: ArrayLike = (0.0, 0.30),
    length: float = 0.40,
    r: float = 0.10,
    V: float = 0.10,
    t_a: float = 3.0,
    t_d: float = 3.0,
    plane: Plane | None = None,
) -> CompositePath:
    """Seed 004's capsule (section V, fig. 14), defaults in SI units.

    Two semicircles of radius r joined by two lines of length ``length``, centred at
    ``center`` (plane coordinates, m), run counter-clockwise from the bottom-right
    corner: arc about (u_c + L/2, v_c) from β = −90° sweeping 180° (AccelProfile,
    t_a), top line right→left (ConstantProfile), arc about (u_c − L/2, v_c) from
    β = 90° sweeping 180° (ConstantProfile), bottom line left→right back to the
    start (DecelProfile, t_d), all at cruise speed V.

    Defaults reproduce the paper: arcs centred at (±0.20, 0.30) m, r = 0.10 m, lines
    0.40 m, V = 0.10 m/s, t_a = t_d = 3 s, start/end at (0.20, 0.20) m, on the plane
    z = 0.50 m ("a una altura de 50cm"). Segment times 4.6416, 4, 3.1416, 5.5 s;
    T = 17.2832 s.
    """
    c = _vector("center", center, 2)
    L = float(length)
    if not math.isfinite(L) or L <= 0.0:
        raise ValueError(f"length must be > 0 m, got {length!r}")
    right = c + np.array([L / 2.0, 0.0])
    left = c - np.array([L / 2.0, 0.0])
    curves: list[Line | Arc] = [
        Arc(right, r, -math.pi / 2.0, math.pi),
        Line(right + [0.0, r], left + [0.0, r]),
        Arc(left, r, math.pi / 2.0, math.pi),
        Line(left - [0.0, r], right - [0.0, r]),
    ]
    return constant_speed_path(curves, V, t_a, t_d, Plane.xy(0.50) if plane is None else plane)
