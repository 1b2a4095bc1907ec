"""Validation of the documents users send (robot models, job specs) before anything is stored.

Every check is legcore's own (``parse_robot_spec``/``build_robot``, ``parse_job_spec``,
``prepare``, ``job_size``) plus the settings' size limits; this module only resolves robot
references and turns legcore's errors into 422s located at the offending field (see
``services.api.errors``). Nothing here touches the database: stored robots are looked up through
the ``RobotLookup`` callable the route passes in.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Callable, MutableMapping, Sequence
from dataclasses import dataclass
from typing import Any

from pydantic import ValidationError

from legcore.jobspec import JobSpec, parse_job_spec, spec_error_locations
from legcore.robots import LeggedRobot, Robot, build_robot, catalog, parse_robot_spec
from legcore.runner import JobSize, job_size, prepare
from services.api.errors import (
    Loc,
    clean_pydantic_errors,
    from_pydantic,
    from_value_error,
    invalid,
    split_field_message,
    validation_error,
)
from services.store.settings import Settings

log = logging.getLogger("legopt.api")

#: ``lookup(reference)`` -> the robot document a stored robot stands for (a catalog name or an
#: inline spec mapping), or None when the caller has no robot with that id or name.
RobotLookup = Callable[[str], "str | dict[str, Any] | None"]

JOB_FIELDS = frozenset(JobSpec.model_fields)


# --------------------------------------------------------------------------- robots


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


def build_inline_robot(spec: Any, loc: Loc) -> tuple[dict[str, Any], Robot]:
    """Validate and BUILD an inline DH/URDF spec; returns ``(document, robot)``.

    The document is the user's mapping with its ``kind`` made explicit. A spec failing the
    field rules or the physical ones (inertia, limits, URDF) is a 422 located under ``loc``,
    e.g. ``loc + ("joints", 1, "inertia")``.
    """
    if not isinstance(spec, dict):
        raise invalid(loc, "must be an object: a DH or URDF robot spec", "dict_type")
    try:
        parsed = parse_robot_spec(spec)
        robot = build_robot(parsed)
    except ValidationError as exc:
        raise from_pydantic(exc, loc) from None
    except ValueError as exc:
        raise from_value_error(exc, loc) from None
    except Exception as exc:  # pinocchio on input nobody anticipated: still the user's model
        log.warning("robot build failed unexpectedly: %r", exc)
        raise invalid(loc, f"the model cannot be built: {type(exc).__name__}: {exc}") from None
    return {"kind": parsed.kind, **spec}, robot


# --------------------------------------------------------------------------- job specs


@dataclass(frozen=True)
class CheckedJob:
    """A job spec that passed every check: the document to store and its size."""

    spec: dict[str, Any]
    total_generations: int
    size: JobSize


def resolve_robot(doc: dict[str, Any], lookup: RobotLookup, prefix: Loc) -> dict[str, Any]:
    """``doc`` with ``robot`` resolved: a stored robot's id or name becomes its document (a
    catalog name or an inline spec); catalog names, inline specs and ``None`` stay as they are.

    An unknown reference, a robot of the wrong type or a bad inline spec is a 422 at
    ``prefix + ("robot", ...)``.
    """
    loc = (*prefix, "robot")
    robot = doc.get("robot")
    if robot is None:
        return doc
    if isinstance(robot, str):
        if robot in catalog.names():
            return doc
        stored = lookup(robot)
        if stored is None:
            raise invalid(
                loc,
                f"unknown robot {robot!r}: neither a catalog robot "
                f"({', '.join(catalog.names())}) nor the id or name of one of your robots",
            )
        return {**doc, "robot": stored}
    if isinstance(robot, dict):
        return doc
    raise invalid(
        loc,
        "must be a catalog name, the id of a stored robot, or an inline robot spec (object)",
        "robot_type",
    )


def _job_errors(exc: ValidationError, doc: dict[str, Any], prefix: Loc) -> list[dict[str, Any]]:
    """Pydantic errors of a job spec, without the study kind pydantic puts in ``problem``
    locations (``problem.swing_energy.obstacle`` -> ``problem.obstacle``)."""
    errors = clean_pydantic_errors(exc, prefix)
    n = len(prefix)
    for err, (loc, _) in zip(errors, spec_error_locations(exc, doc), strict=True):
        err["loc"] = [*err["loc"][:n], *loc]
    return errors


_POPULATION_PARAMS = ("pop_size", "n_samples", "n_subproblems")


def _size_loc(reason: str, doc: dict[str, Any], prefix: Loc) -> Loc:
    """Which field to blame for a refused job size (see ``Settings.check_job_size``)."""
    if reason.startswith("population x"):
        return (*prefix, "budget")
    if reason.startswith("population"):
        optimizer = doc.get("optimizer")
        params = optimizer.get("params") if isinstance(optimizer, dict) else None
        given = [k for k in _POPULATION_PARAMS if isinstance(params, dict) and k in params]
        return (*prefix, "optimizer", "params", *given[:1])
    if reason.startswith("generations"):
        return (*prefix, "budget", "generations")
    if reason.startswith("samples"):
        return (*prefix, "problem")
    return (*prefix, "budget")


def _cache_key(doc: dict[str, Any]) -> str | None:
    """Key of the expensive part (prepare + size): the spec without seed and name."""
    try:
        rest = {k: v for k, v in doc.items() if k not in ("seed", "name")}
        return json.dumps(rest, sort_keys=True, allow_nan=False)
    except (TypeError, ValueError):
        return None


def check_job_spec(
    doc: Any,
    *,
    settings: Settings,
    lookup: RobotLookup,
    prefix: Loc = ("body",),
    cache: MutableMapping[str, tuple[int, JobSize]] | None = None,
) -> CheckedJob:
    """Validate a job spec document exactly as the worker will run it, before storing it.

    Steps: resolve the robot reference (stored robots by id or name), build an inline robot,
    ``parse_job_spec``, ``prepare`` (robot + problem + algorithm), ``job_size`` against the
    settings' limits. Any failure is a ``RequestValidationError`` located under ``prefix``.
    ``cache`` (shared across the jobs of one sweep) skips ``prepare`` for specs that differ
    only in seed or name.
    """
    if not isinstance(doc, dict):
        raise invalid(prefix, "a job spec must be a JSON object", "dict_type")
    doc = resolve_robot(doc, lookup, prefix)
    if isinstance(doc.get("robot"), dict):
        doc = {**doc, "robot": build_inline_robot(doc["robot"], (*prefix, "robot"))[0]}
    try:
        spec = parse_job_spec(doc)
    except ValidationError as exc:
        raise validation_error(_job_errors(exc, doc, prefix)) from None

    key = _cache_key(doc) if cache is not None else None
    if cache is not None and key is not None and key in cache:
        total, size = cache[key]
    else:
        total, size = _prepare_and_size(spec, doc, prefix)
        if cache is not None and key is not None:
            cache[key] = (total, size)

    reason = settings.check_job_size(size.population, size.generations, size.samples)
    if reason is not None:
        raise invalid(_size_loc(reason, doc, prefix), f"job too large: {reason}", "job_too_large")
    return CheckedJob(spec=doc, total_generations=total, size=size)


def _prepare_and_size(spec: JobSpec, doc: dict[str, Any], prefix: Loc) -> tuple[int, JobSize]:
    try:
        prepared = prepare(spec)
        size = job_size(prepared)
    except ValidationError as exc:
        raise validation_error(_job_errors(exc, doc, prefix)) from None
    except ValueError as exc:
        raise _prepare_error(exc, prefix) from None
    except Exception as exc:  # a study rejecting input in a way nobody anticipated
        log.warning("prepare failed unexpectedly", exc_info=True)
        raise invalid(
            (*prefix, "problem"), f"the job cannot be prepared: {type(exc).__name__}: {exc}"
        ) from None
    total = prepared.total_generations
    return (int(total) if total is not None else int(size.generations)), size


def _prepare_error(exc: ValueError, prefix: Loc) -> Exception:
    """A ``prepare`` ValueError: a message naming a job field (``robot: ...``) stays there,
    one naming a study parameter (``obstacle: ...``) is located under ``problem``."""
    sub, reason = split_field_message(str(exc))
    if not sub:
        return invalid((*prefix, "problem"), str(exc))
    if sub[0] in JOB_FIELDS:
        return invalid((*prefix, *sub), reason)
    return invalid((*prefix, "problem", *sub), reason)


def example_specs() -> dict[str, dict[str, Any]]:
    """One minimal job spec per available study kind (each study's defaults)."""
    from legcore.problems.registry import studies

    return {kind: {"problem": {"kind": kind}} for kind in sorted(studies())}


__all__: Sequence[str] = [
    "CheckedJob",
    "RobotLookup",
    "RobotSummary",
    "build_inline_robot",
    "catalog_robot",
    "check_job_spec",
    "example_specs",
    "resolve_robot",
    "summarize_robot",
]
