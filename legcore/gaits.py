"""Gait sequences, support polygons and static stability of legged robots.

Gaits are periodic: the *phase* ``φ ∈ [0, 1)`` runs once per cycle (``φ = (t − t0)/T mod 1``).
Each leg leaves the ground at its ``offset`` and stays in the air for ``1 − duty`` of the cycle::

    u = (φ − offset) mod 1          leg-local phase
    in the air  for u ∈ [0, 1 − duty)      (lifted, then moved forward: "retracción"/"recuperación")
    on the ground for u ∈ [1 − duty, 1)    (pushing the body forward: "avance")

so every leg swings exactly once per cycle. The source figures are kept as data in
:attr:`Gait.states` (equal-length states); the tests check that the offsets/duty reproduce them.

* :data:`TRIPOD` — seed 002 Fig. 3 (hexapod, legs ``L1``…``L6``): six states starting from legs
  1, 3, 5 on the ground and 2, 4, 6 lifted. 1 advance of 1-3-5; 2 recovery of 2-4-6 (θ1 → 0);
  3 transition (2-4-6 down, then 1-3-5 up); 4 advance of 2-4-6; 5 recovery of 1-3-5;
  6 transition. Hence legs 2, 4, 6: offset 0, legs 1, 3, 5: offset 1/2, duty 2/3.
* :data:`QUADRUPED_FIG8` — seed 003 Fig. 8 as printed (legs ``FL, FR, RL, RR`` = the paper's
  PDI, PDD, PTI, PTD): diagonal pairs alternate, FL+RR retract while RL+FR push, then the
  reverse. The printed four "tiempos" are two cycles of this 2-beat (trot-like) sequence.
* :data:`QUADRUPED_WALK` — the 4-beat walk of seed 003's text: "the four legs out of phase by
  exactly a quarter of the cycle". Fig. 8 and the text disagree (Fig. 8 has diagonal partners in
  phase); we keep Fig. 8's pairing — FL and RR swing in one half-cycle, RL and FR in the other —
  and split each pair by a quarter cycle. Of the orders that do so, FL → RR → FR → RL is the
  lateral-sequence walk (LH, LF, RH, RF) that a walking dog — the animal the paper copies — uses,
  and the only one of all six 4-beat orders that keeps the centre inside the support triangle
  with the feet sliding back evenly (margin ≥ 0, zero only at the beat boundaries for duty 3/4).
  Offsets FL 0, RR 1/4, FR 1/2, RL 3/4; duty 3/4.

Support polygon and stability: :func:`support_polygon` (convex hull of the stance feet in the
ground plane, counter-clockwise), :func:`stability_margin` (minimum signed distance from the
body centre / COM projection to the hull's edge lines, positive inside). Seed 002's support
triangle: :func:`support_triangle` (β1, β5, perimeter p, its eqs 12–14), :func:`tripod_feet`,
:func:`tripod_triangle` (both vectorised over a population of θ1 triples) and
:func:`tripod_stability` (its S_f, S_b).

Units: m and rad (any consistent length unit works for the geometric functions).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.ik.leg3 import leg3_fk

__all__ = [
    "GAITS",
    "Gait",
    "GaitState",
    "QUADRUPED_FIG8",
    "QUADRUPED_WALK",
    "TRIPOD",
    "gait_phase",
    "leg_phase",
    "stability_margin",
    "support_flags",
    "support_polygon",
    "support_triangle",
    "tripod_feet",
    "tripod_stability",
    "tripod_triangle",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


# ----------------------------------------------------------------------------------------------
# Gait sequences
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class GaitState:
    """One state of a source figure's gait table (all states of a gait last equally long).

    ``support``: legs on the ground during the state (in a transition both tripods touch the
    ground: the lifted ones are put down before the others are lifted); ``moving``: legs whose
    joints move during it; ``action``: what happens, in words (with the paper's term).
    """

    name: str
    support: frozenset[str]
    moving: frozenset[str]
    action: str


@dataclass(frozen=True)
class Gait:
    """A periodic gait: per-leg lift-off phase ``offsets`` (fractions of the cycle, [0, 1)) and the
    stance fraction ``duty`` (0 < duty < 1), plus the source figure's state table."""

    name: str
    legs: tuple[str, ...]
    offsets: tuple[float, ...]
    duty: float
    states: tuple[GaitState, ...] = ()
    source: str = ""

    def __post_init__(self) -> None:
        if len(self.offsets) != len(self.legs):
            raise ValueError(
                f"offsets: {len(self.offsets)} values for {len(self.legs)} legs {self.legs}"
            )
        if len(set(self.legs)) != len(self.legs):
            raise ValueError(f"legs: names must be unique, got {self.legs}")
        if not all(0.0 <= o < 1.0 for o in self.offsets):
            raise ValueError(f"offsets: must lie in [0, 1), got {self.offsets}")
        if not 0.0 < self.duty < 1.0:
            raise ValueError(f"duty: stance fraction must be in (0, 1), got {self.duty}")

    @property
    def n_legs(self) -> int:
        return len(self.legs)

    def with_duty(self, duty: float) -> Gait:
        """The same sequence with another stance fraction (e.g. > 3/4 for a 4-beat walk with
        four-leg overlap); the state table is dropped when it no longer applies."""
        states = self.states if duty == self.duty else ()
        return Gait(self.name, self.legs, self.offsets, duty, states, self.source)


def gait_phase(t: ArrayLike, period: float, t0: float = 0.0) -> FloatArray:
    """Cycle phase ``((t − t0) / period) mod 1`` (same shape as ``t``; t, t0, period in s)."""
    if not (np.isfinite(period) and period > 0.0):
        raise ValueError(f"period: must be a positive number of seconds, got {period}")
    return np.mod((np.asarray(t, dtype=float) - t0) / period, 1.0)


def leg_phase(gait: Gait, phase: ArrayLike) -> FloatArray:
    """Leg-local phase ``u = (φ − offset) mod 1``, shape ``phase.shape + (n_legs,)``.

    ``u < 1 − duty``: in the air (``u / (1 − duty)`` is the swing progress);
    otherwise on the ground (``(u − (1 − duty)) / duty`` is the stance progress).
    """
    phi = np.asarray(phase, dtype=float)
    return np.mod(phi[..., None] - np.asarray(gait.offsets), 1.0)


def support_flags(gait: Gait, phase: ArrayLike) -> BoolArray:
    """True where a leg is on the ground, shape ``phase.shape + (n_legs,)`` (legs in
    ``gait.legs`` order). ``phase`` is the cycle phase in [0, 1) (see :func:`gait_phase`)."""
    return leg_phase(gait, phase) >= 1.0 - gait.duty - 1e-12


def _fs(*names: str) -> frozenset[str]:
    return frozenset(names)


_HEX = ("L1", "L2", "L3", "L4", "L5", "L6")
_A = _fs("L1", "L3", "L5")
_B = _fs("L2", "L4", "L6")

TRIPOD = Gait(
    name="tripod",
    legs=_HEX,
    offsets=(0.5, 0.0, 0.5, 0.0, 0.5, 0.0),
    duty=2.0 / 3.0,
    states=(
        GaitState(
            "1 advance",
            _A,
            _A,
            "1, 3, 5 on the ground push back (θ1,1 and θ1,3 by −Δθ1, "
            "θ1,5 by +Δθ1): the body advances; 2, 4, 6 stay lifted",
        ),
        GaitState("2 recovery", _A, _B, "2, 4, 6 (in the air) return to θ1 = 0"),
        GaitState(
            "3 transition", _fs(*_HEX), _fs(*_HEX), "2, 4, 6 are put down, then 1, 3, 5 lifted"
        ),
        GaitState("4 advance", _B, _B, "2, 4, 6 on the ground push back; 1, 3, 5 stay lifted"),
        GaitState("5 recovery", _B, _A, "1, 3, 5 (in the air) return to θ1 = 0"),
        GaitState(
            "6 transition", _fs(*_HEX), _fs(*_HEX), "1, 3, 5 are put down, then 2, 4, 6 lifted"
        ),
    ),
    source="seed 002 Fig. 3 (six-state tripod cycle)",
)

_Q = ("FL", "FR", "RL", "RR")

QUADRUPED_FIG8 = Gait(
    name="quadruped_fig8",
    legs=_Q,
    offsets=(0.0, 0.5, 0.5, 0.0),
    duty=0.5,
    states=(
        GaitState(
            "tiempo 1",
            _fs("FR", "RL"),
            _fs(*_Q),
            "retracción PDI (FL) and PTD (RR); avance PTI (RL) and PDD (FR)",
        ),
        GaitState(
            "tiempo 2",
            _fs("FL", "RR"),
            _fs(*_Q),
            "avance PDI (FL) and PTD (RR); retracción PTI (RL) and PDD (FR)",
        ),
    ),
    source="seed 003 Fig. 8 as printed (its tiempos 3, 4 repeat 1, 2)",
)

QUADRUPED_WALK = Gait(
    name="quadruped_walk",
    legs=_Q,
    offsets=(0.0, 0.5, 0.75, 0.25),
    duty=0.75,
    states=(
        GaitState("beat 1", _fs("FR", "RL", "RR"), _fs(*_Q), "FL (PDI) swings; others push"),
        GaitState("beat 2", _fs("FL", "FR", "RL"), _fs(*_Q), "RR (PTD) swings; others push"),
        GaitState("beat 3", _fs("FL", "RL", "RR"), _fs(*_Q), "FR (PDD) swings; others push"),
        GaitState("beat 4", _fs("FL", "FR", "RR"), _fs(*_Q), "RL (PTI) swings; others push"),
    ),
    source="seed 003 text (quarter-cycle offsets) with Fig. 8's diagonal pairing per half cycle",
)


GAITS: dict[str, Gait] = {g.name: g for g in (TRIPOD, QUADRUPED_WALK, QUADRUPED_FIG8)}
"""The built-in gaits by name (``LeggedRobot.meta["gait"]`` names the catalog robots' default)."""


# ----------------------------------------------------------------------------------------------
# Support polygon and stability margin
# ----------------------------------------------------------------------------------------------


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _prepare(feet: ArrayLike, support: ArrayLike | None) -> tuple[FloatArray, BoolArray, float]:
    P = np.asarray(feet, dtype=float)
    if P.ndim < 2 or P.shape[-1] not in (2, 3):
        raise ValueError(f"feet: expected shape (..., k, 2) or (..., k, 3), got {P.shape}")
    P = P[..., :2]
    if support is None:
        S = np.ones(P.shape[:-1], dtype=bool)
    else:
        S = np.asarray(support, dtype=bool)
        try:
            S = np.broadcast_to(S, P.shape[:-1])
        except ValueError:
            raise ValueError(
                f"support: shape {S.shape} does not match feet {P.shape[:-1]} (..., k)"
            ) from None
    S = S & np.all(np.isfinite(P), axis=-1)
    finite = P[np.broadcast_to(S[..., None], P.shape)]
    scale = float(np.abs(finite).max()) if finite.size else 1.0
    return P, S, max(scale, 1e-300)


def _hull_edges(P: FloatArray, S: BoolArray, eps_area: float, eps_len: float) -> BoolArray:
    """(..., k, k) True where i→j is a counter-clockwise edge line of the stance hull (every
    stance foot on its left or on it)."""
    k = P.shape[-2]
    d = P[..., None, :, :] - P[..., :, None, :]  # d[..., i, j] = P_j − P_i
    rel = P[..., None, :, :] - P[..., :, None, :]  # rel[..., i, m] = P_m − P_i
    cr = _cross(d[..., :, :, None, :], rel[..., :, None, :, :])  # (..., i, j, m)
    left = (cr >= -eps_area) | ~S[..., None, None, :]
    pair = S[..., :, None] & S[..., None, :] & ~np.eye(k, dtype=bool)
    pair &= np.linalg.norm(d, axis=-1) > eps_len
    return pair & np.all(left, axis=-1)


def _degenerate(P: FloatArray, S: BoolArray, eps_area: float) -> BoolArray:
    """(...,) True where fewer than three stance feet or all stance feet are collinear."""
    rel = P[..., None, :, :] - P[..., :, None, :]  # (..., i, m)
    cr = _cross(rel[..., :, :, None, :], rel[..., :, None, :, :])  # (..., i, j, m)
    mask = S[..., :, None, None] & S[..., None, :, None] & S[..., None, None, :]
    area = np.where(mask, np.abs(cr), 0.0).max(axis=(-3, -2, -1), initial=0.0)
    return (S.sum(axis=-1) < 3) | (area <= eps_area)


def support_polygon(
    feet: ArrayLike, support: ArrayLike | None = None
) -> tuple[FloatArray, NDArray[np.int64]]:
    """Convex hull of the stance feet projected on the ground plane (x, y).

    Args:
        feet: foot positions (..., k, 2|3) (m); only x and y are used.
        support: (..., k) bool, True for feet on the ground (default: all).

    Returns:
        ``(vertices, n)``: vertices (..., k, 2) counter-clockwise, padded with NaN after the
        first ``n`` rows; n (...,) the number of hull vertices (collinear stance feet give the
        two end points, coincident feet count once).
    """
    P, S, scale = _prepare(feet, support)
    k = P.shape[-2]
    eps_len = 1e-12 * scale
    eps_area = 1e-12 * scale * scale
    edges = _hull_edges(P, S, eps_area, eps_len)
    # Drop feet lying strictly inside a hull edge (collinear middle points) and duplicates.
    d = P[..., None, :, :] - P[..., :, None, :]  # (..., i, j)
    rel = P[..., None, :, :] - P[..., :, None, :]  # (..., i, m)
    cr = _cross(d[..., :, :, None, :], rel[..., :, None, :, :])  # (..., i, j, m)
    dd = np.sum(d * d, axis=-1)[..., None]
    t = np.sum(d[..., :, :, None, :] * rel[..., :, None, :, :], axis=-1) / np.where(dd > 0, dd, 1.0)
    inner = (np.abs(cr) <= eps_area) & (t > 1e-12) & (t < 1.0 - 1e-12) & edges[..., None]
    inner = inner.any(axis=(-3, -2))
    close = np.linalg.norm(rel, axis=-1) <= eps_len  # (..., i, m)
    earlier = np.tril(np.ones((k, k), dtype=bool), -1)  # i < m  ->  [m, i] lower triangle
    dup = np.any(close.swapaxes(-1, -2) & earlier & S[..., None, :], axis=-1)
    vert = S & ~inner & ~dup & (edges.any(axis=-1) | (S.sum(axis=-1, keepdims=True) == 1))
    n = vert.sum(axis=-1)
    # Counter-clockwise order by angle about the vertex centroid.
    w = vert.astype(float)
    centre = np.sum(P * w[..., None], axis=-2) / np.maximum(n, 1)[..., None]
    ang = np.arctan2(P[..., 1] - centre[..., None, 1], P[..., 0] - centre[..., None, 0])
    ang = np.where(vert, ang, np.inf)
    order = np.argsort(ang, axis=-1, kind="stable")
    V = np.take_along_axis(P, order[..., None], axis=-2)
    keep = np.arange(k) < n[..., None]
    V = np.where(keep[..., None], V, np.nan)
    return V, n.astype(np.int64)


def stability_margin(
    feet: ArrayLike, support: ArrayLike | None = None, c: ArrayLike | None = None
) -> FloatArray:
    """Static stability margin: minimum signed distance from ``c`` to the support-polygon edges.

    Args:
        feet: foot positions (..., k, 2|3) (m), x and y used.
        support: (..., k) bool, True for feet on the ground (default: all).
        c: body centre / COM ground projection (2,) or (..., 2|3) (m); default the origin.

    Returns:
        (...,) margin in m. Inside the polygon it is the distance to the nearest edge (> 0);
        outside it is negative (the largest excursion beyond an edge line). With fewer than three
        stance feet or collinear ones (zero-area support) it is minus the distance to the
        support segment/point (≤ 0); with no foot on the ground −inf.
    """
    P, S, scale = _prepare(feet, support)
    C = np.zeros(2) if c is None else np.asarray(c, dtype=float)
    if C.ndim == 0 or C.shape[-1] not in (2, 3):
        raise ValueError(f"c: expected shape (2,) or (..., 2|3), got {C.shape}")
    C = C[..., :2]
    scale = max(scale, float(np.abs(C).max()) if C.size else 0.0)
    eps_len = 1e-12 * scale
    eps_area = 1e-12 * scale * scale
    batch = np.broadcast_shapes(P.shape[:-2], C.shape[:-1])
    P = np.broadcast_to(P, batch + P.shape[-2:])
    S = np.broadcast_to(S, batch + S.shape[-1:])
    C = np.broadcast_to(C, batch + (2,))

    edges = _hull_edges(P, S, eps_area, eps_len)
    d = P[..., None, :, :] - P[..., :, None, :]  # (..., i, j)
    rc = C[..., None, :] - P  # (..., i, 2): c − P_i
    length = np.linalg.norm(d, axis=-1)
    signed = _cross(d, rc[..., :, None, :]) / np.where(length > 0, length, 1.0)
    m_poly = np.where(edges, signed, np.inf).min(axis=(-2, -1), initial=np.inf)

    # Degenerate support: minus the distance to the segment hull of the stance feet.
    dd = length**2
    t = np.sum(d * rc[..., :, None, :], axis=-1) / np.where(dd > 0, dd, 1.0)
    t = np.clip(t, 0.0, 1.0)
    gap = rc[..., :, None, :] - t[..., None] * d
    dist = np.linalg.norm(gap, axis=-1)
    pair = S[..., :, None] & S[..., None, :]
    m_seg = -np.where(pair, dist, np.inf).min(axis=(-2, -1), initial=np.inf)

    degenerate = _degenerate(P, S, eps_area)
    return np.where(degenerate, m_seg, m_poly)


# ----------------------------------------------------------------------------------------------
# Seed 002: the tripod's support triangle
# ----------------------------------------------------------------------------------------------


def _xy(p: ArrayLike, name: str) -> FloatArray:
    arr = np.asarray(p, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] not in (2, 3):
        raise ValueError(f"{name}: expected shape (..., 2) or (..., 3), got {arr.shape}")
    return arr[..., :2]


def support_triangle(
    p1: ArrayLike,
    p3: ArrayLike,
    p5: ArrayLike,
    formula: Literal["interior", "paper"] = "interior",
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Seed 002 eqs (12)–(14): angles β1 (at foot 1), β5 (at foot 5) and perimeter p of the
    support triangle of feet 1, 3, 5 (each (..., 2|3), m; x, y used).

    ``d1 = |p1 − p3|``, ``d2 = |p3 − p5|``, ``d3 = |p1 − p5|``, ``p = d1 + d2 + d3`` (eq 14).

    ``formula="interior"`` (default): the triangle's interior angles at feet 1 and 5
    (``atan2(|u × v|, u · v)``), invariant to how the triangle sits in the plane.
    ``formula="paper"``: eq (12) and (13) literally,
    ``β1 = atan((x1−x5)/(y1−y5)) + atan((x1−x3)/(y1−y3))``, ``β5 = asin(sin β1 · d1/d2)``.
    The two agree when foot 3 is straight behind foot 1 (``x1 = x3``, as in the paper's initial
    stance); otherwise eq (12)'s "+" would need to be "−" (the second term measures the tilt of
    edge 1–3, which *reduces* the angle) and eq (13)'s arcsine cannot return an obtuse β5.

    Returns:
        ``(beta1, beta5, perimeter)`` each of the broadcast batch shape (rad, rad, m).
    """
    a, b, c = _xy(p1, "p1"), _xy(p3, "p3"), _xy(p5, "p5")
    d1 = np.linalg.norm(a - b, axis=-1)
    d2 = np.linalg.norm(b - c, axis=-1)
    d3 = np.linalg.norm(a - c, axis=-1)
    perimeter = d1 + d2 + d3
    if formula == "interior":
        u, v = b - a, c - a
        beta1 = np.arctan2(np.abs(_cross(u, v)), np.sum(u * v, axis=-1))
        u, v = a - c, b - c
        beta5 = np.arctan2(np.abs(_cross(u, v)), np.sum(u * v, axis=-1))
    elif formula == "paper":
        with np.errstate(divide="ignore", invalid="ignore"):
            beta1 = np.arctan((a[..., 0] - c[..., 0]) / (a[..., 1] - c[..., 1])) + np.arctan(
                (a[..., 0] - b[..., 0]) / (a[..., 1] - b[..., 1])
            )
            beta5 = np.arcsin(np.sin(beta1) * d1 / d2)
    else:
        raise ValueError(f"formula: must be 'interior' or 'paper', got {formula!r}")
    return beta1, beta5, perimeter


def tripod_feet(
    theta1: ArrayLike,
    hips: ArrayLike,
    L: ArrayLike,
    theta2: ArrayLike,
    theta3: ArrayLike,
) -> FloatArray:
    """Body-frame foot positions of three 3-DOF legs for a batch of coxa angles.

    Args:
        theta1: coxa angles (..., 3) rad, one per leg (seed 002: legs 1, 3, 5 in that order).
        hips: (3, 4, 4) hip placements of those legs in the body frame (m).
        L: link lengths (3,) m.
        theta2, theta3: femur and tibia angles (rad), scalars or broadcastable to (..., 3).

    Returns:
        feet (..., 3, 3): foot k of sample b at ``feet[b, k]`` (m), via eqs (5)–(7).
    """
    th1 = np.asarray(theta1, dtype=float)
    if th1.ndim == 0 or th1.shape[-1] != 3:
        raise ValueError(f"theta1: expected shape (..., 3), got {th1.shape}")
    H = np.asarray(hips, dtype=float)
    if H.shape != (3, 4, 4):
        raise ValueError(f"hips: expected shape (3, 4, 4), got {H.shape}")
    th2, th3 = np.broadcast_arrays(th1, np.asarray(theta2, float), np.asarray(theta3, float))[1:]
    p_leg = leg3_fk(np.stack((th1, th2, th3), -1), L)  # (..., 3, 3) in each hip frame
    return np.einsum("kij,...kj->...ki", H[:, :3, :3], p_leg) + H[:, :3, 3]


def tripod_triangle(
    theta1: ArrayLike,
    hips: ArrayLike,
    L: ArrayLike,
    theta2: ArrayLike,
    theta3: ArrayLike,
    formula: Literal["interior", "paper"] = "interior",
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """β1, β5, perimeter (seed 002 eqs 12–14) for a population of θ1 triples (..., 3) of legs
    1, 3, 5 — :func:`tripod_feet` followed by :func:`support_triangle`."""
    F = tripod_feet(theta1, hips, L, theta2, theta3)
    return support_triangle(F[..., 0, :], F[..., 1, :], F[..., 2, :], formula=formula)


UNBOUNDED_SPANS = 100.0
"""A tripod stability distance beyond this many tripod spans is reported as unbounded (inf)."""


def tripod_stability(
    front: ArrayLike,
    middle: ArrayLike,
    back: ArrayLike,
    c: ArrayLike | None = None,
    axis: ArrayLike = (1.0, 0.0),
) -> tuple[FloatArray, FloatArray]:
    """Seed 002's stability distances S_f and S_b of a tripod (its Fig. 6).

    ``S_f`` is the distance, measured along ``axis`` (default the body x axis, as the paper says:
    "la distancia S_f sobre el eje x"), from the body centre ``c`` to the diagonal through the
    middle foot and the front foot; ``S_b`` the same for the diagonal through the middle and back
    feet. Each is signed positive when ``c`` is on the triangle's side of that diagonal (the
    side of the third foot), so the robot is statically stable while ``S_f > 0`` and ``S_b > 0``.

    Args:
        front, middle, back: foot positions (..., 2|3) (m); for stance 1-3-5 of seed 002's
            hexapod front = leg 1, middle = leg 5, back = leg 3.
        c: body centre / COM ground projection, default the origin.
        axis: measuring direction (2,) in the ground plane (normalised here).

    Returns:
        ``(S_f, S_b)`` (m); ±inf where the distance is unbounded: a diagonal parallel to
        ``axis``, or so nearly parallel that the distance exceeds ``UNBOUNDED_SPANS`` (100) times
        the tripod's span (the largest of |front − middle|, |back − middle|, |c − middle|) — a
        number like 16 642.8 m measures how parallel the lines are, not how stable the body is.
    """
    f, m, b = _xy(front, "front"), _xy(middle, "middle"), _xy(back, "back")
    C = np.zeros(2) if c is None else _xy(c, "c")
    u = np.asarray(axis, dtype=float)
    if u.shape != (2,) or not np.all(np.isfinite(u)) or np.linalg.norm(u) == 0.0:
        raise ValueError(f"axis: expected a non-zero finite 2-vector, got {u}")
    u = u / np.linalg.norm(u)

    def along(end: FloatArray, other: FloatArray) -> FloatArray:
        d = end - m
        side_c = _cross(d, C - m)
        side_o = _cross(d, other - m)
        denom = np.abs(_cross(d, np.broadcast_to(u, d.shape)))
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = np.abs(side_c) / denom
        span = np.maximum(
            np.linalg.norm(d, axis=-1),
            np.maximum(np.linalg.norm(other - m, axis=-1), np.linalg.norm(C - m, axis=-1)),
        )
        dist = np.where(dist > UNBOUNDED_SPANS * span, np.inf, dist)
        dist = np.where(side_c == 0.0, 0.0, dist)
        return np.where(side_c * side_o >= 0.0, dist, -dist)

    return along(f, b), along(b, f)
