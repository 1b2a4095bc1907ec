"""The built robot: a Pinocchio model plus the arrays the batched fast paths run on.

Like Pinocchio, the model (constant) is kept apart from the data (scratch space per thread):
:class:`Robot` is immutable and shareable; ``robot.data()`` makes a fresh ``pinocchio.Data``.

:class:`Chain` is a flat, numba-friendly copy of the serial chain taken *from the Pinocchio model*
(so DH and URDF robots share one fast path): for joint ``i`` (0-based) its placement in the frame
of joint ``i-1`` (``R_i``, ``p_i``), its unit axis, whether it is prismatic, the link inertia in
the joint frame, and the armature.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from legcore.robots.spec import DHRobotSpec, URDFRobotSpec

__all__ = ["Chain", "MotorArrays", "Robot"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Chain:
    """Serial-chain arrays extracted from a Pinocchio model (all SI, per joint i = 0..n-1).

    ``R`` (n,3,3), ``p`` (n,3): placement of joint i in the frame of joint i-1 (joint 0: base).
    ``axis`` (n,3): unit motion axis in the joint frame. ``prismatic`` (n,) bool.
    ``mass`` (n,) kg, ``com`` (n,3) m and ``I_com`` (n,3,3) kg·m² about the COM, in joint frame i.
    ``armature`` (n,) reflected rotor inertia (kg·m² or kg). ``tool_R`` (3,3), ``tool_p`` (3,):
    tool placement in the last joint frame. ``gravity`` (3,) m/s² in the base frame.
    """

    R: FloatArray
    p: FloatArray
    axis: FloatArray
    prismatic: NDArray[np.bool_]
    mass: FloatArray
    com: FloatArray
    I_com: FloatArray
    armature: FloatArray
    tool_R: FloatArray
    tool_p: FloatArray
    gravity: FloatArray

    @property
    def n(self) -> int:
        return int(self.mass.shape[0])


@dataclass(frozen=True, eq=False)
class MotorArrays:
    """Per-joint actuator data (n,), NaN where unknown (see ``MotorSpec``)."""

    G: FloatArray
    Jm: FloatArray
    Kt: FloatArray
    Ke: FloatArray
    R: FloatArray
    B: FloatArray
    Tc_pos: FloatArray
    Tc_neg: FloatArray

    @property
    def electrical(self) -> NDArray[np.bool_]:
        """(n,) True for joints whose Kt, Ke and R are all known."""
        return np.isfinite(self.Kt) & np.isfinite(self.Ke) & np.isfinite(self.R)


@dataclass(frozen=True, eq=False)
class Robot:
    """An immutable serial robot.

    Attributes: ``name``; ``spec`` (the validated specification it was built from); ``model``
    (``pinocchio.Model``, treat as read-only); ``tool_frame`` (frame id of the tool);
    ``link_frames`` (frame ids of the link frames 1..n, for drawing and per-link quantities);
    joint limits ``q_min``, ``q_max`` (rad or m), ``qd_max`` (rad/s), ``qdd_max`` (rad/s², inf
    if not given: URDF has no acceleration limits, the spec may add them), ``tau_max`` (N·m,
    inf if unknown); ``home`` configuration; ``motors``; ``chain`` (fast-path arrays); ``ik_family``
    (name of the closed-form IK that applies, or None for damped least squares).
    """

    name: str
    spec: DHRobotSpec | URDFRobotSpec
    model: pin.Model
    tool_frame: int
    link_frames: tuple[int, ...]
    q_min: FloatArray
    q_max: FloatArray
    qd_max: FloatArray
    qdd_max: FloatArray
    tau_max: FloatArray
    home: FloatArray
    motors: MotorArrays
    chain: Chain
    ik_family: str | None = None
    meta: dict[str, object] = field(default_factory=dict)

    @property
    def nq(self) -> int:
        return int(self.model.nq)

    def data(self) -> pin.Data:
        """A fresh ``pinocchio.Data`` for this model (not thread-safe to share)."""
        return self.model.createData()

    def within_limits(self, q: FloatArray, tol: float = 1e-12) -> NDArray[np.bool_]:
        """(…,) True where every joint of ``q`` (…, nq) lies inside [q_min, q_max]."""
        q = np.asarray(q, dtype=float)
        return np.all((q >= self.q_min - tol) & (q <= self.q_max + tol), axis=-1)


def chain_from_model(model: pin.Model, tool_frame: int) -> Chain:
    """Extract :class:`Chain` arrays from a serial Pinocchio model with 1-DOF joints."""
    n = model.njoints - 1
    R = np.zeros((n, 3, 3))
    p = np.zeros((n, 3))
    axis = np.zeros((n, 3))
    prismatic = np.zeros(n, dtype=bool)
    mass = np.zeros(n)
    com = np.zeros((n, 3))
    I_com = np.zeros((n, 3, 3))
    for i in range(n):
        jid = i + 1
        if model.parents[jid] != i:
            raise ValueError(f"joint {model.names[jid]!r}: model is not a serial chain")
        jm = model.joints[jid]
        if jm.nq != 1 or jm.nv != 1:
            raise ValueError(f"joint {model.names[jid]!r}: only 1-DOF joints are supported")
        M = model.jointPlacements[jid]
        R[i], p[i] = M.rotation, M.translation
        S = _motion_axis(jm)  # unit twist [v; ω] of the joint in its own frame
        if np.linalg.norm(S[3:]) < 1e-12:
            prismatic[i] = True
            axis[i] = S[:3]
        elif np.linalg.norm(S[:3]) < 1e-12:
            axis[i] = S[3:]
        else:
            raise ValueError(f"joint {model.names[jid]!r}: helical joints are not supported")
        inertia = model.inertias[jid]
        mass[i] = inertia.mass
        com[i] = inertia.lever
        I_com[i] = inertia.inertia
    armature = np.asarray(model.armature, dtype=float).copy()
    frame = model.frames[tool_frame]
    if frame.parentJoint != n:
        raise ValueError("tool frame must be attached to the last joint")
    return Chain(
        R=R,
        p=p,
        axis=axis,
        prismatic=prismatic,
        mass=mass,
        com=com,
        I_com=I_com,
        armature=armature,
        tool_R=np.asarray(frame.placement.rotation).copy(),
        tool_p=np.asarray(frame.placement.translation).copy(),
        gravity=np.asarray(model.gravity.linear).copy(),
    )


def _motion_axis(jm: pin.JointModel) -> FloatArray:
    """The 6-vector motion subspace S = [v; ω] of a 1-DOF joint (at q = 0)."""
    model = pin.Model()
    model.addJoint(0, jm, pin.SE3.Identity(), "probe")
    data = model.createData()
    q = pin.neutral(model)
    pin.computeJointJacobians(model, data, q)
    J = pin.getJointJacobian(model, data, 1, pin.ReferenceFrame.LOCAL)
    return np.asarray(J, dtype=float).reshape(6, -1)[:, 0]
