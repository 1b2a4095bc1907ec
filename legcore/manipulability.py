"""Manipulability of serial chains: Yoshikawa's measure of the tool Jacobian, and seed 001's
closed-form split ``(w, w_A, w_W)`` of a spherical-wrist 6R arm."""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.kinematics import jacobian
from legcore.robots.model import Robot
from legcore.robots.spec import DHRobotSpec

__all__ = ["manipulability", "manipulability_split"]

FloatArray = NDArray[np.float64]

Rows = Literal["all", "translational", "rotational"]


def manipulability(robot: Robot, q: ArrayLike, rows: Rows | None = None) -> FloatArray:
    """Yoshikawa's manipulability (..., ) of the tool Jacobian rows selected by ``rows``.

    ``w = sqrt(det(J_r J_rᵀ))`` with ``J_r`` the selected rows of :func:`jacobian` (m rows × n
    joints). ``rows``: ``"all"`` (6 rows), ``"translational"`` (``v``, 3 rows, unit m³ for a
    revolute 3-row measure) or ``"rotational"`` (``ω``, 3 rows). Default: ``"all"`` for n ≥ 6,
    ``"translational"`` for n < 6 (a 5-DOF arm or a leg cannot span all six twist directions,
    and the tool position is what such robots are asked to place). When n < m (e.g. all six
    rows of the 5-DOF arm, or a planar 2-DOF leg: 3 rows × 2 joints) ``det(J_r J_rᵀ)`` is
    identically 0, so the measure is the product of the n singular values,
    ``sqrt(det(J_rᵀ J_r))`` — the n-dimensional volume of the manipulability ellipsoid (0 only at
    a singularity). For n = m both forms are ``|det J_r|``.
    """
    n = robot.nq
    if rows is None:
        rows = "all" if n >= 6 else "translational"
    if rows == "all":
        sl = slice(0, 6)
    elif rows == "translational":
        sl = slice(0, 3)
    elif rows == "rotational":
        sl = slice(3, 6)
    else:
        raise ValueError(f"rows: must be 'all', 'translational' or 'rotational', got {rows!r}")
    J = jacobian(robot, q)[..., sl, :]
    m = J.shape[-2]
    Jt = np.swapaxes(J, -1, -2)
    G = J @ Jt if m <= n else Jt @ J
    return np.sqrt(np.clip(np.linalg.det(G), 0.0, None))


def _spherical_wrist_params(robot: Robot) -> tuple[float, float, float, float, FloatArray]:
    """(a1, a2, a3, d4, offset) of a PUMA-type 6R arm with a spherical wrist; ValueError else."""
    spec = robot.spec
    if not isinstance(spec, DHRobotSpec) or spec.convention != "standard":
        raise ValueError("robot: manipulability_split needs a standard-DH robot spec")
    j = spec.joints
    if len(j) != 6 or any(x.type != "revolute" for x in j):
        raise ValueError("robot: manipulability_split needs a 6R arm (6 revolute joints)")
    half = math.pi / 2
    alphas = (half, 0.0, -half, half, -half)
    tol = 1e-9
    if any(abs(x.alpha - al) > tol for x, al in zip(j[:5], alphas, strict=False)):
        raise ValueError(
            "robot: manipulability_split needs the PUMA-type DH twists "
            "α1..α5 = (90°, 0, −90°, 90°, −90°) of seed 001"
        )
    if abs(j[3].a) > tol or abs(j[4].a) > tol or abs(j[4].d) > tol:
        raise ValueError("robot: not a spherical wrist (needs a4 = a5 = d5 = 0)")
    offset = np.array([x.offset for x in j])
    return j[0].a, j[1].a, j[2].a, j[3].d, offset


def manipulability_split(robot: Robot, q: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Seed 001 eqs (6)–(8): ``(w, w_A, w_W)``, each (...,), for a spherical-wrist 6R arm.

    With ``θ_i = q_i + offset_i`` and the standard-DH lengths of the PUMA-type arm::

        w_A = a2 (d4 cos θ3 + a3 sin θ3) (a1 + a3 cos(θ2+θ3) − d4 sin(θ2+θ3) + a2 cos θ2)   (7)
        w_W = sin θ5                                                                      (8)
        w   = w_A · w_W                                                                   (6)

    The paper writes them signed; here all three are returned as absolute values (a measure is
    ≥ 0): ``w_A = |eq 7|`` (m³) is |det| of the 3×3 Jacobian of the wrist-centre position w.r.t.
    θ1..θ3 (Yoshikawa's translational manipulability of the arm), ``w_W = |sin θ5|`` that of the
    wrist's three unit axes, and ``w = w_A·w_W`` equals Yoshikawa's ``sqrt(det(J Jᵀ)) = |det J|``
    of the full 6×6 Jacobian at any tool point (moving the reference point or rotating the axes
    multiplies J by a matrix of determinant ±1). Raises ``ValueError`` unless the robot is a
    standard-DH 6R arm with α1..α5 = (90°, 0, −90°, 90°, −90°) and a4 = a5 = d5 = 0.
    """
    a1, a2, a3, d4, offset = _spherical_wrist_params(robot)
    qa = np.asarray(q, dtype=float)
    if qa.ndim == 0 or qa.shape[-1] != 6:
        raise ValueError(f"q: last axis must have length 6, got shape {qa.shape}")
    th = qa + offset
    t2, t3, t5 = th[..., 1], th[..., 2], th[..., 4]
    t23 = t2 + t3
    w_A = np.abs(
        a2
        * (d4 * np.cos(t3) + a3 * np.sin(t3))
        * (a1 + a3 * np.cos(t23) - d4 * np.sin(t23) + a2 * np.cos(t2))
    )
    w_W = np.abs(np.sin(t5))
    return w_A * w_W, w_A, w_W
