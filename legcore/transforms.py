"""Rotation and pose helpers: rotation vectors of rotation matrices (``log3``) and the
world-aligned error between two poses (``pose_error``), as used by the IK solvers."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["log3", "pose_error"]

FloatArray = NDArray[np.float64]


def log3(Rm: ArrayLike) -> FloatArray:
    """Rotation vector (..., 3) (rad) of rotation matrices (..., 3, 3): ``exp([ω]×) = R``.

    Robust at 0 and near π (the axis then comes from the symmetric part ``(R + I)/2``).
    """
    Rm = np.asarray(Rm, dtype=float)
    tr = Rm[..., 0, 0] + Rm[..., 1, 1] + Rm[..., 2, 2]
    vee = np.stack(
        [
            Rm[..., 2, 1] - Rm[..., 1, 2],
            Rm[..., 0, 2] - Rm[..., 2, 0],
            Rm[..., 1, 0] - Rm[..., 0, 1],
        ],
        axis=-1,
    )  # = 2 sin θ · axis
    sin_t = 0.5 * np.linalg.norm(vee, axis=-1)
    cos_t = 0.5 * (tr - 1.0)
    theta = np.arctan2(sin_t, cos_t)  # accurate at 0 and at π, unlike arccos
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = np.where(theta < 1e-8, 0.5 + theta**2 / 12.0, 0.5 * theta / sin_t)
    out = factor[..., None] * vee
    near_pi = theta > math.pi - 1e-3
    if np.any(near_pi):
        # axis from the symmetric part: (R + Rᵀ)/2 = cos θ I + (1 − cos θ) a aᵀ
        Rn = Rm[near_pi]
        c = cos_t[near_pi]
        S = (0.5 * (Rn + np.swapaxes(Rn, -1, -2)) - c[:, None, None] * np.eye(3)) / (1.0 - c)[
            :, None, None
        ]
        diag = np.stack([S[:, 0, 0], S[:, 1, 1], S[:, 2, 2]], axis=-1)
        k = np.argmax(diag, axis=-1)
        idx = np.arange(Rn.shape[0])
        a = S[idx, k, :] / np.sqrt(np.clip(diag[idx, k], 1e-300, None))[:, None]
        a /= np.linalg.norm(a, axis=-1, keepdims=True)
        sign = np.where(np.sum(a * vee[near_pi], axis=-1) < 0.0, -1.0, 1.0)
        out[near_pi] = (sign * theta[near_pi])[:, None] * a
    return out


def pose_error(T: ArrayLike, T_target: ArrayLike) -> FloatArray:
    """World-aligned error (..., 6) that takes pose ``T`` to ``T_target``: ``[Δp; Δω]``.

    ``Δp = p_target − p`` (m); ``Δω = log3(R_target Rᵀ)`` (rad), a world-frame rotation vector —
    so that for a small joint step ``J Δq ≈ error`` with :func:`jacobian`'s convention.
    """
    T = np.asarray(T, dtype=float)
    T_target = np.asarray(T_target, dtype=float)
    dp = T_target[..., :3, 3] - T[..., :3, 3]
    Rerr = T_target[..., :3, :3] @ np.swapaxes(T[..., :3, :3], -1, -2)
    return np.concatenate([dp, log3(Rerr)], axis=-1)
