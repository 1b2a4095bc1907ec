"""Build the robot of a URDF spec: a serial :class:`~legcore.robots.model.Robot`
(:mod:`legcore.robots.urdf_build`: fixed, locked, mimic and continuous joints) or a
:class:`~legcore.robots.legged.LeggedRobot` (:mod:`legcore.robots.urdf_legs`), or one leg of it.
The one place that chooses between the two, so neither imports the other."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from legcore.robots.legged import LeggedRobot
from legcore.robots.model import Robot
from legcore.robots.spec import URDFRobotSpec
from legcore.robots.urdf_build import (
    check_inertias,
    frame_id,
    full_model,
    leaf_frame,
    lock_values,
    serial_path_error,
    serial_robot,
)
from legcore.robots.urdf_legs import build_legged
from legcore.robots.urdf_parse import lock_xml, parse_urdf

__all__ = ["build_urdf"]


def build_urdf(spec: URDFRobotSpec) -> Robot | LeggedRobot:
    """The robot of a URDF spec: a serial :class:`Robot`, a :class:`LeggedRobot` when ``legs``
    is given, or one leg's serial :class:`Robot` when ``leg`` is given too. ``ValueError``
    naming the field (``urdf: …``, ``locked_joints: …``, ``legs.LF.foot: …``) otherwise."""
    parsed = parse_urdf(spec.urdf)
    unknown = sorted(set(spec.motors) - set(parsed.movable))
    if unknown:
        raise ValueError(f"motors: unknown joint name(s) {unknown}")
    unknown = sorted(set(spec.qdd_max) - set(parsed.movable))
    if unknown:
        raise ValueError(f"qdd_max: unknown joint name(s) {unknown} (give moving joints' names)")
    values = lock_values(spec, parsed)
    xml = lock_xml(parsed.xml, values)
    model = full_model(xml)
    model.name = spec.name
    check_inertias(parsed, model)
    if spec.legs is not None:
        floating = full_model(xml, pin.JointModelFreeFlyer())
        floating.name = spec.name
        floating.gravity.linear = np.asarray(spec.gravity, dtype=float)
        legged = build_legged(spec, parsed, model, floating)
        return legged if spec.leg is None else legged.leg(spec.leg).robot
    if model.njoints == 1:
        raise ValueError("urdf: no moving joint left (every joint is fixed or locked)")
    problem = serial_path_error(model)
    if problem is not None:
        raise ValueError(f"urdf: {problem}")
    n = model.njoints - 1
    if spec.tool_frame is not None:
        found = frame_id(model, spec.tool_frame)
        if found is None:
            raise ValueError(f"tool_frame: no frame named {spec.tool_frame!r} in the URDF")
        tool_src = found
    else:
        tool_src = leaf_frame(model, n)
    return serial_robot(spec, model, tool_src, meta={"locked_joints": values} if values else None)
