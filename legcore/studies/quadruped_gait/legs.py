"""The legs of any quadruped for the ``quadruped_gait`` study: which corner each leg is, where
its foot goes, and its joint motion along the gait cycle (IK + joint rates), batched.

Frames and units (SI): body frame x forward, y left, z up; each leg's chain has its base at the
hip (``Leg.hip``, 4×4 in the body frame). The foot cycle of
:func:`~legcore.studies.quadruped_gait.cycle.foot_cycle` — ``(x, y)`` = (depth below the hip,
forward of it) — is placed in the body frame at ``hip + (y, ±lateral, −x)`` and mapped into the
leg frame.

Two ways to the joint motion, equal where both apply (checked in the tests):

- **closed form** (fast path) for a planar 2-joint DH leg with ``ik: leg2`` (seed 003's):
  :func:`legcore.ik.leg2.leg2_ik` on the anatomical branch and the analytic rates
  :func:`~legcore.studies.quadruped_gait.cycle.leg2_rates`;
- **numerical** for any other leg of 2–3 joints (and for every leg with ``ik: numeric``):
  :func:`legcore.ik.solve` (``"position"``) warm started along the cycle from the reference
  posture ``q_ref``, then ``q̇ = J⁺ ṗ`` and ``q̈ = J⁺ (p̈ − J̇ q̇)`` with the translational
  Jacobian ``J`` of :func:`legcore.kinematics.jacobian` (``J̇ q̇`` by a central difference of
  ``J`` along ``q̇``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from legcore.ik import solve
from legcore.ik.leg2 import leg2_fk, leg2_ik
from legcore.kinematics import fk, jacobian
from legcore.robots.legged import Leg, LeggedRobot
from legcore.robots.spec import DHRobotSpec
from legcore.studies.quadruped_gait.cycle import leg2_rates

__all__ = ["GaitLeg", "IK_RESTARTS", "ROLES", "gait_legs"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: The four corners, in the names of :data:`legcore.gaits.QUADRUPED_WALK`.
ROLES = ("FL", "FR", "RL", "RR")
_SINGULAR = 1e-6  # |sin q4| (closed form) or σ_min(J_v) in m (numerical) of a straight leg
_FD = 1e-6  # step (rad) of the central difference J̇ q̇
#: Restart seeds of the numerical IK per sample it cannot track (the solver's default is 32).
#: Bounds the cost of an unreachable sample — a step the search box allows but the leg cannot
#: make — to about 1 + 14 substeps + 4 restarts Newton solves instead of 47 (≈ 7× less on Go1;
#: reachable samples are tracked by continuation and never restart).
IK_RESTARTS = 4


@dataclass(frozen=True, eq=False)
class GaitLeg:
    """One leg as the gait uses it.

    ``role``: its corner (FL, FR, RL, RR, from the hip position); ``closed_form``: the leg2 fast
    path applies; ``L``/``branch``: link lengths and knee sign of a closed-form leg; ``q_ref``
    (n,) reference posture (rad); ``lateral``: signed body-y offset of the foot from the hip (m);
    ``com_link`` (n, 3) link COMs in the link frames of :func:`legcore.kinematics.frames`.
    """

    leg: Leg
    role: str
    closed_form: bool
    L: tuple[float, ...]
    branch: float
    q_ref: FloatArray
    lateral: float
    com_link: FloatArray

    @property
    def name(self) -> str:
        return self.leg.name

    @property
    def n(self) -> int:
        return self.leg.robot.nq

    def to_leg(self, v_body: FloatArray) -> FloatArray:
        """Vectors (..., 3) from body axes to leg-frame axes."""
        return np.asarray(v_body, dtype=float) @ self.leg.hip[:3, :3]

    def cycle_to_body(self, p: FloatArray, lateral: bool = True) -> FloatArray:
        """Cycle coordinates (..., 2) = (down, forward) → body-axes offsets (..., 3) from the hip
        (``lateral``: add the foot's lateral offset; off for velocities/accelerations)."""
        y = np.full(p.shape[:-1], self.lateral if lateral else 0.0)
        return np.stack((p[..., 1], y, -p[..., 0]), -1)

    def motion(
        self,
        p: FloatArray,
        dp: FloatArray,
        ddp: FloatArray,
        T: FloatArray,
        numeric: bool,
    ) -> tuple[FloatArray, FloatArray, FloatArray, BoolArray]:
        """Joint motion of the foot cycle samples ``p``, ``dp``, ``ddp`` (B, M, 2) (per unit
        phase; cycle times ``T`` (B, 1) s; the M axis is a path through the cycle).

        Returns ``q``, ``qd``, ``qdd`` (B, M, n) rad, rad/s, rad/s² and ``ok`` (B, M): reached
        inside the joint limits, not singular, finite rates (elsewhere q = home; rates 0 where
        they are not finite)."""
        rb = self.leg.robot
        Tt = T[..., None]
        if self.closed_form and not numeric:
            p_leg = self.to_leg(self.cycle_to_body(p))
            q, ok = leg2_ik(p_leg[..., :2], self.L, self.branch, rb.q_min, rb.q_max)
            ok &= np.abs(p_leg[..., 2]) < 1e-9
            ok &= np.abs(np.sin(np.where(ok, q[..., 1], 0.0))) > _SINGULAR
            q = np.where(ok[..., None], q, rb.home)
            qd, qdd, _ = leg2_rates(q, dp / Tt, ddp / Tt**2, self.L)
        else:
            target = self.to_leg(self.cycle_to_body(p))
            sol = solve(rb, target, "position", q0=self.q_ref, rest=self.q_ref, path=True,
                        method="numeric" if numeric else "auto", restarts=IK_RESTARTS)
            ok = np.asarray(sol.reachable, dtype=bool)
            q = np.where(ok[..., None], np.nan_to_num(sol.q), rb.home)
            v = self.to_leg(self.cycle_to_body(dp, False)) / Tt
            a = self.to_leg(self.cycle_to_body(ddp, False)) / Tt**2
            qd, qdd, sigma = _rates(rb, q, v, a)
            ok &= sigma > _SINGULAR
        bad = ~np.all(np.isfinite(qd) & np.isfinite(qdd), axis=-1)
        qd = np.where(bad[..., None], 0.0, qd)
        qdd = np.where(bad[..., None], 0.0, qdd)
        return q, qd, qdd, ok & ~bad

    def posture(self, p: FloatArray, q0: FloatArray, numeric: bool) -> tuple[FloatArray, BoolArray]:
        """Joint angles (..., n) of isolated cycle samples ``p`` (..., 2), each solved from the
        nearby posture ``q0`` (..., n) (the margin's event samples)."""
        rb = self.leg.robot
        p_leg = self.to_leg(self.cycle_to_body(p))
        if self.closed_form and not numeric:
            q, ok = leg2_ik(p_leg[..., :2], self.L, self.branch, rb.q_min, rb.q_max)
            ok &= np.abs(np.sin(np.where(ok, q[..., 1], 0.0))) > _SINGULAR
        else:
            sol = solve(rb, p_leg, "position", q0=q0, rest=self.q_ref,
                        method="numeric" if numeric else "auto", restarts=IK_RESTARTS)
            q, ok = sol.q, np.asarray(sol.reachable, dtype=bool)
        return np.where(ok[..., None], np.nan_to_num(q), rb.home), ok


def _rates(
    rb: object, q: FloatArray, v: FloatArray, a: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``q̇ = J⁺ v``, ``q̈ = J⁺ (a − J̇ q̇)`` with the translational Jacobian (..., 3, n), and its
    smallest singular value (m)."""
    J = jacobian(rb, q)[..., :3, :]  # type: ignore[arg-type]
    Jp = np.linalg.pinv(J)
    qd = np.einsum("...ij,...j->...i", Jp, v)
    Jm = jacobian(rb, q - _FD * qd)[..., :3, :]  # type: ignore[arg-type]
    Jpl = jacobian(rb, q + _FD * qd)[..., :3, :]  # type: ignore[arg-type]
    jdqd = np.einsum("...ij,...j->...i", (Jpl - Jm) / (2.0 * _FD), qd)
    qdd = np.einsum("...ij,...j->...i", Jp, a - jdqd)
    sigma = np.asarray(np.linalg.svd(J, compute_uv=False)[..., -1], dtype=np.float64)
    return qd, qdd, sigma


def _role(leg: Leg) -> str:
    x, y = float(leg.hip[0, 3]), float(leg.hip[1, 3])
    return ("F" if x > 0.0 else "R") + ("L" if y > 0.0 else "R")


def _closed_form(leg: Leg) -> tuple[bool, tuple[float, ...]]:
    """Whether the leg2 fast path applies: a 2-joint standard-DH leg with ``ik: leg2`` whose
    model equals the closed form's convention (x down, y forward, a = link lengths)."""
    rb = leg.robot
    if rb.nq != 2 or rb.ik_family != "leg2" or not isinstance(rb.spec, DHRobotSpec):
        return False, ()
    L = tuple(float(j.a) for j in rb.spec.joints)
    q_test = rb.home + np.array([[0.0, 0.0], [0.3, 0.2], [-0.4, 0.5]])
    if not np.allclose(fk(rb, q_test)[:, :3, 3], leg2_fk(q_test, L), atol=1e-9):
        return False, ()
    return True, L


def _branch(meta: dict[str, object], leg: Leg) -> float:
    br = meta.get("branch", {})
    if isinstance(br, dict) and leg.name in br:
        return float(br[leg.name])
    rb = leg.robot  # the joint limits of q4 hold the branch
    if rb.q_min[1] >= 0.0:
        return 1.0
    if rb.q_max[1] <= 0.0:
        return -1.0
    raise ValueError(
        f"robot: leg {leg.name!r} has no branch in meta['branch'] and its knee limits "
        f"[{rb.q_min[1]}, {rb.q_max[1]}] do not decide one"
    )


def _com_in_links(leg: Leg) -> FloatArray:
    """Link COMs (n, 3) in the link frames of :func:`legcore.kinematics.frames` (the chain keeps
    them in the joint frames)."""
    rb = leg.robot
    out = np.zeros((rb.nq, 3))
    for i, fid in enumerate(rb.link_frames):
        M = rb.model.frames[fid].placement  # link frame in joint frame i+1
        out[i] = M.rotation.T @ (rb.chain.com[i] - M.translation)
    return out


def gait_legs(
    robot: object,
    q_ref: dict[str, tuple[float, ...]] | None,
    foot_lateral: float | None,
) -> tuple[GaitLeg, ...]:
    """The four legs of ``robot`` in its own order, each with its corner; ``ValueError`` naming
    ``robot`` (legs that are not one per corner, gravity not down the body's z) or ``q_ref``."""
    if not isinstance(robot, LeggedRobot):
        raise ValueError("robot: quadruped_gait needs a legged robot")
    roles = [_role(leg) for leg in robot.legs]
    if len(robot.legs) != 4 or sorted(roles) != sorted(ROLES):
        where = ", ".join(f"{leg.name} at {r}" for leg, r in zip(robot.legs, roles, strict=True))
        raise ValueError(f"robot: quadruped_gait needs one leg at each corner (front/rear × "
                         f"left/right of the body centre); {robot.name} has {where}")
    names = [leg.name for leg in robot.legs]
    unknown = sorted(set(q_ref or {}) - set(names))
    if unknown:
        raise ValueError(f"q_ref: unknown legs {unknown}; legs are {names}")
    meta = dict(robot.meta or {})
    out = []
    for leg, role in zip(robot.legs, roles, strict=True):
        rb = leg.robot
        g_body = leg.hip[:3, :3] @ rb.chain.gravity
        g_norm = max(float(np.linalg.norm(g_body)), 1e-300)
        if not np.allclose(g_body / g_norm, [0.0, 0.0, -1.0], atol=1e-6):
            raise ValueError(f"robot: leg {leg.name!r} gravity {rb.chain.gravity.tolist()} (leg "
                             "frame) does not point down the body's z axis")
        ref = np.asarray((q_ref or {}).get(leg.name, rb.home), dtype=float)
        if ref.shape != (rb.nq,):
            raise ValueError(f"q_ref: leg {leg.name!r} has {rb.nq} joints, got {ref.size} angles")
        closed, L = _closed_form(leg)
        lat = float(leg.foot_in_body(fk(rb, ref)[:3, 3])[1] - leg.hip[1, 3])
        if foot_lateral is not None:
            lat = foot_lateral if role.endswith("L") else -foot_lateral
        out.append(GaitLeg(leg=leg, role=role, closed_form=closed, L=L,
                           branch=_branch(meta, leg) if closed else 0.0, q_ref=ref,
                           lateral=lat, com_link=_com_in_links(leg)))
    return tuple(out)
