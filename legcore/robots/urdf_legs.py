"""A legged robot from one URDF: a floating base (the root link) carrying serial legs.

Legs are found on the model whose unused joints are already locked (every joint left moves):

- ``legs: {LF: {foot: LF_FOOT}}`` — the chain of joints from the base down to the frame
  ``LF_FOOT``; with ``hip: LF_HAA`` too, the chain from that joint down;
- ``legs: {LF: {hip: LF_HAA}}`` — that joint and the joints below it (they must not branch),
  ending at the leaf frame of the last one (:func:`~legcore.robots.urdf_build.leaf_frame`);
- ``legs: auto`` — one leg per leaf of the joint tree, the chain from the base to it.

Every moving joint belongs to exactly one leg, and nothing between the base and a hip moves.
Each leg becomes a fixed-base serial :class:`~legcore.robots.model.Robot` whose base frame sits
at its hip joint's origin with the body's axes (``Leg.hip`` is that translation, m), so its
foot positions read "from the hip, body axes" and its gravity is the body's.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from legcore.robots.legged import Leg, LeggedRobot
from legcore.robots.spec import URDFRobotSpec
from legcore.robots.urdf_build import extract_chain, frame_id, leaf_frame, serial_robot
from legcore.robots.urdf_parse import ParsedURDF

__all__ = ["LegChain", "build_legged", "find_legs"]

_SEP = re.compile(r"[_\-.]")


@dataclass(frozen=True)
class LegChain:
    """A leg found in a model: ``joints`` (ids, hip first) and its ``foot`` frame id."""

    name: str
    joints: tuple[int, ...]
    foot: int


def _path(model: pin.Model, jid: int) -> list[int]:
    """Joint ids from the base down to ``jid`` (inclusive)."""
    out = []
    while jid != 0:
        out.append(jid)
        jid = int(model.parents[jid])
    return out[::-1]


def _children(model: pin.Model) -> dict[int, list[int]]:
    kids: dict[int, list[int]] = {j: [] for j in range(model.njoints)}
    for j in range(1, model.njoints):
        kids[int(model.parents[j])].append(j)
    return kids


def _joint_id(model: pin.Model, name: str, field: str) -> int:
    if not model.existJointName(name):
        raise ValueError(
            f"{field}: no moving joint named {name!r} (a locked or fixed joint cannot start a leg)"
        )
    return int(model.getJointId(name))


def _explicit(model: pin.Model, spec: URDFRobotSpec) -> list[LegChain]:
    assert isinstance(spec.legs, dict)
    kids = _children(model)
    out = []
    for name, leg in spec.legs.items():
        field = f"legs.{name}"
        if leg.foot is not None:
            found = frame_id(model, leg.foot)
            if found is None:
                raise ValueError(f"{field}.foot: no frame or link named {leg.foot!r} in the URDF")
            foot = found
            end = int(model.frames[foot].parentJoint)
            if end == 0:
                raise ValueError(
                    f"{field}.foot: {leg.foot!r} is on the base (no moving joint above it)"
                )
            chain = _path(model, end)
            if leg.hip is not None:
                hip = _joint_id(model, leg.hip, f"{field}.hip")
                if hip not in chain:
                    raise ValueError(
                        f"{field}: hip {leg.hip!r} is not between the base and the foot "
                        f"{leg.foot!r}"
                    )
                chain = chain[chain.index(hip) :]
        else:
            assert leg.hip is not None
            chain = [_joint_id(model, leg.hip, f"{field}.hip")]
            while kids[chain[-1]]:
                below = kids[chain[-1]]
                if len(below) > 1:
                    names = ", ".join(repr(model.names[k]) for k in below)
                    raise ValueError(
                        f"{field}.hip: the joints below {leg.hip!r} branch at "
                        f"{model.names[chain[-1]]!r} ({names}); name the leg by its foot, or "
                        "lock the branch it does not use (locked_joints)"
                    )
                chain.append(below[0])
            foot = leaf_frame(model, chain[-1])
        out.append(LegChain(name, tuple(chain), foot))
    return out


def _auto_names(model: pin.Model, chains: list[list[int]], feet: list[int]) -> list[str]:
    """Common prefix of each leg's joint names (cut at a separator), else its foot's name."""
    names = []
    for chain in chains:
        prefix = os.path.commonprefix([model.names[j] for j in chain])
        cut = [m.start() for m in _SEP.finditer(prefix)]
        if cut and (len(chain) > 1 or cut[-1] > 0):
            prefix = prefix[: cut[-1]]
        names.append(prefix)
    ok = re.compile(r"^[A-Za-z0-9_\-]{1,32}$")
    if all(ok.match(n) for n in names) and len(set(names)) == len(names):
        return names
    names = [re.sub(r"[^A-Za-z0-9_\-]", "_", model.frames[f].name)[:32] for f in feet]
    if all(names) and len(set(names)) == len(names):
        return names
    return [f"leg{i + 1}" for i in range(len(chains))]


def _leg_leaves(model: pin.Model, leaves: list[int]) -> list[int]:
    """The leaves whose end frames are feet: at the neutral configuration at least half as far
    below the base as the lowest end (an arm, a head or a tail ends higher). All of them when
    no end is below the base."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    z = np.array([data.oMf[leaf_frame(model, j)].translation[2] for j in leaves])
    if z.size == 0 or z.min() >= 0.0:
        return leaves
    return [j for j, zj in zip(leaves, z, strict=True) if zj <= 0.5 * z.min()]


def _auto(model: pin.Model) -> list[LegChain]:
    kids = _children(model)
    all_leaves = [j for j in range(1, model.njoints) if not kids[j]]
    leaves = _leg_leaves(model, all_leaves)
    others = [j for j in all_leaves if j not in leaves]
    if others:
        moving = sorted({model.names[i] for j in others for i in _path(model, j)
                         if not any(i in _path(model, leg) for leg in leaves)})
        raise ValueError(
            f"legs: auto found {len(leaves)} legs (the lowest branch ends) and other branches "
            f"ending higher (an arm, a head?) whose joints {moving} move; lock them "
            "(locked_joints) or name the legs (legs: {NAME: {foot: FRAME}})"
        )
    chains = [_path(model, j) for j in leaves]
    feet = [leaf_frame(model, j) for j in leaves]
    if not 1 <= len(chains) <= 8:
        raise ValueError(
            f"legs: auto found {len(chains)} leaves in the joint tree, a legged robot has 1 to 8 "
            "legs; lock the joints of the other branches (locked_joints) or name the legs"
        )
    names = _auto_names(model, chains, feet)
    return [LegChain(n, tuple(c), f) for n, c, f in zip(names, chains, feet, strict=True)]


def _check_cover(model: pin.Model, legs: list[LegChain]) -> None:
    owner: dict[int, str] = {}
    for leg in legs:
        above = _path(model, leg.joints[0])[:-1]
        if above:
            names = [model.names[j] for j in above]
            raise ValueError(
                f"legs.{leg.name}: joint(s) {names} between the base and the hip "
                f"{model.names[leg.joints[0]]!r} move; lock them (locked_joints)"
            )
        for j in leg.joints:
            if j in owner:
                raise ValueError(
                    f"legs: joint {model.names[j]!r} belongs to legs {owner[j]!r} and "
                    f"{leg.name!r}; lock it (locked_joints) or name the legs below it (hip)"
                )
            owner[j] = leg.name
    free = [model.names[j] for j in range(1, model.njoints) if j not in owner]
    if free:
        raise ValueError(
            f"legs: joint(s) {free} belong to no leg; lock them (locked_joints) or add a leg "
            "that contains them"
        )


def find_legs(model: pin.Model, spec: URDFRobotSpec) -> list[LegChain]:
    """The legs of ``model`` (a fixed-base model whose joints all move) as ``spec.legs`` names
    them; ``ValueError`` naming the field when they do not partition the moving joints."""
    if model.njoints == 1:
        raise ValueError("legs: no moving joint left (every joint is fixed or locked)")
    legs = _auto(model) if spec.legs == "auto" else _explicit(model, spec)
    _check_cover(model, legs)
    if spec.leg is not None and spec.leg not in {leg.name for leg in legs}:
        raise ValueError(f"leg: no leg {spec.leg!r}; the legs are {[g.name for g in legs]}")
    return legs


def build_legged(
    spec: URDFRobotSpec, parsed: ParsedURDF, model: pin.Model, floating: pin.Model
) -> LeggedRobot:
    """The :class:`LeggedRobot` of ``spec``: ``model`` is the fixed-base model with the unused
    joints locked, ``floating`` the same with a free-flyer root (kept as ``LeggedRobot.model``).

    ``body_mass`` is the floating base's mass (root link, its fixed children and the locked
    parts, kg); ``body_size`` the root link's box geometry if the file gives one, else the box
    around the hips (height a quarter of its length), m.
    """
    legs = []
    for chain in find_legs(model, spec):
        hip = np.asarray(model.jointPlacements[chain.joints[0]].translation, dtype=float).copy()
        leg_model = extract_chain(model, list(chain.joints), pin.SE3(np.eye(3), -hip))
        foot_name = model.frames[chain.foot].name
        foot = max(
            fid
            for fid, f in enumerate(leg_model.frames)
            if f.name == foot_name and f.parentJoint == leg_model.njoints - 1
        )
        leg_spec = spec.model_copy(update={"leg": chain.name})
        robot = serial_robot(
            leg_spec,
            leg_model,
            foot,
            name=f"{spec.name}.{chain.name}",
            meta={"leg": chain.name, "hip": hip.tolist()},
        )
        T = np.eye(4)
        T[:3, 3] = hip
        legs.append(Leg(name=chain.name, robot=robot, hip=T))
    hips = np.array([leg.hip[:3, 3] for leg in legs])
    if parsed.root_box is not None:
        size = parsed.root_box
    else:
        span = np.ptp(hips, axis=0) if len(legs) > 1 else np.zeros(3)
        size = (float(span[0]), float(span[1]), 0.25 * float(max(span[0], span[1])))
    return LeggedRobot(
        name=spec.name,
        legs=tuple(legs),
        body_size=size,
        body_mass=float(floating.inertias[1].mass),
        meta={"urdf": True},
        spec=spec,
        model=floating,
    )
