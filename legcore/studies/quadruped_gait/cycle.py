"""Batched building blocks of the ``quadruped_gait`` study (seed 003): the periodic foot cycle of
a 2-DOF leg, its joint rates, the stance-foot loads and the servo mapping.

Everything is vectorised over leading batch axes (population × samples × legs) and in SI units.

**Foot cycle** (leg base frame of :mod:`legcore.ik.leg2`: x down, y forward). A leg's local
phase ``u ∈ [0, 1)`` (:func:`legcore.gaits.leg_phase`: the leg lifts off at ``u = 0``) splits into

* swing ``u < 1 − β`` ("retracción", in the air), progress ``σ = u / (1 − β)``::

      y(σ) = y_b + v σ + (s − v) S(σ),   S = 10σ³ − 15σ⁴ + 6σ⁵,   v = −s (1 − β) / β
      x(σ) = H − h · η(σ)

  ``y_b = c − s/2`` (lift-off, back), ``y_b + s`` (touch-down, front). The quintic ``y`` matches
  the stance's position, velocity (the foot slides back at the body speed) and zero acceleration
  at both ends, so the whole cycle is C² and the joint accelerations stay finite. The lift is
  ``η = 64 σ³ (1 − σ)³`` (built-in: peak 1 at mid-swing, zero velocity and acceleration at both
  ends) or a user profile through points ``(ξ, η)`` (:class:`SwingShape`);
* stance ``u ≥ 1 − β`` ("avance", pushing), progress ``ς = (u − (1 − β)) / β``::

      y = c + s/2 − s ς,   x = H        (a level stroke at depth H)

``s`` step length (stroke of the foot relative to the body, m), ``h`` step height (m), ``β``
duty factor, ``H`` depth of the foot below the hip in stance (m), ``c`` stroke centre (forward of
the hip, m). Derivatives are per unit phase; divide by the cycle time T (T²) for time rates.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import PchipInterpolator

__all__ = [
    "SwingShape",
    "builtin_lift",
    "foot_cycle",
    "leg2_rates",
    "load_share",
    "servo_angles_deg",
    "stance_loads",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def builtin_lift(sigma: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Built-in lift profile ``η = 64 σ³ (1 − σ)³`` and its first two σ-derivatives."""
    a = sigma * (1.0 - sigma)
    eta = 64.0 * a**3
    d1 = 192.0 * a * a * (1.0 - 2.0 * sigma)
    d2 = 384.0 * a * ((1.0 - 2.0 * sigma) ** 2 - a)
    return eta, d1, d2


def _smoothstep(sigma: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``S = 10σ³ − 15σ⁴ + 6σ⁵`` and its first two derivatives."""
    s2 = sigma * sigma
    S = s2 * sigma * (10.0 + sigma * (-15.0 + 6.0 * sigma))
    a = sigma * (1.0 - sigma)
    return S, 30.0 * a * a, 60.0 * a * (1.0 - 2.0 * sigma)


@dataclass(frozen=True, eq=False)
class SwingShape:
    """A user swing profile: lift fraction ``η`` against horizontal progress ``ξ``.

    ``points`` (M, 2): ``(ξ, η)`` with ξ strictly increasing from −0.5 (lift-off, back of the
    stroke) to +0.5 (touch-down, front), η ≥ 0, η = 0 at both ends; η is normalised by its
    maximum, so the peak equals the step height. Interpolated by a shape-preserving PCHIP
    (no overshoot, so the foot never dips below the ground). Evaluated at the monotone progress
    ``ξ = S(σ) − ½`` (the smoothstep of the swing time), which gives zero lift velocity and
    acceleration at both ends of the swing. The horizontal motion is the module's quintic
    ``y(σ)``, which differs from ``S(σ)`` only by the stance-velocity term ``v (σ − S)``
    (≤ 0.1 |v| in σ units: a few mm), so the foot path follows the points up to that shift.
    """

    points: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        P = np.asarray(self.points, dtype=float)
        if P.ndim != 2 or P.shape[1] != 2 or P.shape[0] < 3:
            raise ValueError(
                f"swing_points: expected at least 3 (xi, eta) pairs, got shape {P.shape}"
            )
        if not np.all(np.isfinite(P)):
            raise ValueError("swing_points: values must be finite")
        xi, eta = P[:, 0], P[:, 1]
        if abs(xi[0] + 0.5) > 1e-9 or abs(xi[-1] - 0.5) > 1e-9:
            raise ValueError(
                f"swing_points: xi must run from -0.5 (lift-off) to 0.5 (touch-down), "
                f"got {xi[0]} ... {xi[-1]}"
            )
        if np.any(np.diff(xi) <= 0.0):
            raise ValueError("swing_points: xi must be strictly increasing")
        if np.any(eta < 0.0):
            raise ValueError("swing_points: eta (lift) must be >= 0 (the ground is at 0)")
        if abs(eta[0]) > 1e-12 or abs(eta[-1]) > 1e-12:
            raise ValueError("swing_points: eta must be 0 at lift-off and touch-down")
        if eta.max() <= 0.0:
            raise ValueError("swing_points: eta must rise above 0 somewhere")

    def _interp(self) -> PchipInterpolator:
        P = np.asarray(self.points, dtype=float)
        return PchipInterpolator(P[:, 0], P[:, 1] / P[:, 1].max(), extrapolate=False)

    def lift(self, sigma: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``η(σ)`` and its first two σ-derivatives (σ = swing progress in [0, 1])."""
        f = self._interp()
        S, S1, S2 = _smoothstep(sigma)
        xi = np.clip(S - 0.5, -0.5, 0.5)
        e0 = np.nan_to_num(f(xi))
        e1 = np.nan_to_num(f.derivative(1)(xi))
        e2 = np.nan_to_num(f.derivative(2)(xi))
        return e0, e1 * S1, e2 * S1 * S1 + e1 * S2


def foot_cycle(
    u: ArrayLike,
    s: ArrayLike,
    h: ArrayLike,
    beta: ArrayLike,
    depth: float,
    center: float,
    shape: SwingShape | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray, BoolArray]:
    """Foot position and its phase derivatives over one gait cycle (module docstring).

    Args:
        u: leg-local phase (...,) in [0, 1).
        s, h, beta: step length (m), step height (m), duty factor — broadcastable to ``u``.
        depth: foot depth below the hip in stance, H (m); center: stroke centre c (m).
        shape: user swing profile, or None for the built-in ``64 σ³ (1 − σ)³``.

    Returns:
        ``(p, dp, ddp, stance)``: p (..., 2) m in the leg frame (x down, y forward); dp, ddp
        (..., 2) its first and second derivatives per unit phase; stance (...,) bool.
    """
    u, s, h, beta = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (u, s, h, beta)))
    air = 1.0 - beta
    stance = u >= air - 1e-12
    # swing
    sig = np.clip(u / air, 0.0, 1.0)
    S, S1, S2 = _smoothstep(sig)
    v = -s * air / beta
    y_sw = center - 0.5 * s + v * sig + (s - v) * S
    dy_sw = (v + (s - v) * S1) / air
    ddy_sw = (s - v) * S2 / (air * air)
    eta, e1, e2 = builtin_lift(sig) if shape is None else shape.lift(sig)
    x_sw = depth - h * eta
    dx_sw = -h * e1 / air
    ddx_sw = -h * e2 / (air * air)
    # stance
    y_st = center + 0.5 * s - s * (u - air) / beta
    dy_st = -s / beta
    x = np.where(stance, depth, x_sw)
    y = np.where(stance, y_st, y_sw)
    dx = np.where(stance, 0.0, dx_sw)
    dy = np.where(stance, dy_st, dy_sw)
    ddx = np.where(stance, 0.0, ddx_sw)
    ddy = np.where(stance, 0.0, ddy_sw)
    return (
        np.stack((x, y), -1),
        np.stack((dx, dy), -1),
        np.stack((ddx, ddy), -1),
        stance,
    )


def leg2_rates(
    q: FloatArray, pd: FloatArray, pdd: FloatArray, L: Sequence[float]
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Joint rates of the planar 2-DOF leg from the foot's velocity and acceleration.

    ``q`` (..., 2) rad; ``pd``, ``pdd`` (..., 2) foot velocity / acceleration (x down, y
    forward) in m/s, m/s² (or per unit phase). ``J = [[−y, −l2 s12], [x, l2 c12]]``,
    ``det J = l1 l2 sin q4``; ``q̇ = J⁻¹ ṗ``, ``q̈ = J⁻¹ (p̈ − J̇ q̇)`` with
    ``J̇ q̇ = −(l1 c1 q̇1² + l2 c12 Ω², l1 s1 q̇1² + l2 s12 Ω²)``, ``Ω = q̇1 + q̇2``.

    Returns ``(qd, qdd, det)``; where ``det`` is 0 (straight leg) the rates are inf/NaN — the
    caller treats those samples as infeasible.
    """
    l1, l2 = float(L[0]), float(L[1])
    q1, q12 = q[..., 0], q[..., 0] + q[..., 1]
    c1, s1, c12, s12 = np.cos(q1), np.sin(q1), np.cos(q12), np.sin(q12)
    x = l1 * c1 + l2 * c12
    y = l1 * s1 + l2 * s12
    det = l1 * l2 * np.sin(q[..., 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det

        def solve(bx: FloatArray, by: FloatArray) -> FloatArray:
            return np.stack(((l2 * c12 * bx + l2 * s12 * by) * inv, (-x * bx - y * by) * inv), -1)

        qd = solve(pd[..., 0], pd[..., 1])
        w1, w = qd[..., 0], qd[..., 0] + qd[..., 1]
        jdx = -(l1 * c1 * w1 * w1 + l2 * c12 * w * w)
        jdy = -(l1 * s1 * w1 * w1 + l2 * s12 * w * w)
        qdd = solve(pdd[..., 0] - jdx, pdd[..., 1] - jdy)
    return qd, qdd, det


def stance_loads(feet: FloatArray, share: FloatArray, com: FloatArray, weight: float) -> FloatArray:
    """Vertical ground reactions (N) on the stance feet that hold a body in static equilibrium.

    ``feet`` (..., k, 2) foot positions in the ground plane (m); ``share`` (..., k) ≥ 0 how
    readily each foot takes load (0 = in the air, 1 = fully planted; :func:`load_share`);
    ``com`` (..., 2) the COM ground projection (m); ``weight`` (N). Solves
    ``Σ f_i = W``, ``Σ f_i (p_i − c) = 0`` (force and the two tipping moments) minimising
    ``Σ f_i² / share_i``: the unique solution on three feet, the weighted least-norm one on
    four (statically indeterminate), so a foot that is about to lift or has just landed
    (small share) hands its load over continuously. With the COM outside the support polygon
    some ``f_i`` come out negative (the stability constraint rejects such steps); with fewer
    than three loaded feet the moment equations are met in the least-squares sense.
    """
    rel = feet - com[..., None, :]  # (..., k, 2)
    r = np.sqrt(np.maximum(share, 0.0))
    A = np.stack((r, r * rel[..., 0], r * rel[..., 1]), -2)  # (..., 3, k)
    b = np.array([weight, 0.0, 0.0])
    return r * np.einsum("...ij,j->...i", np.linalg.pinv(A), b)


def load_share(u: FloatArray, beta: FloatArray, overlap: FloatArray) -> FloatArray:
    """Load share of a foot (...,) in [0, 1] from its local phase ``u`` and duty ``beta``.

    0 in the air; in stance it ramps linearly from 0 at touch-down to 1 after ``overlap``
    (a fraction of the cycle: the four-foot phase of the walk, ``β − 3/4``) and back to 0 at
    lift-off, so the load passes from the lifting foot to the landing one during the
    four-foot phase. ``overlap`` ≤ 0 gives a plain 0/1 share.
    """
    u, beta, overlap = np.broadcast_arrays(u, beta, overlap)
    air = 1.0 - beta
    into = u - air  # cycle fraction since touch-down (negative in the air)
    left = 1.0 - u  # cycle fraction until lift-off
    with np.errstate(divide="ignore", invalid="ignore"):
        ramp = np.clip(np.minimum(into, left) / overlap, 0.0, 1.0)
    ramp = np.where(overlap > 0.0, ramp, 1.0)
    return np.where(into >= -1e-12, ramp, 0.0)


def servo_angles_deg(
    q: FloatArray,
    link_offset: Sequence[float],
    link_matrix: Sequence[Sequence[float]],
    servo_offset: Sequence[float],
    servo_direction: Sequence[float],
) -> tuple[FloatArray, FloatArray]:
    """Seed 003 Table 2 mapping: DH ``q`` (..., 2) rad → link angles and servo commands (deg).

    ``Ang = link_offset + link_matrix @ q_deg`` (the catalog's ``meta["servo"]``: Ang3 =
    90° − q3, Ang4 = 90° − q3 − q4), then ``servo = servo_offset + servo_direction · Ang``.
    Returns ``(Ang, servo)``, each (..., 2) degrees.
    """
    qd = np.degrees(q)
    ang = np.asarray(link_offset, dtype=float) + qd @ np.asarray(link_matrix, dtype=float).T
    servo = np.asarray(servo_offset, dtype=float) + np.asarray(servo_direction, dtype=float) * ang
    return ang, servo
