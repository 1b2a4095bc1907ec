"""Closed-form IK of seed 004's 5-DOF articulated arm with the tool pointing straight down.

Standard DH (``θ_i = q_i + offset_i``), α = (90°, 0, 0, 90°, 0), a4 = a5 = 0, d2 = d3 = d4 = 0
(seed 004 fig. 18: d1 = 0.50, a2 = a3 = 0.40, d5 = 0.20 m); a1 is allowed. The spec's ``tool``
may add a roll γ about z5 and a length along z5 (``tool = Rz(γ) Tz(d_t)``); ``base`` may be any
translation plus a rotation about the vertical. "Down" is −z of the base frame.

Frames (see ``docs/kinematics.md``): with ``e_r = (c1, s1, 0)``, ``e_t = (−s1, c1, 0)`` and ``ẑ``,
the axes of joints 2–4 are all ``z1 = −e_t``, so the arm moves in the vertical plane (e_r, ẑ);
``θ2`` tilts link 2 from ``e_r`` up towards ``ẑ``. With ``φ = θ2 + θ3 + θ4``::

    z5 = z4 = sin φ e_r − cos φ ẑ,    x4 = cos φ e_r + sin φ ẑ,    y4 = −e_t

so the tool points down (z5 = −ẑ) exactly when ``φ = 0`` (mod 2π) — at the paper's home
(0, 90°, −90°, 90°, 0) φ = 90° and the tool points horizontally outwards. Then
``x_tool = cos(θ5 + γ) e_r − sin(θ5 + γ) e_t`` has heading ``θ1 − θ5 − γ``.

Solution for a tool point p (base frame):

1. wrist centre ``w = p + (d5 + d_t) ẑ``;
2. base yaw ``θ1 = atan2(w_y, w_x)`` ("front") or ``+ π`` ("back", reaching over the top),
   radial coordinate of the wrist in the arm plane ``x = ±hypot(w_x, w_y) − a1``, height
   ``y = w_z − d1`` (on the z axis, ``θ1`` = 0 is used);
3. planar 2R: ``cos θ3 = (x² + y² − a2² − a3²) / (2 a2 a3)``; elbow "up" (above the
   shoulder–wrist line) is ``θ3 = −σ acos(·)``, "down" ``+σ acos(·)`` with σ = +1 front, −1 back;
   ``θ2 = atan2(y, x) − atan2(a3 sin θ3, a2 + a3 cos θ3)``; unreachable if |cos θ3| > 1;
4. ``θ4 = −θ2 − θ3`` (tool vertical);
5. ``θ5 = θ1 − γ − yaw`` for a requested tool heading ``yaw``; without one, ``q5 = 0``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.joint_angles import wrap_branch_solutions
from legcore.robots.spec import DHRobotSpec, RobotSpec

__all__ = ["BRANCH_NAMES", "Arm5Geometry", "Arm5Solutions", "arm5_geometry", "arm5_ik_down"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Branch names by index ``2·reach + elbow``.
BRANCH_NAMES: tuple[str, ...] = ("front-up", "front-down", "back-up", "back-down")

_REACH_TOL = 1e-12


@dataclass(frozen=True, eq=False)
class Arm5Geometry:
    """DH data of the 5-DOF arm (m, rad): ``d5`` includes the tool length along z5, ``gamma``
    is the tool roll about z5, ``base_yaw``/``base_p`` the base placement, ``offset`` (5,)."""

    d1: float
    a1: float
    a2: float
    a3: float
    d5: float
    gamma: float
    offset: FloatArray
    base_yaw: float
    base_p: FloatArray


def arm5_geometry(spec: RobotSpec | DHRobotSpec) -> Arm5Geometry:
    """Read and check the DH data of a seed-004-type 5-DOF arm (``ValueError`` if not)."""
    if not isinstance(spec, DHRobotSpec) or spec.convention != "standard":
        raise ValueError("spec: the 5-DOF arm closed form needs a standard-DH robot spec")
    j = spec.joints
    if len(j) != 5 or any(x.type != "revolute" for x in j):
        raise ValueError("spec: the 5-DOF arm closed form needs 5 revolute joints")
    half = math.pi / 2
    for i, al in enumerate((half, 0.0, 0.0, half, 0.0)):
        if abs(j[i].alpha - al) > 1e-9:
            raise ValueError(
                f"spec.joints.{i}.alpha: the 5-DOF arm closed form needs α = "
                f"(90°, 0, 0, 90°, 0), got {math.degrees(j[i].alpha):.6g}°"
            )
    for i, attr in ((1, "d"), (2, "d"), (3, "d"), (3, "a"), (4, "a")):
        if abs(getattr(j[i], attr)) > 1e-12:
            raise ValueError(f"spec.joints.{i}.{attr}: must be 0 for the 5-DOF arm closed form")
    if j[1].a <= 0.0 or j[2].a <= 0.0:
        raise ValueError("spec: the 5-DOF arm closed form needs a2 > 0 and a3 > 0")
    tool = np.asarray(spec.tool, dtype=float) if spec.tool is not None else np.eye(4)
    if abs(tool[2, 2] - 1.0) > 1e-12 or np.abs(tool[:2, 3]).max() > 1e-12:
        raise ValueError("spec.tool: must be Rz(γ)·Tz(d) (a roll and a length along z5)")
    base = np.asarray(spec.base, dtype=float) if spec.base is not None else np.eye(4)
    if abs(base[2, 2] - 1.0) > 1e-12:
        raise ValueError("spec.base: must be a translation plus a rotation about the vertical")
    return Arm5Geometry(
        d1=j[0].d,
        a1=j[0].a,
        a2=j[1].a,
        a3=j[2].a,
        d5=j[4].d + float(tool[2, 3]),
        gamma=math.atan2(tool[1, 0], tool[0, 0]),
        offset=np.array([x.offset for x in j]),
        base_yaw=math.atan2(base[1, 0], base[0, 0]),
        base_p=base[:3, 3].copy(),
    )


@dataclass(frozen=True, eq=False)
class Arm5Solutions:
    """All 4 branches for targets of batch shape S: ``q`` (*S, 4, 5) rad (NaN where not
    reachable), ``reachable`` (*S, 4), ``within_limits`` (*S, 4)."""

    q: FloatArray
    reachable: BoolArray
    within_limits: BoolArray


def arm5_ik_down(
    p: ArrayLike,
    geometry: Arm5Geometry,
    yaw: ArrayLike | None = None,
    q_min: ArrayLike | None = None,
    q_max: ArrayLike | None = None,
    q_ref: ArrayLike | None = None,
) -> Arm5Solutions:
    """Joint solutions placing the tool point at ``p`` (..., 3) (world, m) pointing down.

    ``yaw`` (broadcastable to ...): heading (rad) of the tool x axis in the world xy plane; None
    keeps joint 5 at q5 = 0. With ``q_min``/``q_max`` (5,) the angles are shifted by 2π into the
    limits where possible (nearest ``q_ref`` (…, 4, 5)-broadcastable, if given).
    """
    p = np.asarray(p, dtype=float)
    if p.ndim < 1 or p.shape[-1] != 3:
        raise ValueError(f"p: expected positions (..., 3), got shape {p.shape}")
    batch = p.shape[:-1]
    g = geometry
    cb, sb = math.cos(g.base_yaw), math.sin(g.base_yaw)
    d = p.reshape(-1, 3) - g.base_p
    N = d.shape[0]
    # into the base frame (rotation about z by −base_yaw)
    wx = cb * d[:, 0] + sb * d[:, 1]
    wy = -sb * d[:, 0] + cb * d[:, 1]
    wz = d[:, 2] + g.d5
    if yaw is not None:
        yaw_b = np.broadcast_to(np.asarray(yaw, dtype=float), batch).reshape(-1) - g.base_yaw
    rxy = np.hypot(wx, wy)
    phi = np.where(rxy > 0.0, np.arctan2(wy, wx), 0.0)
    y = wz - g.d1
    out = np.full((N, 4, 5), np.nan)
    reach = np.zeros((N, 4), dtype=bool)
    for ri, sgn in enumerate((1.0, -1.0)):  # front, back
        th1 = phi if sgn > 0 else phi + math.pi
        x = sgn * rxy - g.a1
        c3 = (x**2 + y**2 - g.a2**2 - g.a3**2) / (2.0 * g.a2 * g.a3)
        ok = np.abs(c3) <= 1.0 + _REACH_TOL
        a3c = np.arccos(np.clip(c3, -1.0, 1.0))
        for ei, e in enumerate((1.0, -1.0)):  # up, down
            th3 = -sgn * e * a3c
            th2 = np.arctan2(y, x) - np.arctan2(g.a3 * np.sin(th3), g.a2 + g.a3 * np.cos(th3))
            th4 = -th2 - th3
            if yaw is None:
                th5 = np.full(N, g.offset[4])
            else:
                th5 = th1 - g.gamma - yaw_b
            th = np.stack([th1, th2, th3, th4, th5], axis=-1)
            b = 2 * ri + ei
            out[:, b] = th - g.offset
            reach[:, b] = ok
    out, within = wrap_branch_solutions(out, reach, q_min, q_max, q_ref)
    return Arm5Solutions(
        q=out.reshape(*batch, 4, 5),
        reachable=reach.reshape(*batch, 4),
        within_limits=within.reshape(*batch, 4),
    )
