"""Validation of the robot documents users send (a catalog name or an inline model) before
anything is stored: legcore's own ``parse_robot_spec`` / ``build_any_robot``, its errors turned
into 422s located at the offending field (see ``services.api.errors``), and what a robot's
pages show of it (``summarize_robot``). Job specs: ``services.api.validation``.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from pydantic import ValidationError

from legcore.robots import LeggedRobot, Robot, build_any_robot, catalog, parse_robot_spec
from legcore.robots.capabilities import capabilities
from services.api.errors import Loc, from_pydantic, from_value_error, invalid

log = logging.getLogger("legopt.api")


@dataclass(frozen=True)
class RobotSummary:
    """What a built robot model looks like: kind, DOF, joints, legs, total mass."""

    name: str
    kind: str  # "serial" | "legged"
    nq: int
    joint_names: tuple[str, ...]
    n_legs: int
    mass_kg: float
    electrical_motors: int


def _serial_mass(robot: Robot) -> float:
    return float(sum(inertia.mass for inertia in robot.model.inertias))


def summarize_robot(robot: Robot | LeggedRobot) -> RobotSummary:
    """Summary of a built model (serial chain or multi-legged robot)."""
    if isinstance(robot, LeggedRobot):
        joints = tuple(
            f"{leg.name}.{name}" for leg in robot.legs for name in list(leg.robot.model.names)[1:]
        )
        return RobotSummary(
            name=robot.name,
            kind="legged",
            nq=sum(leg.robot.nq for leg in robot.legs),
            joint_names=joints,
            n_legs=robot.n_legs,
            mass_kg=float(robot.body_mass) + sum(_serial_mass(leg.robot) for leg in robot.legs),
            electrical_motors=sum(int(leg.robot.motors.electrical.sum()) for leg in robot.legs),
        )
    return RobotSummary(
        name=robot.name,
        kind="serial",
        nq=robot.nq,
        joint_names=tuple(list(robot.model.names)[1:]),
        n_legs=0,
        mass_kg=_serial_mass(robot),
        electrical_motors=int(robot.motors.electrical.sum()),
    )


def catalog_robot(name: Any, loc: Loc) -> Robot | LeggedRobot:
    """The catalog robot ``name``; 422 at ``loc`` naming the known entries otherwise."""
    names = catalog.names()
    if not isinstance(name, str) or name not in names:
        raise invalid(loc, f"unknown catalog robot {name!r}; known: {', '.join(names)}")
    return catalog.get(name)


def build_inline_robot(spec: Any, loc: Loc) -> tuple[dict[str, Any], Robot | LeggedRobot]:
    """Validate and BUILD an inline DH/URDF spec; returns ``(document, robot)``.

    The document is the user's mapping with its ``kind`` made explicit. A spec failing the
    field rules or the physical ones (inertia, limits, URDF) is a 422 located under ``loc``,
    e.g. ``loc + ("joints", 1, "inertia")``.
    """
    if not isinstance(spec, dict):
        raise invalid(loc, "must be an object: a DH or URDF robot spec", "dict_type")
    try:
        parsed = parse_robot_spec(spec)
        robot = build_any_robot(parsed)
    except ValidationError as exc:
        raise from_pydantic(exc, loc) from None
    except ValueError as exc:
        raise from_value_error(exc, loc) from None
    except Exception as exc:  # pinocchio on input nobody anticipated: still the user's model
        log.warning("robot build failed unexpectedly: %r", exc)
        raise invalid(loc, f"the model cannot be built: {type(exc).__name__}: {exc}") from None
    return {"kind": parsed.kind, **spec}, robot


@dataclass(frozen=True)
class RobotInfo:
    """What the API answers about a validated robot, as plain (picklable) data: computed where
    the model was built (a validation process, see ``services.api.validation_pool``)."""

    source: str  # "catalog" | "dh" | "urdf"
    spec: dict[str, Any]  # the document to store: {"catalog": name} or the inline spec
    inline_spec: dict[str, Any] | None  # the spec the model was built from, as JSON
    summary: RobotSummary
    capabilities: dict[str, Any]  # legcore's ``Capabilities.as_dict()``


def robot_info(source: str, spec: dict[str, Any], robot: Robot | LeggedRobot) -> RobotInfo:
    """Summary, capabilities and inline spec of a built model (None for a catalog legged
    robot, which has no single spec)."""
    inline = robot.spec.model_dump(mode="json") if robot.spec is not None else None
    caps = capabilities(robot).as_dict()
    return RobotInfo(source, spec, inline, summarize_robot(robot), caps)


def check_robot_doc(catalog_name: str | None, spec: Any) -> RobotInfo:
    """Validate and build the robot of ``POST /robots`` (and ``/robots/validate``): the
    catalog entry ``catalog_name``, else the inline ``spec``; 422 at ``body.catalog`` /
    ``body.spec`` (and below) otherwise."""
    if catalog_name is not None:
        robot = catalog_robot(catalog_name, ("body", "catalog"))
        return robot_info("catalog", {"catalog": catalog_name}, robot)
    doc, built = build_inline_robot(spec, ("body", "spec"))
    return robot_info(str(doc["kind"]), doc, built)


__all__: Sequence[str] = [
    "RobotInfo",
    "RobotSummary",
    "build_inline_robot",
    "catalog_robot",
    "check_robot_doc",
    "robot_info",
    "summarize_robot",
]
