"""Build a :class:`~legcore.robots.model.Robot` (Pinocchio model) from a specification.

Standard DH: frame i = frame i-1 · ``Rz(q_i + offset_i) Tz(d_i) Tx(a_i) Rx(α_i)``. Pinocchio's
joint i sits at DH frame i-1 and turns about its z axis; the link inertia of link i is attached
in DH frame i, i.e. after ``Tz Tx Rx`` (DESIGN.md §2). Modified DH (Craig): joint i is placed at
``Rx(α_{i-1}) Tx(a_{i-1}) Rz(offset_i) Tz(d_i)`` from joint i-1 and the link frame is the joint
frame. Rotor inertia becomes Pinocchio's ``armature`` (``Jm·G²``, joint side).

Frames added to the model: ``frame_1 … frame_n`` (the link frames) and ``tool``.

URDF specifications are built by :mod:`legcore.robots.urdf_build` (whole files: fixed, locked,
mimic and continuous joints) and :mod:`legcore.robots.urdf_legs` (legged robots).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin
from pydantic import TypeAdapter

from legcore.robots.legged import LeggedRobot
from legcore.robots.model import Robot, chain_from_model
from legcore.robots.spec import DHRobotSpec, RobotSpec, URDFRobotSpec
from legcore.robots.urdf_build import motor_arrays
from legcore.robots.urdf_parse import reject_declarations
from legcore.robots.urdf_robot import build_urdf as _build_urdf

__all__ = [
    "build_any_robot",
    "build_robot",
    "parse_robot_spec",
    "reject_declarations",
    "rot_x",
    "rot_z",
    "dh_transform",
]

_SPEC_ADAPTER: TypeAdapter[DHRobotSpec | URDFRobotSpec] = TypeAdapter(RobotSpec)


def parse_robot_spec(data: dict[str, Any]) -> DHRobotSpec | URDFRobotSpec:
    """Validate a JSON/YAML mapping into a robot specification (raises pydantic ValidationError).

    Error locations are relative to the robot (``joints.1.mass``), not prefixed by the kind tag.
    """
    kind = data.get("kind", "dh") if isinstance(data, dict) else None
    if kind == "dh":
        return DHRobotSpec.model_validate(data)
    if kind == "urdf":
        return URDFRobotSpec.model_validate(data)
    return _SPEC_ADAPTER.validate_python(data)


def rot_z(theta: float) -> np.ndarray:
    """4×4 homogeneous rotation about z by ``theta`` (rad)."""
    c, s = math.cos(theta), math.sin(theta)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    return T


def rot_x(alpha: float) -> np.ndarray:
    """4×4 homogeneous rotation about x by ``alpha`` (rad)."""
    c, s = math.cos(alpha), math.sin(alpha)
    T = np.eye(4)
    T[1:3, 1:3] = [[c, -s], [s, c]]
    return T


def _trans(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def dh_transform(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """Standard DH link transform ``Rz(θ) Tz(d) Tx(a) Rx(α)`` (4×4)."""
    return rot_z(theta) @ _trans(0.0, 0.0, d) @ _trans(a, 0.0, 0.0) @ rot_x(alpha)


def _se3(T: np.ndarray) -> pin.SE3:
    return pin.SE3(np.ascontiguousarray(T[:3, :3]), np.ascontiguousarray(T[:3, 3]))


def _build_dh(spec: DHRobotSpec) -> Robot:
    model = pin.Model()
    model.name = spec.name
    model.gravity.linear = np.asarray(spec.gravity, dtype=float)
    base = np.asarray(spec.base, dtype=float) if spec.base is not None else np.eye(4)
    tool = np.asarray(spec.tool, dtype=float) if spec.tool is not None else np.eye(4)
    n = len(spec.joints)
    placement = base
    parent = 0
    link_frames: list[int] = []
    link_in_joint: np.ndarray = np.eye(4)
    for i, j in enumerate(spec.joints):
        name = j.name or f"joint_{i + 1}"
        if spec.convention == "standard":
            joint_placement = placement
            link_in_joint = dh_transform(j.offset, j.d, j.a, j.alpha)
        else:  # modified (Craig): a, alpha of this entry act before the joint
            joint_placement = rot_x(j.alpha) @ _trans(j.a, 0.0, 0.0) @ rot_z(j.offset)
            joint_placement = joint_placement @ _trans(0.0, 0.0, j.d)
            link_in_joint = np.eye(4)
        jmodel = pin.JointModelRZ() if j.type == "revolute" else pin.JointModelPZ()
        tau_max = j.tau_max if j.tau_max is not None else 1e9
        jid = model.addJoint(
            parent,
            jmodel,
            _se3(joint_placement),
            name,
            np.array([tau_max]),
            np.array([j.qd_max]),
            np.array([j.q_min]),
            np.array([j.q_max]),
        )
        X = _se3(link_in_joint)
        inertia = pin.Inertia(j.mass, np.asarray(j.com, float), np.asarray(j.inertia, float))
        model.appendBodyToJoint(jid, X.act(inertia), pin.SE3.Identity())
        link_frames.append(
            model.addFrame(pin.Frame(f"frame_{i + 1}", jid, X, pin.FrameType.OP_FRAME))
        )
        if j.motor is not None:
            model.armature[i] = j.motor.Jm * j.motor.G**2
        placement = link_in_joint
        parent = jid
    tool_frame = model.addFrame(
        pin.Frame("tool", n, _se3(link_in_joint @ tool), pin.FrameType.OP_FRAME)
    )
    home = np.asarray(spec.home if spec.home is not None else np.zeros(n), dtype=float)
    home = np.clip(home, [j.q_min for j in spec.joints], [j.q_max for j in spec.joints])
    return Robot(
        name=spec.name,
        spec=spec,
        model=model,
        tool_frame=tool_frame,
        link_frames=tuple(link_frames),
        q_min=np.array([j.q_min for j in spec.joints]),
        q_max=np.array([j.q_max for j in spec.joints]),
        qd_max=np.array([j.qd_max for j in spec.joints]),
        qdd_max=np.array([np.inf if j.qdd_max is None else j.qdd_max for j in spec.joints]),
        tau_max=np.array([j.tau_max if j.tau_max is not None else np.inf for j in spec.joints]),
        home=home,
        motors=motor_arrays([j.motor for j in spec.joints]),
        chain=chain_from_model(model, tool_frame),
        ik_family=spec.ik,
    )


def build_any_robot(
    spec: DHRobotSpec | URDFRobotSpec | dict[str, Any],
) -> Robot | LeggedRobot:
    """Build a robot from a specification (or a mapping that validates into one): a serial
    :class:`Robot`, or a :class:`LeggedRobot` for a URDF spec with ``legs`` (and no ``leg``).

    Raises ``pydantic.ValidationError`` for a spec that fails the field rules and ``ValueError``
    (message starting with the field, e.g. ``urdf: …``, ``locked_joints: …``) for a model that
    fails the physical rules.
    """
    if isinstance(spec, dict):
        spec = parse_robot_spec(spec)
    if isinstance(spec, DHRobotSpec):
        return _build_dh(spec)
    return _build_urdf(spec)


def build_robot(spec: DHRobotSpec | URDFRobotSpec | dict[str, Any]) -> Robot:
    """Build a serial :class:`Robot` from a specification (see :func:`build_any_robot`; a spec
    of a whole legged robot is a ``ValueError`` here — give ``leg`` to get one of its legs)."""
    robot = build_any_robot(spec)
    if isinstance(robot, LeggedRobot):
        raise ValueError(
            f"legs: {robot.name!r} is a legged robot ({robot.n_legs} legs), not a serial chain; "
            f"give 'leg' (one of {[leg.name for leg in robot.legs]}) for one leg's chain"
        )
    return robot
