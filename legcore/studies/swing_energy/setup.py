"""Set-up of a ``swing_energy`` problem on any leg: which chain swings, where its foot is, its
start and end configurations, and the obstacle boxes (see
:mod:`legcore.studies.swing_energy.problem`).

- :func:`swing_leg` — the serial chain that swings: the robot itself (a serial leg or arm of 2–6
  revolute joints), or one leg of a legged robot (``params.leg``); with ``params.foot_frame``
  the chain's tool frame is moved to that frame (it must hang from the last joint).
- :func:`configuration` — a start/end configuration from joint values or a foot position (IK:
  the closed form where the chain has one, :func:`legcore.ik.solve` otherwise), checked against
  the joint limits (the defaults of both: :mod:`legcore.studies.swing_energy.defaults`).
- :func:`boxes` — the mid-stride obstacle of seed 000 plus the user's boxes.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray

from legcore.ik import solve
from legcore.robots.legged import LeggedRobot
from legcore.robots.model import Robot, chain_from_model
from legcore.studies.study import Box
from legcore.studies.swing_energy.params import BoxSpec, Obstacle, Params

__all__ = ["boxes", "configuration", "swing_leg"]

FloatArray = NDArray[np.float64]


def swing_leg(robot: object, params: Params) -> tuple[Robot, str]:
    """The chain that swings and its display name (``"solo12.FL"`` for a leg of a robot).

    Raises ``ValueError`` naming ``leg`` / ``foot_frame`` / ``robot``.
    """
    if isinstance(robot, LeggedRobot):
        names = [leg.name for leg in robot.legs]
        if params.leg is None:
            raise ValueError(f"leg: swing_energy swings one leg of the legged robot "
                             f"{robot.name!r}; name it in problem.leg (one of {names})")
        if params.leg not in names:
            raise ValueError(f"leg: robot {robot.name!r} has no leg {params.leg!r}; legs are "
                             f"{names}")
        chain, label = robot.leg(params.leg).robot, f"{robot.name}.{params.leg}"
    elif isinstance(robot, Robot):
        if params.leg is not None:
            raise ValueError(f"leg: robot {robot.name!r} is a serial chain (it is the leg); "
                             "'leg' names a leg of a legged robot")
        chain, label = robot, robot.name
    else:
        raise ValueError(f"robot: swing_energy needs a serial leg or a legged robot, got "
                         f"{type(robot).__name__}")
    if params.foot_frame is not None:
        chain = with_foot_frame(chain, params.foot_frame)
    return chain, label


def with_foot_frame(robot: Robot, name: str) -> Robot:
    """``robot`` with its tool frame moved to the frame ``name`` (which must hang from the last
    joint); the closed-form IK family is dropped unless the frame is the tool already."""
    model = robot.model
    ids = [i for i, f in enumerate(model.frames) if f.name == name]
    if not ids:
        known = sorted({f.name for f in model.frames if f.parentJoint == robot.nq})
        raise ValueError(f"foot_frame: no frame {name!r} in {robot.name!r}; frames on its last "
                         f"joint: {known}")
    fid = ids[-1]
    if fid == robot.tool_frame:
        return robot
    if model.frames[fid].parentJoint != robot.nq:
        raise ValueError(f"foot_frame: {name!r} is not attached to the last joint of "
                         f"{robot.name!r} (it would not move with the whole leg)")
    chain = chain_from_model(model, fid)
    meta = {**robot.meta, "tool_source": name}
    return dataclasses.replace(robot, tool_frame=fid, chain=chain, ik_family=None, meta=meta)


def configuration(
    robot: Robot,
    which: str,
    q: tuple[float, ...] | None,
    foot: tuple[float, float, float] | None,
    reference: FloatArray,
    res: float,
    exact: bool,
) -> tuple[FloatArray, NDArray[np.int64]]:
    """A start/end configuration: ``(q (n,) rad, its grid steps (n,))``.

    ``q`` (joint values) or ``foot`` (a foot position in the leg base frame, m; solved by
    :func:`legcore.ik.solve` on the branch nearest ``reference``); one of them must be given
    (``derive`` fills them). Rounded onto the grid of ``res`` unless ``exact``. ``ValueError``
    naming ``q_<which>`` / ``foot_<which>``.
    """
    n = robot.nq
    field = f"q_{which}" if foot is None else f"foot_{which}"
    if foot is not None:
        sol = solve(robot, np.asarray(foot, dtype=float), "position", q0=reference,
                    rest=reference)
        if not bool(sol.reachable):
            raise ValueError(f"foot_{which}: {list(foot)} m is not reachable by "
                             f"{robot.name!r} within its joint limits")
        qq = np.asarray(sol.q, dtype=float)
    elif q is not None:
        if len(q) != n:
            raise ValueError(f"q_{which}: {len(q)} values for a leg of {n} joints")
        qq = np.asarray(q, dtype=float)
    else:
        raise ValueError(f"q_{which}: give q_{which} or foot_{which} for this {n}-joint leg")
    steps = np.rint(qq / res).astype(np.int64)
    if not exact:
        qq = steps * res
    if np.any(qq < robot.q_min - 1e-12) or np.any(qq > robot.q_max + 1e-12):
        raise ValueError(f"{field}: configuration {qq.round(4).tolist()} rad is outside the "
                         f"joint limits of {robot.name!r}")
    return qq, steps


def boxes(
    ob: Obstacle | None,
    extra: tuple[BoxSpec, ...],
    foot_start: FloatArray,
    foot_end: FloatArray,
    z_ground: float,
) -> tuple[tuple[Box, ...], tuple[float, ...]]:
    """The obstacle boxes (without margin) and their margins (m): seed 000's mid-stride box
    :class:`Obstacle` (placed from the feet and the ground) first, then the user's boxes."""
    out: list[Box] = []
    margins: list[float] = []
    if ob is not None:
        if ob.length is None or ob.width is None or ob.height is None or ob.margin is None:
            raise ValueError("obstacle: its size is left to the leg; derive it first "
                             "(legcore.studies.swing_energy.defaults.derive)")
        length, width, height = ob.length, ob.width, ob.height
        chord = foot_end - foot_start
        heading = np.array([chord[0], chord[1], 0.0])
        n = float(np.linalg.norm(heading))
        if n < 1e-9:
            raise ValueError("obstacle: start and end feet coincide in the horizontal plane; "
                             "'mid-stride' is undefined")
        heading /= n
        left = np.array([-heading[1], heading[0], 0.0])
        c = foot_start + ob.along * chord + ob.lateral * left
        c[2] = z_ground + 0.5 * height
        along_x = abs(heading[0]) >= abs(heading[1])
        half = (length / 2, width / 2) if along_x else (width / 2, length / 2)
        out.append(Box(center=(float(c[0]), float(c[1]), float(c[2])),
                       half_size=(float(half[0]), float(half[1]), height / 2)))
        margins.append(float(ob.margin))
    for b in extra:
        out.append(Box(center=tuple(float(v) for v in b.center),  # type: ignore[arg-type]
                       half_size=tuple(float(v) / 2 for v in b.size)))  # type: ignore[arg-type]
        margins.append(float(b.margin))
    return tuple(out), tuple(margins)
