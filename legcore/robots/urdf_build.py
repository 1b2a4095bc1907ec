"""Build a :class:`~legcore.robots.model.Robot` (or a legged robot) from a URDF specification.

The joints the study does not move are locked first (``locked_joints``, and the ``<mimic>``
joints that follow them: each becomes a fixed joint at its value in the text), the whole file is
built (a fixed base at its root link), its inertias are checked against the robot's own scale,
and what moves must be one serial chain — or, with ``legs``, one serial chain per leg
(:mod:`legcore.robots.urdf_legs`).

The chain's end (``tool`` frame) is the named ``tool_frame`` or, by default, the leaf of the
chain: the frame attached to the last moving joint that no other frame hangs from (the foot of a
leg, ``tool0`` of a UR arm), the farthest from that joint on a tie.

Units: m, rad, kg, kg·m²; motor constants as :class:`~legcore.robots.spec.MotorSpec`.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from legcore.robots.model import MotorArrays, Robot, chain_from_model
from legcore.robots.spec import MotorSpec, URDFRobotSpec, validate_inertia
from legcore.robots.urdf_parse import ParsedURDF

__all__ = [
    "INERTIA_RTOL",
    "extract_chain",
    "frame_id",
    "full_model",
    "leaf_frame",
    "lock_values",
    "motor_arrays",
    "serial_robot",
]

#: Inertia checks allow this fraction of the robot's scale (total mass × size², kg·m²): a dummy
#: link of 1e-6 kg with a rounded 1e-6 kg·m² inertia passes, a wrong link inertia does not.
INERTIA_RTOL = 1e-5
#: Moving joints of one serial chain (or of one leg).
MAX_CHAIN_JOINTS = 12


def motor_arrays(motors: list[MotorSpec | None]) -> MotorArrays:
    """Per-joint actuator arrays (NaN where a constant is unknown) from optional motor specs."""

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


# --------------------------------------------------------------------------- checks


def robot_scale(parsed: ParsedURDF, model: pin.Model) -> float:
    """The robot's inertia scale (kg·m²): total mass × (largest distance of a frame origin or
    a body's COM from the root at q = 0)², or the largest link moment if that is larger."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    pts = [np.asarray(M.translation) for M in data.oMf]
    pts += [np.asarray(data.oMi[j].act(model.inertias[j].lever)) for j in range(model.njoints)]
    size = max(float(np.linalg.norm(p)) for p in pts)
    mass = sum(m for _, m, _ in parsed.inertias)
    moment = max((float(np.abs(inertia).max()) for _, _, inertia in parsed.inertias), default=0.0)
    return max(mass * size**2, moment)


def check_inertias(parsed: ParsedURDF, model: pin.Model) -> None:
    """Every link inertia physical up to ``INERTIA_RTOL`` × :func:`robot_scale`; else a
    ``ValueError`` naming the link and saying what to change."""
    scale = robot_scale(parsed, model)
    tol = INERTIA_RTOL * scale
    for name, _mass, inertia in parsed.inertias:
        try:
            validate_inertia(inertia, tol)
        except ValueError as exc:
            raise ValueError(
                f"urdf: link {name!r} inertia: {exc}; the tolerance is {tol:.1e} kg·m² "
                f"({INERTIA_RTOL:g} × the robot's scale, total mass × size² = {scale:.3g} "
                "kg·m²): correct the link's <inertia> (e.g. that of a solid box of its mass and "
                "size), or remove its <inertial> if it carries no mass"
            ) from None


# --------------------------------------------------------------------------- locking


def lock_values(spec: URDFRobotSpec, parsed: ParsedURDF) -> dict[str, float]:
    """Joint name -> locked value (rad or m): the spec's ``locked_joints`` (null: zero clipped
    to the limits; a given value must lie within them) and the ``<mimic>`` joints following a
    locked master. ``ValueError`` naming the field otherwise."""
    movable = set(parsed.movable)
    values: dict[str, float] = {}
    limits = parsed.limits.__getitem__

    for name, value in spec.locked_joints.items():
        if name not in movable:
            known = ", ".join(sorted(movable)[:12]) + (" …" if len(movable) > 12 else "")
            raise ValueError(
                f"locked_joints: {name!r} is not a moving joint of the URDF (moving: {known})"
            )
        if name in parsed.mimic:
            continue  # set from its master below
        lo, hi = limits(name)
        if value is None:
            values[name] = min(max(0.0, lo), hi)
        elif not lo <= value <= hi:
            raise ValueError(
                f"locked_joints: {name!r} value {value} is outside its limits [{lo:g}, {hi:g}]"
            )
        else:
            values[name] = float(value)
    pending = dict(parsed.mimic)
    while pending:  # a mimic of a mimic follows once its master is known
        done = [n for n, m in pending.items() if m.master in values or m.master not in movable]
        if not done:
            name, m = next(iter(pending.items()))
            raise ValueError(
                f"urdf: joint {name!r} mimics {m.master!r}, which moves; a mimic joint moves "
                f"only with its master: lock {m.master!r} (locked_joints: {{{m.master}: null}}) "
                f"and {name!r} follows it"
            )
        for name in done:
            m = pending.pop(name)
            lo, hi = limits(name)
            value = min(max(m.multiplier * values.get(m.master, 0.0) + m.offset, lo), hi)
            given = spec.locked_joints.get(name)
            if given is not None and abs(given - value) > 1e-9:
                raise ValueError(
                    f"locked_joints: {name!r} mimics {m.master!r} and is held at {value:g} by "
                    f"it; give {m.master!r}'s value instead (or null for {name!r})"
                )
            values[name] = value
    return values


# --------------------------------------------------------------------------- chains


def frame_id(model: pin.Model, name: str) -> int | None:
    """The frame called ``name`` (a link's body frame first, as a joint may share its name),
    or None."""
    found = [fid for fid, f in enumerate(model.frames) if f.name == name]
    if not found:
        return None
    bodies = [fid for fid in found if model.frames[fid].type == pin.FrameType.BODY]
    return (bodies or found)[0]


def leaf_frame(model: pin.Model, joint_id: int) -> int:
    """The end frame of joint ``joint_id``'s subtree: the frame attached to it that no other
    frame hangs from (a link or operational frame), the farthest from the joint on a tie (the
    last declared among equals)."""
    parents = {f.parentFrame for fid, f in enumerate(model.frames) if fid}
    kinds = (pin.FrameType.BODY, pin.FrameType.OP_FRAME)
    leaves = [
        fid
        for fid, f in enumerate(model.frames)
        if f.parentJoint == joint_id and fid not in parents and f.type in kinds
    ]
    if not leaves:
        return next(
            fid
            for fid, f in enumerate(model.frames)
            if f.parentJoint == joint_id and f.type == pin.FrameType.JOINT
        )
    return max(
        leaves,
        key=lambda fid: (
            round(float(np.linalg.norm(model.frames[fid].placement.translation)), 12),
            fid,
        ),
    )


def serial_path_error(model: pin.Model) -> str | None:
    """Why the moving joints of ``model`` are not one serial chain (None when they are)."""
    children: dict[int, list[int]] = {}
    for j in range(1, model.njoints):
        children.setdefault(int(model.parents[j]), []).append(j)
    for parent, kids in children.items():
        if len(kids) > 1:
            where = "the base" if parent == 0 else repr(model.names[parent])
            names = ", ".join(repr(model.names[k]) for k in kids)
            return (
                f"the moving joints do not form one serial chain: {names} all hang from "
                f"{where}; lock the branches the study does not use (locked_joints), or describe "
                "a legged robot (legs)"
            )
    return None


def extract_chain(model: pin.Model, joints: list[int], base: pin.SE3) -> pin.Model:
    """A new model holding only the serial chain ``joints`` of ``model`` (a path whose first
    joint hangs from the base), their bodies and frames; the chain's base frame is moved to
    ``base`` (the old base expressed in the new one: the first joint sits at ``base ·
    placement``)."""
    out = pin.Model()
    out.name = model.name
    out.gravity = pin.Motion(model.gravity)
    jmap = {0: 0}
    for k, jid in enumerate(joints):
        parent = int(model.parents[jid])
        if parent not in jmap:
            raise ValueError(f"joint {model.names[jid]!r} does not hang from the chain")
        M = model.jointPlacements[jid]
        iv = model.joints[jid].idx_v
        new = out.addJoint(
            jmap[parent],
            model.joints[jid],
            base * M if k == 0 else M,
            model.names[jid],
            np.array([model.effortLimit[iv]]),
            np.array([model.velocityLimit[iv]]),
            np.array([model.lowerPositionLimit[model.joints[jid].idx_q]]),
            np.array([model.upperPositionLimit[model.joints[jid].idx_q]]),
        )
        out.appendBodyToJoint(new, model.inertias[jid], pin.SE3.Identity())
        out.armature[new - 1] = model.armature[iv]
        jmap[jid] = new
    fmap = {0: 0}
    for fid, f in enumerate(model.frames):
        if f.parentJoint not in jmap or f.parentJoint == 0:
            continue
        parent_frame = fmap.get(int(f.parentFrame), 0)
        if f.type == pin.FrameType.JOINT:
            fmap[fid] = out.addJointFrame(jmap[f.parentJoint], parent_frame)
        else:
            frame = pin.Frame(f.name, jmap[f.parentJoint], parent_frame, f.placement, f.type)
            fmap[fid] = out.addFrame(frame, False)
    return out


def serial_robot(
    spec: URDFRobotSpec,
    model: pin.Model,
    tool_src: int,
    *,
    name: str | None = None,
    meta: dict[str, object] | None = None,
) -> Robot:
    """The :class:`Robot` of a serial ``model`` (1-DOF joints, joint i's parent is i-1) whose
    end is frame ``tool_src`` (copied as the ``tool`` frame), motors taken from ``spec`` by
    joint name."""
    n = model.njoints - 1
    if not 1 <= n <= MAX_CHAIN_JOINTS:
        raise ValueError(
            f"urdf: a serial chain needs 1 to {MAX_CHAIN_JOINTS} moving joints, found {n}; "
            "lock the others (locked_joints)"
        )
    model.gravity.linear = np.asarray(spec.gravity, dtype=float)
    joint_names = list(model.names)[1:]
    motors = [spec.motors.get(jn) for jn in joint_names]
    for i, m in enumerate(motors):
        if m is not None:
            model.armature[i] = m.Jm * m.G**2
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
    src = model.frames[tool_src]
    if src.parentJoint != n:
        where = "the base" if src.parentJoint == 0 else repr(model.names[src.parentJoint])
        raise ValueError(
            f"tool_frame: frame {src.name!r} is attached to {where}, not to the chain's last "
            f"moving joint {model.names[n]!r}; lock the joints after it (locked_joints)"
        )
    tool_frame = model.addFrame(pin.Frame("tool", n, src.placement, pin.FrameType.OP_FRAME))
    chain = chain_from_model(model, tool_frame)
    q_min = np.asarray(model.lowerPositionLimit, dtype=float).copy()
    q_max = np.asarray(model.upperPositionLimit, dtype=float).copy()
    qd_max = np.asarray(model.velocityLimit, dtype=float).copy()
    qd_max[qd_max <= 0] = 10.0
    tau = np.asarray(model.effortLimit, dtype=float).copy()
    tau[tau <= 0] = np.inf
    return Robot(
        name=name or spec.name,
        spec=spec,
        model=model,
        tool_frame=tool_frame,
        link_frames=tuple(link_frames),
        q_min=q_min,
        q_max=q_max,
        qd_max=qd_max,
        qdd_max=np.array([spec.qdd_max.get(jn, np.inf) for jn in joint_names], dtype=float),
        tau_max=tau,
        home=np.clip(np.zeros(n), q_min, q_max),
        motors=motor_arrays(motors),
        chain=chain,
        ik_family=None,
        meta={"urdf": True, "tool_source": src.name, **(meta or {})},
    )


# --------------------------------------------------------------------------- entry point


def full_model(xml: str, root_joint: pin.JointModel | None = None) -> pin.Model:
    try:
        if root_joint is None:
            return pin.buildModelFromXML(xml)
        return pin.buildModelFromXML(xml, root_joint)
    except Exception as exc:  # pinocchio raises RuntimeError/ValueError with its own text
        raise ValueError(f"urdf: pinocchio could not build the model ({exc})") from None
