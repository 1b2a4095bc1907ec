"""Closed-form inverse kinematics of the PUMA 560 (and any arm with its DH structure): 8 branches.

Standard DH (``θ_i = q_i + offset_i``), twists α1..α5 = (90°, 0, −90°, 90°, −90°), a4 = a5 =
d5 = 0 (spherical wrist); a1, a2, a3, d1, d2 + d3 (shoulder offset, along the parallel axes z1,
z2), d4, the last link's (d6, a6, α6), the spec's ``base`` and ``tool`` are read from the spec.

Derivation (frames as in ``docs/kinematics.md``). ``R_03 = Rz(θ1) Ry(−θ23)`` and the wrist
centre (origin of DH frames 4, 5) is::

    p_w = (c1 X + s1 d3,  s1 X − c1 d3,  d1 + Y)
    X = a1 + a2 c2 + a3 c23 − d4 s23,   Y = a2 s2 + a3 s23 + d4 c23

1. Wrist centre from the target: ``W = base⁻¹ T (C6 · tool)⁻¹`` where ``C6 = Tz(d6) Tx(a6)
   Rx(α6)``; ``W = T_05 Rz(θ6)``, so ``p_w`` is W's origin.
2. Shoulder: ``ρ² = p_wx² + p_wy²``; ``X = s·sqrt(ρ² − d3²)`` with s = +1 ("left",
   Corke's/Paul & Zhang's 'l') or −1 ("right"); ``θ1 = atan2(p_wy, p_wx) − atan2(−d3, X)``.
   Unreachable if ρ < |d3|.
3. Elbow: with ``L3 = hypot(a3, d4)``, ``ψ = atan2(d4, a3)`` the forearm is a link of length L3
   at angle ``θ23 + ψ``; ``x = X − a1``, ``y = p_wz − d1``, ``cos β = (x² + y² − a2² − L3²) /
   (2 a2 L3)`` with ``β = θ3 + ψ``. Elbow "up" (elbow above the shoulder–wrist line) is
   ``β = −s·acos(·)``, "down" ``β = +s·acos(·)``; ``θ3 = β − ψ``,
   ``θ2 = atan2(y, x) − atan2(L3 sin β, a2 + L3 cos β)``. Unreachable if |cos β| > 1.
4. Wrist: ``M = R_03ᵀ R_W = Rz(θ4) Ry(−θ5) Rz(θ6)`` (ZYZ Euler with middle angle −θ5):
   ``θ5 = atan2(±sqrt(M02² + M12²), M22)``, ``θ4 = atan2(−M12/s5, −M02/s5)``,
   ``θ6 = atan2(−M21/s5, M20/s5)``. "noflip" takes sin θ5 ≥ 0, "flip" the other
   (θ4 + π, −θ5, θ6 + π). At the wrist singularity (sin θ5 = 0) only θ4 ± θ6 is defined: θ4 is
   set to 0 (flip: π) and θ6 takes the rest.

Branch order (index = 4·shoulder + 2·elbow + wrist): see :data:`BRANCH_NAMES`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.joint_angles import wrap_branch_solutions
from legcore.robots.spec import DHRobotSpec, RobotSpec

__all__ = [
    "BRANCH_NAMES",
    "Puma560Geometry",
    "Puma560Solutions",
    "puma560_geometry",
    "puma560_ik",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Branch names by index ``4·shoulder + 2·elbow + wrist`` (0 = left/up/noflip).
BRANCH_NAMES: tuple[str, ...] = tuple(
    f"{s}-{e}-{w}" for s in ("left", "right") for e in ("up", "down") for w in ("noflip", "flip")
)

#: |cos β| may exceed 1 by this much from rounding and still count as reachable (boundary).
_REACH_TOL = 1e-12
#: sin θ5 below this is treated as the wrist singularity.
_WRIST_SINGULAR = 1e-12


@dataclass(frozen=True, eq=False)
class Puma560Geometry:
    """DH data of a PUMA-type arm (m, rad). ``d3`` is the total shoulder offset d2 + d3;
    ``post`` (4,4) = ``Tz(d6) Tx(a6) Rx(α6) · tool``, ``base`` (4,4); ``offset`` (6,)."""

    d1: float
    a1: float
    a2: float
    a3: float
    d3: float
    d4: float
    offset: FloatArray
    base: FloatArray
    post: FloatArray


def _dh_const(d: float, a: float, alpha: float) -> FloatArray:
    ca, sa = math.cos(alpha), math.sin(alpha)
    return np.array([[1.0, 0.0, 0.0, a], [0.0, ca, -sa, 0.0], [0.0, sa, ca, d], [0, 0, 0, 1.0]])


def puma560_geometry(spec: RobotSpec | DHRobotSpec) -> Puma560Geometry:
    """Read and check the DH data of a PUMA-type arm from a robot spec (``ValueError`` if not)."""
    if not isinstance(spec, DHRobotSpec) or spec.convention != "standard":
        raise ValueError("spec: the PUMA 560 closed form needs a standard-DH robot spec")
    j = spec.joints
    if len(j) != 6 or any(x.type != "revolute" for x in j):
        raise ValueError("spec: the PUMA 560 closed form needs 6 revolute joints")
    half = math.pi / 2
    for i, al in enumerate((half, 0.0, -half, half, -half)):
        if abs(j[i].alpha - al) > 1e-9:
            raise ValueError(
                f"spec.joints.{i}.alpha: the PUMA 560 closed form needs α1..α5 = "
                f"(90°, 0, −90°, 90°, −90°), got {math.degrees(j[i].alpha):.6g}°"
            )
    for i, attr in ((3, "a"), (4, "a"), (4, "d")):
        if abs(getattr(j[i], attr)) > 1e-12:
            raise ValueError(
                f"spec.joints.{i}.{attr}: must be 0 for a spherical wrist (a4 = a5 = d5 = 0)"
            )
    if j[1].a <= 0.0 or math.hypot(j[2].a, j[3].d) <= 0.0:
        raise ValueError("spec: the PUMA 560 closed form needs a2 > 0 and a forearm a3, d4 ≠ 0")
    tool = np.asarray(spec.tool, dtype=float) if spec.tool is not None else np.eye(4)
    base = np.asarray(spec.base, dtype=float) if spec.base is not None else np.eye(4)
    return Puma560Geometry(
        d1=j[0].d,
        a1=j[0].a,
        a2=j[1].a,
        a3=j[2].a,
        d3=j[1].d + j[2].d,
        d4=j[3].d,
        offset=np.array([x.offset for x in j]),
        base=base,
        post=_dh_const(j[5].d, j[5].a, j[5].alpha) @ tool,
    )


def _inv(T: FloatArray) -> FloatArray:
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return out


@dataclass(frozen=True, eq=False)
class Puma560Solutions:
    """All 8 branches for targets of batch shape S: ``q`` (*S, 8, 6) rad (NaN where not
    reachable), ``reachable`` (*S, 8), ``within_limits`` (*S, 8) (reachable and inside the joint
    limits, when limits were given; else equal to ``reachable``)."""

    q: FloatArray
    reachable: BoolArray
    within_limits: BoolArray


def puma560_ik(
    T: ArrayLike,
    geometry: Puma560Geometry,
    q_min: ArrayLike | None = None,
    q_max: ArrayLike | None = None,
    q_ref: ArrayLike | None = None,
) -> Puma560Solutions:
    """All 8 closed-form solutions for tool poses ``T`` (..., 4, 4) in the world frame (m).

    Angles come out as principal values (−π, π] of ``q = θ − offset``; with ``q_min``/``q_max``
    (6,) they are shifted by 2π into the limits where possible (nearest ``q_ref``, broadcastable
    to (..., 8, 6), if given) and ``within_limits`` says which branches are inside.
    """
    T = np.asarray(T, dtype=float)
    if T.ndim < 2 or T.shape[-2:] != (4, 4):
        raise ValueError(f"T: expected poses (..., 4, 4), got shape {T.shape}")
    batch = T.shape[:-2]
    Tf = T.reshape(-1, 4, 4)
    g = geometry
    W = np.linalg.inv(g.base) @ Tf @ _inv(g.post)  # (N,4,4) = T_05 Rz(θ6)
    N = W.shape[0]
    pw = W[:, :3, 3]
    RW = W[:, :3, :3]

    out = np.full((N, 8, 6), np.nan)
    reach = np.zeros((N, 8), dtype=bool)
    rho2 = pw[:, 0] ** 2 + pw[:, 1] ** 2
    h2 = rho2 - g.d3**2
    shoulder_ok = h2 >= -_REACH_TOL * max(1.0, g.d3**2)
    Xabs = np.sqrt(np.clip(h2, 0.0, None))
    phi = np.arctan2(pw[:, 1], pw[:, 0])
    L3 = math.hypot(g.a3, g.d4)
    psi = math.atan2(g.d4, g.a3)
    y = pw[:, 2] - g.d1
    for si, s in enumerate((1.0, -1.0)):
        X = s * Xabs
        th1 = phi - np.arctan2(-g.d3 * np.ones(N), X)
        x = X - g.a1
        cb = (x**2 + y**2 - g.a2**2 - L3**2) / (2.0 * g.a2 * L3)
        elbow_ok = shoulder_ok & (np.abs(cb) <= 1.0 + _REACH_TOL)
        acb = np.arccos(np.clip(cb, -1.0, 1.0))
        for ei, e in enumerate((1.0, -1.0)):  # up, down
            beta = -s * e * acb
            th3 = beta - psi
            th2 = np.arctan2(y, x) - np.arctan2(L3 * np.sin(beta), g.a2 + L3 * np.cos(beta))
            th23 = th2 + th3
            c1, s1 = np.cos(th1), np.sin(th1)
            c23, s23 = np.cos(th23), np.sin(th23)
            # R_03 = Rz(θ1) Ry(−θ23); M = R_03ᵀ R_W = Ry(θ23) Rz(−θ1) R_W
            R03 = np.empty((N, 3, 3))
            R03[:, 0, 0] = c1 * c23
            R03[:, 0, 1] = -s1
            R03[:, 0, 2] = -c1 * s23
            R03[:, 1, 0] = s1 * c23
            R03[:, 1, 1] = c1
            R03[:, 1, 2] = -s1 * s23
            R03[:, 2, 0] = s23
            R03[:, 2, 1] = 0.0
            R03[:, 2, 2] = c23
            M = np.swapaxes(R03, -1, -2) @ RW
            s5abs = np.hypot(M[:, 0, 2], M[:, 1, 2])
            singular = s5abs < _WRIST_SINGULAR
            th5 = np.arctan2(s5abs, M[:, 2, 2])
            th4 = np.arctan2(-M[:, 1, 2], -M[:, 0, 2])
            th6 = np.arctan2(-M[:, 2, 1], M[:, 2, 0])
            # singular wrist: M = Rz(θ4 + θ6) at θ5 = 0, Rz(θ4 − θ6) Ry(π) at θ5 = π; θ4 = 0
            sum46 = np.arctan2(-M[:, 0, 1], M[:, 1, 1])
            th4 = np.where(singular, 0.0, th4)
            th6 = np.where(singular, np.where(M[:, 2, 2] > 0.0, sum46, -sum46), th6)
            for wi in range(2):
                b = 4 * si + 2 * ei + wi
                if wi == 0:
                    t4, t5, t6 = th4, th5, th6
                else:
                    t4, t5, t6 = th4 + math.pi, -th5, th6 + math.pi
                th = np.stack([th1, th2, th3, t4, t5, t6], axis=-1)
                out[:, b] = th - g.offset
                reach[:, b] = elbow_ok
    out, within = wrap_branch_solutions(out, reach, q_min, q_max, q_ref)
    return Puma560Solutions(
        q=out.reshape(*batch, 8, 6),
        reachable=reach.reshape(*batch, 8),
        within_limits=within.reshape(*batch, 8),
    )
