"""Compiled body-pose IK of a closed-form tripod: the exact pose workspace in one numba pass.

:func:`closed_form_pose_ik` is what :func:`~legcore.studies.hexapod_workspace.geometry.
body_pose_ik` computes for seed 002's legs (the :mod:`legcore.ik.leg3` closed form, eqs 8–10)
— each pose's three stance feet moved into the body frame and then into each leg's base frame
(``Tripod.to_leg_frames``), the leg IK on the knee branch with the behind-the-yaw-axis family
as fallback, the joint limits — as one loop over the poses instead of ~40 numpy passes over
(poses × legs) temporaries. Every arithmetic step is written in the order of the numpy
formulation it replaces (:func:`~legcore.studies.hexapod_workspace.geometry.
body_pose_ik_reference`); the two differ only where numpy's SIMD ``arctan2`` and libm's (which
the kernel calls) round differently, by ~1e-15 rad (``tests/legcore/studies/test_pose_kernel.py``
checks 1e-12 rad and identical reachability). The yaws' cosines and sines are computed by numpy
before the kernel, as in the reference. Seed 002's workspace grid (13 × 81 × 81 poses): ~6 ms
instead of ~170 ms on the 2-core development machine.

``all_legs=False`` (the pose workspace, which keeps only the poses that all three legs reach)
stops at the first leg that cannot reach and marks the whole pose unreachable (NaN / False for
every leg: what the workspace's mask makes of it anyway), trying first the leg that failed at
the previous pose. Units: m, rad.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = ["ClosedFormTripod", "closed_form_pose_ik", "closed_form_reach", "pose_ik_kernel"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
#: (hips (3, 4, 4), L (3,) m, q_min (3, 3) rad, q_max (3, 3) rad, fixed feet (3, 3) m, knee
#: branch ±1, try the other branch): the arguments of a tripod before its poses.
ClosedFormTripod = tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, float, bool]

#: Slack (m) on the reach annulus and (rad) on the joint limits: ``leg3_ik``'s defaults.
_TOL = 1e-12


@numba.njit(cache=True, nogil=True, inline="always")
def _annulus(rho: float, L2: float, L3: float) -> bool:  # pragma: no cover - compiled
    """The femur-plane target at distance ``rho`` (m) from the femur joint is within reach
    (``leg3._planar``'s ``ok``, slack 1e-12 m)."""
    return L2 + L3 - rho >= -_TOL and rho - abs(L2 - L3) >= -_TOL


@numba.njit(cache=True, nogil=True, inline="always")
def _planar(
    r: float, z: float, rho: float, L2: float, L3: float, eps: float
) -> tuple[float, float]:  # pragma: no cover - compiled
    """``legcore.ik.leg3._planar``'s (q2, q3) for a target (r, z) inside the reach annulus,
    ``rho = hypot(r, z)``; the same operations in the same order."""
    f_out = L2 + L3 - rho
    f_in = rho - abs(L2 - L3)
    if f_out < 0.0:  # np.maximum(f, 0.0)
        f_out = 0.0
    if f_in < 0.0:
        f_in = 0.0
    disc = math.sqrt(f_out * (rho + L2 + L3) * f_in * (rho + abs(L2 - L3)))
    a = 2.0 * L2 * r
    b = 2.0 * L2 * z
    c = r * r + z * z + L2 * L2 - L3 * L3
    q2 = math.atan2(c, eps * disc) - math.atan2(a, b)
    q2 = (q2 + np.pi) % (2.0 * np.pi) - np.pi
    cos3 = (r * r + z * z - L2 * L2 - L3 * L3) / (2.0 * L2 * L3)
    sin3 = disc / (2.0 * L2 * L3)
    return q2, math.atan2(eps * sin3, cos3)


@numba.njit(cache=True, nogil=True, inline="always")
def _within(v: float, lo: float, hi: float) -> bool:  # pragma: no cover - compiled
    """``leg3._limits_mask`` for one joint, and finite (NaN fails both comparisons)."""
    return v - lo >= -_TOL and -(v - hi) >= -_TOL and math.isfinite(v)


@numba.njit(cache=True, nogil=True)
def _leg3(
    x: float, y: float, z: float, L: FloatArray, eps: float, lo: FloatArray, hi: FloatArray,
    k: int,
) -> tuple[bool, float, float, float]:  # pragma: no cover - compiled
    """``legcore.ik.leg3.leg3_ik`` for one foot (x, y, z) in the frame of leg ``k`` (limits
    ``lo[k]``, ``hi[k]``) on branch ``eps``: (reachable, q1, q2, q3), NaN if unreachable.

    The two families (foot in front of the yaw axis, radial h; behind it, q1 + π and radial
    −h) are rejected by the reach annulus, then by the coxa limits, before the angles that
    would not be used are computed."""
    h = math.hypot(x, y)
    r1 = h - L[0]
    r2 = -h - L[0]
    rho1 = math.hypot(r1, z)
    rho2 = math.hypot(r2, z)
    in1 = _annulus(rho1, L[1], L[2])
    in2 = _annulus(rho2, L[1], L[2])
    if in1 or in2:
        q1 = math.atan2(y, x)
        if in1 and _within(q1, lo[k, 0], hi[k, 0]):
            q2, q3 = _planar(r1, z, rho1, L[1], L[2], eps)
            if _within(q2, lo[k, 1], hi[k, 1]) and _within(q3, lo[k, 2], hi[k, 2]):
                return True, q1, q2, q3
        q1 = q1 % (2.0 * np.pi) - np.pi
        if in2 and _within(q1, lo[k, 0], hi[k, 0]):
            q2, q3 = _planar(r2, z, rho2, L[1], L[2], eps)
            if _within(q2, lo[k, 1], hi[k, 1]) and _within(q3, lo[k, 2], hi[k, 2]):
                return True, q1, q2, q3
    return False, np.nan, np.nan, np.nan


@numba.njit(cache=True, nogil=True)
def pose_ik_kernel(
    x: FloatArray, y: FloatArray, cos_yaw: FloatArray, sin_yaw: FloatArray, feet: FloatArray,
    hips: FloatArray, L: FloatArray, q_min: FloatArray, q_max: FloatArray, eps: float,
    either: bool, all_legs: bool, q: FloatArray, ok: BoolArray,
) -> None:  # pragma: no cover - compiled
    """Joint angles ``q`` (N, 3, 3) and reachability ``ok`` (N, 3) of the three legs for the
    body poses ``x``, ``y`` (N,) m with yaw cosines/sines (N,), the feet fixed at ``feet``
    (3, 3) in the world (m); ``hips`` (3, 4, 4) leg base frames, ``L`` (3,) link lengths (m),
    ``q_min``/``q_max`` (3, 3) rad; ``eps`` the knee branch (sign of q3), ``either``: try the
    other branch where the first fails. A ``q`` of no rows: the reachability alone.

    ``all_legs=False``: a pose that one leg cannot reach is all NaN / False (the legs are tried
    starting with the one that failed last: neighbouring poses of a grid fail alike)."""
    with_q = q.shape[0] > 0
    first = 0
    for p in range(x.shape[0]):
        c = cos_yaw[p]
        s = sin_yaw[p]
        for j in range(3):
            k = j if all_legs else (first + j) % 3
            dx = feet[k, 0] - x[p]
            dy = feet[k, 1] - y[p]
            d0 = (c * dx + s * dy) - hips[k, 0, 3]   # body frame, then from the hip
            d1 = (-s * dx + c * dy) - hips[k, 1, 3]
            d2 = feet[k, 2] - hips[k, 2, 3]
            lx = hips[k, 0, 0] * d0 + hips[k, 1, 0] * d1 + hips[k, 2, 0] * d2  # R_kᵀ d
            ly = hips[k, 0, 1] * d0 + hips[k, 1, 1] * d1 + hips[k, 2, 1] * d2
            lz = hips[k, 0, 2] * d0 + hips[k, 1, 2] * d1 + hips[k, 2, 2] * d2
            good, q1, q2, q3 = _leg3(lx, ly, lz, L, eps, q_min, q_max, k)
            if not good and either:
                good, q1, q2, q3 = _leg3(lx, ly, lz, L, -eps, q_min, q_max, k)
            if with_q:
                q[p, k, 0] = q1
                q[p, k, 1] = q2
                q[p, k, 2] = q3
            ok[p, k] = good
            if not good and not all_legs:
                if with_q:
                    q[p, :, :] = np.nan
                ok[p, :] = False
                first = k
                break


def _run(
    tripod: ClosedFormTripod, x: FloatArray, y: FloatArray, yaw: FloatArray, all_legs: bool,
    with_q: bool,
) -> tuple[FloatArray, BoolArray]:
    """:func:`pose_ik_kernel` over poses of one shape (flattened): (q (N, 3, 3) or (0, 3, 3),
    ok (N, 3))."""
    hips, L, q_min, q_max, feet, eps, either = tripod
    f64 = np.float64
    c = np.ascontiguousarray(np.cos(yaw), dtype=f64).ravel()
    s = np.ascontiguousarray(np.sin(yaw), dtype=f64).ravel()
    xs = np.ascontiguousarray(x, dtype=f64).ravel()
    ys = np.ascontiguousarray(y, dtype=f64).ravel()
    q = np.empty((xs.shape[0] if with_q else 0, 3, 3))
    ok = np.empty((xs.shape[0], 3), dtype=np.bool_)
    pose_ik_kernel(xs, ys, c, s, np.ascontiguousarray(feet, dtype=f64),
                   np.ascontiguousarray(hips, dtype=f64), np.ascontiguousarray(L, dtype=f64),
                   np.ascontiguousarray(q_min, dtype=f64), np.ascontiguousarray(q_max, dtype=f64),
                   float(eps), bool(either), bool(all_legs), q, ok)
    return q, ok


def closed_form_pose_ik(
    hips: FloatArray, L: FloatArray, q_min: FloatArray, q_max: FloatArray, feet: FloatArray,
    eps: float, either: bool, x: FloatArray, y: FloatArray, yaw: FloatArray,
    all_legs: bool = True,
) -> tuple[FloatArray, BoolArray]:
    """``(q (*S, 3, 3) rad, reachable (*S, 3))`` of body poses ``x``, ``y`` (m), ``yaw`` (rad)
    of one shape ``S`` by :func:`pose_ik_kernel` (the other arguments as there)."""
    shape = np.shape(x)
    q, ok = _run((hips, L, q_min, q_max, feet, eps, either), x, y, yaw, all_legs, True)
    return q.reshape(*shape, 3, 3), ok.reshape(*shape, 3)


def closed_form_reach(
    hips: FloatArray, L: FloatArray, q_min: FloatArray, q_max: FloatArray, feet: FloatArray,
    eps: float, either: bool, x: FloatArray, y: FloatArray, yaw: FloatArray,
) -> BoolArray:
    """``(*S,)`` True where all three legs reach (:func:`closed_form_pose_ik`'s
    ``reachable.all(-1)``, without the joint angles)."""
    shape = np.shape(x)
    _, ok = _run((hips, L, q_min, q_max, feet, eps, either), x, y, yaw, False, False)
    return np.asarray(ok.all(axis=-1), dtype=bool).reshape(shape)
