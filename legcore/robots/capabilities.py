"""What a robot offers a study, and why a study refuses a robot (DESIGN §5).

A study kind is a task that runs on any robot able to do it. It states what it needs as a
:class:`Needs` (a serial chain of ≥ 5 joints, four legs of 2–3 joints, motor data …), and
:func:`refusal` compares that with the robot's :class:`Capabilities` — never with a robot
family — returning the reason in words that name the missing capability:

    >>> from legcore.robots import catalog
    >>> from legcore.robots.capabilities import Needs, refusal
    >>> refusal("path_tracking", Needs(serial=True, min_joints=5), catalog.get("calderon_leg"))
    'path_tracking needs ≥ 5 actuated joints; robot calderon_leg has 3'
    >>> refusal("path_tracking", Needs(serial=True, min_joints=5), catalog.get("puma560")) is None
    True
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np

from legcore.robots.legged import LeggedRobot
from legcore.robots.model import Robot

__all__ = ["Capabilities", "LegInfo", "Needs", "capabilities", "refusal", "require"]


@dataclass(frozen=True)
class LegInfo:
    """One leg: its joints (hip first), foot frame name, hip position in the body frame (m)."""

    name: str
    n_joints: int
    joint_names: tuple[str, ...]
    foot_frame: str
    hip: tuple[float, float, float]


@dataclass(frozen=True)
class Capabilities:
    """What a built robot offers.

    ``kind``: "serial" (one chain: an arm or a single leg) or "legged" (a body with legs).
    ``n_actuated``: moving joints (all legs together). ``end_frame``: the chain's tool/foot
    frame (serial; the URDF frame it was taken from, or "tool"). ``legs``: each leg's joints.
    ``ik_family``: the closed-form IK that applies (None: numerical). ``electrical``: every
    joint has Kt, Ke and R (electrical energy can be computed; ``electrical_joints`` counts
    those that do). ``torque_limits``: every joint has a finite torque limit. ``prismatic``:
    number of prismatic joints. ``floating_base``: the whole robot's model has a free-flyer root.
    """

    name: str
    kind: Literal["serial", "legged"]
    n_actuated: int
    joint_names: tuple[str, ...]
    end_frame: str | None
    legs: tuple[LegInfo, ...]
    ik_family: str | None
    electrical: bool
    electrical_joints: int
    torque_limits: bool
    prismatic: int
    floating_base: bool

    @property
    def serial_chain(self) -> bool:
        return self.kind == "serial"

    def as_dict(self) -> dict[str, Any]:
        """JSON-able form (tuples as lists)."""
        out = asdict(self)
        out["serial_chain"] = self.serial_chain
        return out


def _chain_facts(robot: Robot) -> tuple[int, int, bool, int]:
    """(electrical joints, torque-limited joints, all electrical, prismatic joints)."""
    elec = int(robot.motors.electrical.sum())
    torque = int(np.isfinite(robot.tau_max).sum())
    return elec, torque, elec == robot.nq, int(robot.chain.prismatic.sum())


def _end_frame(robot: Robot) -> str:
    source = robot.meta.get("tool_source")
    return str(source) if source else str(robot.model.frames[robot.tool_frame].name)


def capabilities(robot: Robot | LeggedRobot) -> Capabilities:
    """The :class:`Capabilities` of a built robot (serial or legged)."""
    if isinstance(robot, LeggedRobot):
        legs = tuple(
            LegInfo(
                name=leg.name,
                n_joints=leg.robot.nq,
                joint_names=tuple(list(leg.robot.model.names)[1:]),
                foot_frame=_end_frame(leg.robot),
                hip=(float(leg.hip[0, 3]), float(leg.hip[1, 3]), float(leg.hip[2, 3])),
            )
            for leg in robot.legs
        )
        facts = [_chain_facts(leg.robot) for leg in robot.legs]
        n = sum(leg.n_joints for leg in legs)
        return Capabilities(
            name=robot.name,
            kind="legged",
            n_actuated=n,
            joint_names=tuple(f"{g.name}.{j}" for g in legs for j in g.joint_names),
            end_frame=None,
            legs=legs,
            ik_family=None,
            electrical=all(f[2] for f in facts),
            electrical_joints=sum(f[0] for f in facts),
            torque_limits=sum(f[1] for f in facts) == n,
            prismatic=sum(f[3] for f in facts),
            floating_base=robot.model is not None,
        )
    elec, torque, all_elec, prismatic = _chain_facts(robot)
    return Capabilities(
        name=robot.name,
        kind="serial",
        n_actuated=robot.nq,
        joint_names=tuple(list(robot.model.names)[1:]),
        end_frame=_end_frame(robot),
        legs=(),
        ik_family=robot.ik_family,
        electrical=all_elec,
        electrical_joints=elec,
        torque_limits=torque == robot.nq,
        prismatic=prismatic,
        floating_base=False,
    )


@dataclass(frozen=True)
class Needs:
    """What a study kind needs from a robot (unset fields: no requirement).

    ``serial``: one serial chain (an arm, or one leg of a legged robot built with ``leg``);
    ``legged``: a body with legs. ``min_joints``/``max_joints``: actuated joints of the chain
    (serial). ``n_legs``: allowed numbers of legs; ``leg_joints``: (min, max) joints per leg.
    ``electrical``: motor data (Kt, Ke, R) on every joint; ``torque_limits``: a finite torque
    limit on every joint; ``revolute``: no prismatic joint.
    """

    serial: bool = False
    legged: bool = False
    min_joints: int | None = None
    max_joints: int | None = None
    n_legs: tuple[int, ...] | None = None
    leg_joints: tuple[int, int] | None = None
    electrical: bool = False
    torque_limits: bool = False
    revolute: bool = False


def _count(lo: int | None, hi: int | None) -> str:
    if lo is not None and hi is not None:
        return f"{lo}" if lo == hi else f"{lo}–{hi}"
    return f"≥ {lo}" if lo is not None else f"≤ {hi}"


def refusal(kind: str, needs: Needs, robot: Robot | LeggedRobot | Capabilities) -> str | None:
    """Why study ``kind`` cannot run on ``robot`` (the first unmet need, naming it and what the
    robot has), or None when the robot offers everything ``needs`` asks for."""
    caps = robot if isinstance(robot, Capabilities) else capabilities(robot)
    who = f"robot {caps.name}"
    if needs.serial and caps.kind != "serial":
        legs = ", ".join(g.name for g in caps.legs)
        return (
            f"{kind} needs a serial chain; {who} is legged (legs {legs}): choose one leg "
            "(robot spec 'leg')"
        )
    if needs.legged and caps.kind != "legged":
        return f"{kind} needs a legged robot; {who} is a serial chain"
    lo, hi = needs.min_joints, needs.max_joints
    if (lo is not None and caps.n_actuated < lo) or (hi is not None and caps.n_actuated > hi):
        return f"{kind} needs {_count(lo, hi)} actuated joints; {who} has {caps.n_actuated}"
    if needs.n_legs is not None and len(caps.legs) not in needs.n_legs:
        allowed = " or ".join(str(n) for n in needs.n_legs)
        of = "" if needs.leg_joints is None else f" of {_count(*needs.leg_joints)} joints"
        return f"{kind} needs {allowed} legs{of}; {who} has {len(caps.legs)} legs"
    if needs.leg_joints is not None:
        lo_l, hi_l = needs.leg_joints
        for leg in caps.legs:
            if not lo_l <= leg.n_joints <= hi_l:
                return (
                    f"{kind} needs legs of {_count(lo_l, hi_l)} joints; leg {leg.name} of "
                    f"{who} has {leg.n_joints}"
                )
    if needs.electrical and not caps.electrical:
        return (
            f"{kind} needs motor data (Kt, Ke, R) on every joint for the electrical energy; "
            f"{who} has it on {caps.electrical_joints} of {caps.n_actuated}"
        )
    if needs.torque_limits and not caps.torque_limits:
        return f"{kind} needs a torque limit on every joint; {who} lacks some"
    if needs.revolute and caps.prismatic:
        return f"{kind} needs revolute joints only; {who} has {caps.prismatic} prismatic"
    return None


def require(kind: str, needs: Needs, robot: Robot | LeggedRobot) -> None:
    """Raise ``ValueError("robot: <reason>")`` when :func:`refusal` gives a reason."""
    reason = refusal(kind, needs, robot)
    if reason is not None:
        raise ValueError(f"robot: {reason}")
