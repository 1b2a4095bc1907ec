"""Closed-form kinematics of the 3-DOF insect/mammal leg (coxa yaw, femur pitch, tibia pitch).

Source: seed 002 (Domínguez et al., hexapod workspace), Table 1 and eqs (5)–(10); the same chain
is the leg of seed 000 (``calderon_leg``). Standard DH in the leg base (hip) frame, z up, x along
the leg at q = 0::

    link   a     alpha   d   theta
    1      L1    +90°    0   q1      (coxa, yaw about the vertical)
    2      L2    0       0   q2      (femur, pitch)
    3      L3    0       0   q3      (tibia, pitch)

Forward kinematics, eqs (5)–(7) (``R = L1 + L2 cos q2 + L3 cos(q2 + q3)``)::

    x = R cos q1,   y = R sin q1,   z = L2 sin q2 + L3 sin(q2 + q3)

Inverse kinematics, eqs (8)–(10), with ``r = sqrt(x² + y²) − L1``, ``a = 2 L2 r``,
``b = 2 L2 z``, ``c = r² + z² + L2² − L3²``::

    q1 = atan2(y, x)
    q2 = atan2(c, ε sqrt(a² + b² − c²)) − atan2(a, b)
    q3 = ε arccos[(r² + z² − L2² − L3²) / (2 L2 L3)]

The paper prints ``sqrt(a² + b² + c²)`` in eq (9); the derivation (``a cos q2 + b sin q2 = c``)
needs ``a² + b² − c²`` — we use the latter. The paper also prints eq (10) without a sign although
its own posture has q3 = −π/4: the sign ε of q3 is the *knee branch* and the same ε must be used
in eq (9) (checked numerically: that pairing reproduces every reachable point). ``branch = −1``
(:data:`KNEE_UP`, q3 ≤ 0) is the paper's posture: the knee lies above the line from the femur joint
to the foot. ``branch = +1`` (:data:`KNEE_DOWN`) is the other solution.

For numerical accuracy near the workspace boundary the square roots are evaluated in factored form
(``a² + b² − c² = (L2+L3−ρ)(ρ−L2+L3)(ρ+L2−L3)(ρ+L2+L3)`` with ``ρ = sqrt(r² + z²)``), which is the
same quantity without cancellation.

A target whose foot lies behind the yaw axis (``R < 0`` in eq 5) is also reachable with
``q1 = atan2(y, x) ± π``; that family is tried only where eq (8)'s family fails (and the joint
limits, if given, allow it). ``branch`` is always the sign of q3.

Units: lengths in m (any consistent unit works), angles in rad.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["KNEE_DOWN", "KNEE_UP", "leg3_fk", "leg3_ik"]

KNEE_UP = -1
"""Branch of q3 ≤ 0: knee above the femur-joint→foot line (seed 002's posture q3 = −π/4)."""
KNEE_DOWN = +1
"""Branch of q3 ≥ 0: knee below the femur-joint→foot line."""

# --- argument checks shared with legcore.ik.leg2 -------------------------------------

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def _as_lengths(L: ArrayLike, n: int, name: str = "L") -> FloatArray:
    """Validate link lengths: shape (n,), finite, ``L[0] >= 0`` and the others ``> 0`` (m)."""
    arr = np.asarray(L, dtype=float)
    if arr.shape != (n,):
        raise ValueError(f"{name}: expected {n} link lengths (m), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: link lengths must be finite, got {arr.tolist()}")
    first_free = 1 if n == 3 else 0  # the 3-DOF leg's coxa may have zero length
    if np.any(arr[:first_free] < 0.0) or np.any(arr[first_free:] <= 0.0):
        raise ValueError(f"{name}: link lengths must be positive (m), got {arr.tolist()}")
    return arr


def _as_points(p: ArrayLike, dims: tuple[int, ...], name: str = "p") -> FloatArray:
    """Return ``p`` as a float array whose last axis has one of the sizes ``dims``."""
    arr = np.asarray(p, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] not in dims:
        want = " or ".join(str(d) for d in dims)
        raise ValueError(f"{name}: last axis must have size {want}, got shape {arr.shape}")
    return arr


def _as_angles(q: ArrayLike, n: int, name: str = "q") -> FloatArray:
    """Return ``q`` as a float array of shape (..., n)."""
    arr = np.asarray(q, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] != n:
        raise ValueError(
            f"{name}: last axis must have size {n} (joint angles, rad), got shape {arr.shape}"
        )
    return arr


def _as_branch(branch: ArrayLike, batch_shape: tuple[int, ...], name: str = "branch") -> FloatArray:
    """Validate a branch selector (+1 / -1, scalar or broadcastable to the batch shape)."""
    arr = np.asarray(branch, dtype=float)
    if not np.all((arr == 1.0) | (arr == -1.0)):
        raise ValueError(f"{name}: must be +1 or -1 (sign of the knee/elbow joint angle)")
    try:
        return np.broadcast_to(arr, batch_shape)
    except ValueError:
        raise ValueError(
            f"{name}: shape {arr.shape} does not broadcast to the batch shape {batch_shape}"
        ) from None


def _limits_mask(
    q: FloatArray, q_min: ArrayLike | None, q_max: ArrayLike | None, n: int, tol: float = 1e-12
) -> BoolArray:
    """(...,) True where ``q`` (..., n) lies inside ``[q_min, q_max]`` (each (n,) or None)."""
    ok = np.ones(q.shape[:-1], dtype=bool)
    for bound, name, sign in ((q_min, "q_min", 1.0), (q_max, "q_max", -1.0)):
        if bound is None:
            continue
        b = np.asarray(bound, dtype=float)
        if b.shape != (n,):
            raise ValueError(f"{name}: expected shape ({n},), got {b.shape}")
        ok &= np.all(sign * (q - b) >= -tol, axis=-1)
    return ok


def leg3_fk(q: ArrayLike, L: ArrayLike) -> FloatArray:
    """Foot position of the 3-DOF leg in its base (hip) frame, seed 002 eqs (5)–(7).

    Args:
        q: joint angles (..., 3) rad — (q1 coxa yaw, q2 femur pitch, q3 tibia pitch).
        L: link lengths (L1, L2, L3) in m.

    Returns:
        p: foot positions (..., 3) in m.
    """
    q = _as_angles(q, 3)
    L1, L2, L3 = _as_lengths(L, 3)
    q1, q2, q3 = q[..., 0], q[..., 1], q[..., 2]
    R = L1 + L2 * np.cos(q2) + L3 * np.cos(q2 + q3)
    return np.stack((R * np.cos(q1), R * np.sin(q1), L2 * np.sin(q2) + L3 * np.sin(q2 + q3)), -1)


def _planar(
    r: FloatArray, z: FloatArray, L2: float, L3: float, eps: FloatArray, tol: float
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Eqs (9)–(10) for a target (r, z) in the femur plane; returns (q2, q3, reachable)."""
    with np.errstate(invalid="ignore", over="ignore"):  # non-finite targets end up NaN
        rho = np.hypot(r, z)
        f_out = L2 + L3 - rho  # >= 0: not beyond full extension
        f_in = rho - abs(L2 - L3)  # >= 0: not inside the inner hole
        ok = (f_out >= -tol) & (f_in >= -tol)
        f_out = np.maximum(f_out, 0.0)
        f_in = np.maximum(f_in, 0.0)
        # a² + b² − c², factored (see module docstring), and its square root.
        disc = np.sqrt(f_out * (rho + L2 + L3) * f_in * (rho + abs(L2 - L3)))
        a = 2.0 * L2 * r
        b = 2.0 * L2 * z
        c = r * r + z * z + L2 * L2 - L3 * L3
        q2 = np.arctan2(c, eps * disc) - np.arctan2(a, b)  # eq (9)
        q2 = np.mod(q2 + np.pi, 2.0 * np.pi) - np.pi
        cos3 = (r * r + z * z - L2 * L2 - L3 * L3) / (2.0 * L2 * L3)
        sin3 = disc / (2.0 * L2 * L3)
        q3 = np.arctan2(eps * sin3, cos3)  # eq (10) with its sign made explicit
    return q2, q3, ok


def leg3_ik(
    p: ArrayLike,
    L: ArrayLike,
    branch: ArrayLike = KNEE_UP,
    q_min: ArrayLike | None = None,
    q_max: ArrayLike | None = None,
    tol: float = 1e-12,
) -> tuple[FloatArray, BoolArray]:
    """Joint angles putting the foot of the 3-DOF leg at ``p``, seed 002 eqs (8)–(10).

    Args:
        p: foot targets (..., 3) in m, in the leg base (hip) frame.
        L: link lengths (L1, L2, L3) in m.
        branch: sign of q3, +1 or −1 (:data:`KNEE_UP` = −1 default, :data:`KNEE_DOWN` = +1);
            a scalar or an array broadcastable to the batch shape ``p.shape[:-1]``.
        q_min, q_max: optional joint limits (3,) rad; a solution outside them counts as
            unreachable.
        tol: slack (m) on the reach annulus before a target is declared unreachable.

    Returns:
        ``(q, reachable)``: q (..., 3) rad, NaN where not reachable; reachable (...,) bool.
        Targets are never clipped onto the workspace.
    """
    p = _as_points(p, (3,))
    L1, L2, L3 = _as_lengths(L, 3)
    batch = p.shape[:-1]
    eps = _as_branch(branch, batch)
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    h = np.hypot(x, y)
    q1 = np.arctan2(y, x)  # eq (8)
    q2, q3, ok = _planar(h - L1, z, L2, L3, eps, tol)
    q = np.stack((q1, q2, q3), -1)
    ok &= _limits_mask(q, q_min, q_max, 3) & np.all(np.isfinite(q), axis=-1)
    if not np.all(ok):
        # Foot behind the yaw axis: q1 + π, radial coordinate −h.
        q1f = np.mod(q1, 2.0 * np.pi) - np.pi
        q2f, q3f, okf = _planar(-h - L1, z, L2, L3, eps, tol)
        qf = np.stack((q1f, q2f, q3f), -1)
        okf &= _limits_mask(qf, q_min, q_max, 3) & np.all(np.isfinite(qf), axis=-1)
        use_f = ~ok & okf
        q = np.where(use_f[..., None], qf, q)
        ok = ok | okf
    q = np.where(ok[..., None], q, np.nan)
    return q, ok
