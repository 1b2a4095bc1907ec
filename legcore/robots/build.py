"""Build a :class:`~legcore.robots.model.Robot` (Pinocchio model) from a specification.

Standard DH: frame i = frame i-1 · ``Rz(q_i + offset_i) Tz(d_i) Tx(a_i) Rx(α_i)``. Pinocchio's
joint i sits at DH frame i-1 and turns about its z axis; the link inertia of link i is attached
in DH frame i, i.e. after ``Tz Tx Rx`` (DESIGN.md §2). Modified DH (Craig): joint i is placed at
``Rx(α_{i-1}) Tx(a_{i-1}) Rz(offset_i) Tz(d_i)`` from joint i-1 and the link frame is the joint
frame. Rotor inertia becomes Pinocchio's ``armature`` (``Jm·G²``, joint side).

Frames added to the model: ``frame_1 … frame_n`` (the link frames) and ``tool``.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from typing import Any

import numpy as np
import pinocchio as pin
from pydantic import TypeAdapter

from legcore.robots.model import MotorArrays, Robot, chain_from_model
from legcore.robots.spec import (
    DHRobotSpec,
    MotorSpec,
    RobotSpec,
    URDFRobotSpec,
    validate_inertia,
)

__all__ = ["build_robot", "parse_robot_spec", "rot_x", "rot_z", "dh_transform"]

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


def _motor_arrays(motors: list[MotorSpec | None]) -> MotorArrays:
    def col(attr: str, default: float) -> np.ndarray:
        out = []
        for m in motors:
            v = getattr(m, attr) if m is not None else None
            out.append(default if v is None else float(v))
        return np.asarray(out, dtype=float)

    return MotorArrays(
        G=col("G", 1.0),
        Jm=col("Jm", 0.0),
        Kt=col("Kt", math.nan),
        Ke=col("Ke", math.nan),
        R=col("R", math.nan),
        B=col("B", 0.0),
        Tc_pos=col("Tc_pos", 0.0),
        Tc_neg=col("Tc_neg", 0.0),
    )


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
        tau_max=np.array([j.tau_max if j.tau_max is not None else np.inf for j in spec.joints]),
        home=home,
        motors=_motor_arrays([j.motor for j in spec.joints]),
        chain=chain_from_model(model, tool_frame),
        ik_family=spec.ik,
    )


def _prepare_urdf(text: str) -> tuple[str, list[str]]:
    """Parse URDF text, map ``continuous`` joints to revolute ±2π, return (xml, movable names)."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ValueError(f"urdf: not well-formed XML ({exc})") from None
    if root.tag != "robot":
        raise ValueError(f"urdf: root element must be <robot>, got <{root.tag}>")
    movable: list[str] = []
    for joint in root.iter("joint"):
        jtype = joint.get("type", "")
        name = joint.get("name", "?")
        if jtype in {"floating", "planar"}:
            raise ValueError(f"urdf: joint {name!r} has type {jtype!r}; only 1-DOF joints")
        if jtype == "continuous":
            joint.set("type", "revolute")
            limit = joint.find("limit")
            if limit is None:
                limit = ET.SubElement(joint, "limit", effort="1e9", velocity="10")
            limit.set("lower", str(-2 * math.pi))
            limit.set("upper", str(2 * math.pi))
        if joint.get("type") in {"revolute", "prismatic"}:
            movable.append(name)
            limit = joint.find("limit")
            if limit is None:
                raise ValueError(f"urdf: joint {name!r} needs a <limit> element")
            lo, hi = float(limit.get("lower", "0")), float(limit.get("upper", "0"))
            if not (math.isfinite(lo) and math.isfinite(hi)) or not lo < hi:
                raise ValueError(f"urdf: joint {name!r} limits must satisfy lower < upper")
    for link in root.iter("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        lname = link.get("name", "?")
        mass_el = inertial.find("mass")
        mass = float(mass_el.get("value", "0")) if mass_el is not None else 0.0
        if not math.isfinite(mass) or mass < 0:
            raise ValueError(f"urdf: link {lname!r} mass must be a finite value >= 0 kg")
        I_el = inertial.find("inertia")
        if I_el is not None:
            g = {k: float(I_el.get(k, "0")) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
            inertia = np.array(
                [
                    [g["ixx"], g["ixy"], g["ixz"]],
                    [g["ixy"], g["iyy"], g["iyz"]],
                    [g["ixz"], g["iyz"], g["izz"]],
                ]
            )
            if not np.all(np.isfinite(inertia)):
                raise ValueError(f"urdf: link {lname!r} inertia has non-finite values")
            try:
                validate_inertia(inertia)
            except ValueError as exc:
                raise ValueError(f"urdf: link {lname!r} inertia: {exc}") from None
    return ET.tostring(root, encoding="unicode"), movable


def _build_urdf(spec: URDFRobotSpec) -> Robot:
    xml, movable = _prepare_urdf(spec.urdf)
    if not 1 <= len(movable) <= 12:
        raise ValueError(f"urdf: needs 1 to 12 movable joints, found {len(movable)}")
    try:
        model = pin.buildModelFromXML(xml)
    except Exception as exc:  # pinocchio raises RuntimeError/ValueError with its own text
        raise ValueError(f"urdf: pinocchio could not build the model ({exc})") from None
    model.name = spec.name
    model.gravity.linear = np.asarray(spec.gravity, dtype=float)
    n = model.njoints - 1
    joint_names = list(model.names)[1:]
    unknown = sorted(set(spec.motors) - set(joint_names))
    if unknown:
        raise ValueError(f"motors: unknown joint name(s) {unknown}")
    motors = [spec.motors.get(name) for name in joint_names]
    for i, m in enumerate(motors):
        if m is not None:
            model.armature[i] = m.Jm * m.G**2
    # Link frames: the body frame of each joint's child link.
    link_frames = []
    for jid in range(1, n + 1):
        bodies = [
            fid
            for fid, f in enumerate(model.frames)
            if f.parentJoint == jid and f.type == pin.FrameType.BODY
        ]
        if not bodies:
            raise ValueError(f"urdf: joint {model.names[jid]!r} has no child link")
        link_frames.append(bodies[0])
    if spec.tool_frame is not None:
        if not model.existFrame(spec.tool_frame):
            raise ValueError(f"tool_frame: no frame named {spec.tool_frame!r} in the URDF")
        tool_src = model.frames[model.getFrameId(spec.tool_frame)]
    else:  # deepest frame of the last joint (the last link or a fixed child of it)
        tool_src = model.frames[
            max(fid for fid, f in enumerate(model.frames) if f.parentJoint == n)
        ]
    tool_frame = model.addFrame(pin.Frame("tool", n, tool_src.placement, pin.FrameType.OP_FRAME))
    chain = chain_from_model(model, tool_frame)
    q_min = np.asarray(model.lowerPositionLimit, dtype=float).copy()
    q_max = np.asarray(model.upperPositionLimit, dtype=float).copy()
    qd_max = np.asarray(model.velocityLimit, dtype=float).copy()
    qd_max[qd_max <= 0] = 10.0
    tau = np.asarray(model.effortLimit, dtype=float).copy()
    tau[tau <= 0] = np.inf
    return Robot(
        name=spec.name,
        spec=spec,
        model=model,
        tool_frame=tool_frame,
        link_frames=tuple(link_frames),
        q_min=q_min,
        q_max=q_max,
        qd_max=qd_max,
        tau_max=tau,
        home=np.clip(np.zeros(n), q_min, q_max),
        motors=_motor_arrays(motors),
        chain=chain,
        ik_family=None,
        meta={"urdf": True},
    )


def build_robot(spec: DHRobotSpec | URDFRobotSpec | dict[str, Any]) -> Robot:
    """Build a :class:`Robot` from a specification (or a mapping that validates into one).

    Raises ``pydantic.ValidationError`` for a spec that fails the field rules and ``ValueError``
    (message starting with the field, e.g. ``urdf: …``) for a URDF that fails the physical rules.
    """
    if isinstance(spec, dict):
        spec = parse_robot_spec(spec)
    if isinstance(spec, DHRobotSpec):
        return _build_dh(spec)
    return _build_urdf(spec)
