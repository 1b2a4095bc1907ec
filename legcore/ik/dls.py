"""Damped-least-squares (Levenberg–Marquardt) inverse kinematics of any serial chain, all samples
iterating together on the numba fast path of :mod:`legcore.kinematics`."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.ik.result import IKResult, _as_target, _residual
from legcore.joint_angles import wrap_to_limits
from legcore.kinematics import fk_jacobian
from legcore.robots.model import Robot
from legcore.transforms import pose_error

__all__ = ["ik_dls"]

FloatArray = NDArray[np.float64]


def ik_dls(
    robot: Robot,
    target: ArrayLike,
    q0: ArrayLike,
    *,
    orientation: bool | None = None,
    tol: float = 1e-10,
    max_iter: int = 200,
    damping: float = 1e-2,
    damping_min: float = 1e-9,
    damping_max: float = 1e3,
    rot_weight: float = 1.0,
) -> IKResult:
    """Damped-least-squares (Levenberg–Marquardt) IK on the robot's kinematic model.

    ``target``: poses (..., 4, 4) or tool positions (..., 3) in the world frame (m).
    ``q0``: start configuration(s), broadcastable to (..., n).
    ``orientation``: match the orientation too (rows ``[v; ω]`` of the Jacobian); default True
    for pose targets on robots with n ≥ 6, False otherwise (position only, rows ``v``).

    All samples iterate together; each iteration computes the tool pose and Jacobian of the whole
    active batch with the numba fast path, proposes ``Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e`` per sample
    (``e`` = :func:`pose_error`, orientation rows scaled by ``rot_weight`` m/rad), accepts it if
    the error decreases (λ ← λ/3, down to ``damping_min``) and otherwise rejects it (λ ← 3λ).
    A sample stops when ``|e| < tol`` (converged) or λ exceeds ``damping_max`` / ``max_iter`` is
    reached (not converged: an unreachable target). Joint limits are not enforced: angles are
    shifted by 2π into the limits where possible and ``within_limits`` reports the rest.
    Returns :class:`IKResult` with ``reachable`` = converged, ``q`` NaN where not converged and
    ``error`` the unweighted residual of the matched rows.
    """
    tf, is_pose, batch = _as_target(target)
    N = tf.shape[0]
    n = robot.nq
    if orientation is None:
        orientation = is_pose and n >= 6
    if orientation and not is_pose:
        raise ValueError("orientation: needs pose targets (..., 4, 4)")
    for name, v in (("tol", tol), ("damping", damping), ("rot_weight", rot_weight)):
        if not (math.isfinite(v) and v > 0.0):
            raise ValueError(f"{name}: must be a finite value > 0, got {v!r}")
    if int(max_iter) < 1:
        raise ValueError(f"max_iter: must be >= 1, got {max_iter}")
    q0a = np.asarray(q0, dtype=float)
    if q0a.shape[-1:] != (n,) or not np.all(np.isfinite(q0a)):
        raise ValueError(f"q0: must be finite with last axis nq = {n}, got shape {q0a.shape}")
    try:
        q = np.array(np.broadcast_to(q0a, (*batch, n)).reshape(N, n))
    except ValueError:
        raise ValueError(
            f"q0: shape {q0a.shape} does not broadcast to the targets' batch {(*batch, n)}"
        ) from None
    rows = slice(0, 6) if orientation else slice(0, 3)
    m = 6 if orientation else 3
    wvec = np.ones(m)
    if orientation:
        wvec[3:] = rot_weight

    def err_of(T: FloatArray, tgt: FloatArray) -> FloatArray:
        if is_pose:
            e = pose_error(T, tgt)[:, rows]
        else:
            e = tgt - T[:, :3, 3]
        return e * wvec

    lam = np.full(N, float(damping))
    converged = np.zeros(N, dtype=bool)
    iters = np.zeros(N, dtype=np.int64)
    active = np.ones(N, dtype=bool)
    T, J = fk_jacobian(robot, q)
    e = err_of(T, tf)
    enorm = np.linalg.norm(e, axis=-1)
    eye = np.eye(m)
    for _ in range(int(max_iter)):
        converged |= active & (enorm < tol)
        active &= ~converged & (lam <= damping_max)
        if not np.any(active):
            break
        ia = np.flatnonzero(active)
        Ja = J[ia][:, rows, :] * wvec[:, None]
        A = Ja @ np.swapaxes(Ja, -1, -2) + (lam[ia] ** 2)[:, None, None] * eye
        y = np.linalg.solve(A, e[ia][..., None])
        dq = (np.swapaxes(Ja, -1, -2) @ y)[..., 0]
        q_try = q[ia] + dq
        T_try, J_try = fk_jacobian(robot, q_try)
        e_try = err_of(T_try, tf[ia])
        n_try = np.linalg.norm(e_try, axis=-1)
        better = n_try < enorm[ia]
        acc = ia[better]
        q[acc] = q_try[better]
        J[acc] = J_try[better]
        e[acc] = e_try[better]
        enorm[acc] = n_try[better]
        lam[acc] = np.maximum(lam[acc] / 3.0, damping_min)
        rej = ia[~better]
        lam[rej] *= 3.0
        iters[ia] += 1
    converged |= enorm < tol
    q_out = wrap_to_limits(q, robot.q_min, robot.q_max, None, ~robot.chain.prismatic)
    q_out = np.where(converged[:, None], q_out, np.nan)
    within = converged & robot.within_limits(np.where(converged[:, None], q_out, 0.0))
    if orientation:
        error = _residual(robot, q_out, tf, True)
    else:
        error = _residual(robot, q_out, tf[:, :3, 3] if is_pose else tf, False)
    return IKResult(
        q=q_out.reshape(*batch, n),
        reachable=converged.reshape(batch),
        within_limits=within.reshape(batch),
        branch=np.where(converged, 0, -1).astype(np.int64).reshape(batch),
        error=error.reshape(batch),
        iterations=iters.reshape(batch),
        branch_names=("dls",),
        method="dls",
    )
