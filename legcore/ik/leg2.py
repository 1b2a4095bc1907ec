"""Closed-form kinematics of the 2-DOF planar leg (hip/shoulder pitch + knee/elbow pitch).

Source: seed 003 (Pailos, Bima, Libal — animatronic quadruped), DH Table 1 / eq (1) for the two
moving links and eqs (5)–(9) (law of cosines) for the inverse kinematics.

Leg base frame (the paper's frame 2, the hip/shoulder joint; used for all four legs of
``animatronic_quadruped``): **x down, y forward, z to the robot's right**. The leg moves in the
x–y plane; standard DH with ``a = (l1, l2)``, ``α = (0, 0)``, ``d = 0``::

    x = l1 cos q3 + l2 cos(q3 + q4),   y = l1 sin q3 + l2 sin(q3 + q4),   z = 0

(we index the joints 0 and 1; the paper calls them q3 and q4). A positive angle turns x (down)
toward y (forward), i.e. swings the foot forward.

Inverse kinematics by the law of cosines, eqs (6)–(8)::

    cos q4 = (x² + y² − l1² − l2²) / (2 l1 l2),   sin q4 = ±sqrt(1 − cos² q4),
    q4 = atan2(sin q4, cos q4),   q3 = atan2(y, x) − atan2(l2 sin q4, l1 + l2 cos q4)

The ± is the **branch** = sign of q4 in this frame:

* ``+1`` — :data:`ELBOW_BACK`: the shank is turned further forward than the thigh, so the joint
  between them points backward. The paper's front legs ("codo hacia atrás"); its Table 2 front
  legs have q4 = +20°…+17°.
* ``−1`` — :data:`KNEE_FORWARD`: the joint points forward. The paper's rear legs ("rodilla
  adelante"); Table 2 rear legs have q4 = −20°…−16°.

Seed 003 Table 2 lists, besides the DH angles, the *link angles* ``Ang3, Ang4`` it feeds to the
servos: the thigh and shank directions measured from the forward horizontal, turning downward
(degrees). Every printed row satisfies ``q3 = 90° − Ang3`` and ``q4 = Ang3 − Ang4`` (mod 360°),
see :func:`leg2_link_angles_deg`.

Units: lengths in m, angles in rad (degrees only in the Table 2 helpers, as named).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from legcore.ik.leg3 import (
    BoolArray,
    FloatArray,
    _as_angles,
    _as_branch,
    _as_lengths,
    _as_points,
    _limits_mask,
)

__all__ = [
    "ELBOW_BACK",
    "KNEE_FORWARD",
    "leg2_fk",
    "leg2_ik",
    "leg2_link_angles_deg",
    "leg2_q_from_link_angles_deg",
]

ELBOW_BACK = +1
"""Branch q4 ≥ 0 (front legs of seed 003: elbow points backward)."""
KNEE_FORWARD = -1
"""Branch q4 ≤ 0 (rear legs of seed 003: knee points forward)."""


def leg2_fk(q: ArrayLike, L: ArrayLike) -> FloatArray:
    """Foot position of the 2-DOF leg in its base frame (x down, y forward, z right).

    Args:
        q: joint angles (..., 2) rad — (hip/shoulder, knee/elbow) = the paper's (q3, q4).
        L: link lengths (l1, l2) in m (thigh/upper arm, shank/forearm).

    Returns:
        p: foot positions (..., 3) in m; z is 0 (the leg is planar).
    """
    q = _as_angles(q, 2)
    l1, l2 = _as_lengths(L, 2)
    a, s = q[..., 0], q[..., 0] + q[..., 1]
    x = l1 * np.cos(a) + l2 * np.cos(s)
    y = l1 * np.sin(a) + l2 * np.sin(s)
    return np.stack((x, y, np.zeros_like(x)), -1)


def leg2_ik(
    p: ArrayLike,
    L: ArrayLike,
    branch: ArrayLike,
    q_min: ArrayLike | None = None,
    q_max: ArrayLike | None = None,
    tol: float = 1e-12,
    plane_tol: float = 1e-9,
) -> tuple[FloatArray, BoolArray]:
    """Joint angles putting the foot of the 2-DOF leg at ``p`` (law of cosines, seed 003).

    Args:
        p: foot targets (..., 2) or (..., 3) in m in the leg base frame; with 3 components the
            z (out-of-plane) component must be within ``plane_tol`` of 0, else unreachable.
        L: link lengths (l1, l2) in m.
        branch: sign of q4: :data:`ELBOW_BACK` (+1, front legs) or :data:`KNEE_FORWARD`
            (−1, rear legs); a scalar or an array broadcastable to ``p.shape[:-1]``.
        q_min, q_max: optional joint limits (2,) rad; solutions outside count as unreachable.
        tol: slack (m) on the reach annulus ``|l1 − l2| <= |p| <= l1 + l2``.
        plane_tol: slack (m) on the out-of-plane component.

    Returns:
        ``(q, reachable)``: q (..., 2) rad, NaN where not reachable; reachable (...,) bool.
        Targets are never clipped onto the workspace.
    """
    p = _as_points(p, (2, 3))
    l1, l2 = _as_lengths(L, 2)
    batch = p.shape[:-1]
    eps = _as_branch(branch, batch)
    x, y = p[..., 0], p[..., 1]
    rho = np.hypot(x, y)
    f_out = l1 + l2 - rho
    f_in = rho - abs(l1 - l2)
    ok = (f_out >= -tol) & (f_in >= -tol)
    if p.shape[-1] == 3:
        ok &= np.abs(p[..., 2]) <= plane_tol
    f_out = np.maximum(f_out, 0.0)
    f_in = np.maximum(f_in, 0.0)
    with np.errstate(invalid="ignore", over="ignore"):  # non-finite targets end up NaN
        cos4 = (x * x + y * y - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)  # eq (6)
        # sqrt(1 − cos² q4), eq (7), in factored form (no cancellation near full extension).
        disc = f_out * (rho + l1 + l2) * f_in * (rho + abs(l1 - l2))
        sin4 = eps * np.sqrt(disc) / (2.0 * l1 * l2)
        q4 = np.arctan2(sin4, cos4)  # eq (8)
        q3 = np.arctan2(y, x) - np.arctan2(l2 * sin4, l1 + l2 * cos4)
        q3 = np.mod(q3 + np.pi, 2.0 * np.pi) - np.pi
    q = np.stack((q3, q4), -1)
    ok &= _limits_mask(q, q_min, q_max, 2) & np.all(np.isfinite(q), axis=-1)
    q = np.where(ok[..., None], q, np.nan)
    return q, ok


def leg2_link_angles_deg(q: ArrayLike) -> FloatArray:
    """Seed 003 Table 2 link angles ``(Ang3, Ang4)`` (..., 2) in degrees from DH ``q`` (rad).

    ``Ang3 = 90° − q3`` (thigh) and ``Ang4 = 90° − (q3 + q4)`` (shank): each link's direction
    measured from the forward horizontal, turning downward — what the paper's drawing device
    (its Fig. 9) reads with protractors and what its servos are mapped from.
    """
    q = np.degrees(_as_angles(q, 2))
    return np.stack((90.0 - q[..., 0], 90.0 - q[..., 0] - q[..., 1]), -1)


def leg2_q_from_link_angles_deg(angles: ArrayLike) -> FloatArray:
    """Inverse of :func:`leg2_link_angles_deg`: DH ``q`` (..., 2) rad from ``(Ang3, Ang4)`` deg,
    i.e. ``q3 = 90° − Ang3``, ``q4 = Ang3 − Ang4``."""
    ang = _as_angles(angles, 2, name="angles")
    return np.radians(np.stack((90.0 - ang[..., 0], ang[..., 0] - ang[..., 1]), -1))
