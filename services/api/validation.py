"""Validation of the job specs users send before anything is stored (robot documents:
``services.api.robot_validation``).

Every check is legcore's own (``parse_robot_spec``/``build_any_robot``, ``parse_job_spec``,
``prepare``, ``job_size``) plus the settings' size limits; this module only resolves robot
references and turns legcore's errors into 422s located at the offending field (see
``services.api.errors``). Nothing here touches the database: stored robots are looked up through
the ``RobotLookup`` callable the route passes in.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Callable, Iterable, MutableMapping, Sequence
from dataclasses import dataclass
from typing import Any

from fastapi.exceptions import RequestValidationError
from pydantic import ValidationError

from legcore.jobspec import JobSpec, parse_job_spec, spec_error_locations
from legcore.robots import LeggedRobot, Robot, catalog
from legcore.runner import JobSize, Prepared, job_size, prepare
from legcore.studies.registry import plugin_errors
from services.api.errors import (
    Loc,
    clean_pydantic_errors,
    field_error,
    invalid,
    split_field_message,
    validation_error,
)
from services.api.robot_validation import build_inline_robot
from services.api.spec_cache import BuiltRobot, SpecCache, problem_builder
from services.store.settings import Settings

log = logging.getLogger("legopt.api")

#: ``lookup(reference)`` -> the robot document a stored robot stands for (a catalog name or an
#: inline spec mapping), or None when the caller has no robot with that id or name.
RobotLookup = Callable[[str], "str | dict[str, Any] | None"]

JOB_FIELDS = frozenset(JobSpec.model_fields)


# --------------------------------------------------------------------------- job specs


@dataclass(frozen=True)
class CheckedJob:
    """A job spec that passed every check: the document to store, its size and what the check
    learned of it (``job_facts``: stored with the job, so nothing re-derives it)."""

    spec: dict[str, Any]
    total_generations: int
    size: JobSize
    facts: dict[str, Any]


def job_facts(prepared: Prepared) -> dict[str, Any]:
    """What a prepared job is, in plain data: study ``kind``, ``robot`` (its name),
    ``optimizer`` (kind; the study's default filled in), ``objectives`` (names, minimised, in
    the front's column order) and ``n_var`` (decision variables)."""
    return {
        "kind": prepared.spec.problem.kind,
        "robot": str(prepared.robot.name),
        "optimizer": prepared.algorithm.kind,
        "objectives": [str(n) for n in prepared.problem.objective_names],
        "n_var": int(prepared.problem.n_var),
    }


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


def stored_references(docs: Iterable[Any], lookup: RobotLookup) -> dict[str, Any]:
    """``{reference: document or None}`` for every ``robot`` of ``docs`` that names no
    catalog robot (a stored robot's id or name), each looked up once: ``table.get`` then
    resolves them as ``lookup`` would, without the database (see ``resolve_robot``)."""
    known = set(catalog.names())
    table: dict[str, Any] = {}
    for doc in docs:
        robot = doc.get("robot") if isinstance(doc, dict) else None
        if isinstance(robot, str) and robot not in known and robot not in table:
            table[robot] = lookup(robot)
    return table


def _job_errors(exc: ValidationError, doc: dict[str, Any], prefix: Loc) -> list[dict[str, Any]]:
    """Pydantic errors of a job spec, without the study kind pydantic puts in ``problem``
    locations (``problem.swing_energy.obstacle`` -> ``problem.obstacle``)."""
    locs = [loc for loc, _ in spec_error_locations(exc, doc)]
    errors = clean_pydantic_errors(exc, prefix, locs=locs)
    problem = doc.get("problem")
    kind = problem.get("kind") if isinstance(problem, dict) else None
    broken = plugin_errors().get(kind) if isinstance(kind, str) else None
    if broken is not None:  # not an unknown kind: its plug-in is installed but did not load
        for err in errors:
            if err.get("type") == "union_tag_invalid":
                err["msg"] = (
                    f"study kind {kind!r} comes from a plug-in that was not loaded ({broken}); "
                    "fix or reinstall the plug-in and restart the service "
                    "(GET /api/v1/studies lists plug-in errors)"
                )
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


def _memory_error(
    reason: str, size: JobSize, doc: dict[str, Any], prefix: Loc
) -> RequestValidationError:
    """A job whose predicted peak memory exceeds the per-worker limit: one error on the
    population parameter and one on the problem (its samples per trajectory), both naming the
    two fields, the predicted MiB and the limit."""
    pop_loc = _size_loc("population", doc, prefix)
    field = ".".join(str(p) for p in pop_loc[len(prefix) :])
    if field == "optimizer.params":
        field = "optimizer.params.pop_size"
    msg = (
        f"job too large: {reason}; it grows with the population ({field} = {size.population}) "
        f"times the samples per trajectory (problem: {size.samples} samples, e.g. problem.dt "
        "or problem.n_samples): lower one of them"
    )
    return validation_error(
        [field_error(pop_loc, msg, "job_too_large"), field_error((*prefix, "problem"), msg,
                                                                 "job_too_large")]
    )


#: Top-level fields of a job spec validated once per distinct content within a request.
_MODEL_FIELDS = ("problem", "optimizer")


def check_job_spec(
    doc: Any,
    *,
    settings: Settings,
    lookup: RobotLookup,
    prefix: Loc = ("body",),
    cache: MutableMapping[str, Any] | None = None,
) -> CheckedJob:
    """Validate a job spec document exactly as the worker will run it, before storing it.

    Steps: resolve the robot reference (stored robots by id or name), build an inline robot,
    ``parse_job_spec``, prepare (robot + problem + algorithm + termination, as
    ``legcore.runner.prepare``), ``job_size`` against the settings' limits. Any failure is a
    ``RequestValidationError`` located under ``prefix``.

    ``cache`` (one mapping per request, shared by the jobs of a sweep) makes the request cost
    O(its size) rather than O(jobs × size) — see ``services.api.spec_cache``: each distinct
    robot document is built once, each distinct ``problem`` / ``optimizer`` validated once, each
    distinct (robot, problem) study problem built once, and job sizes computed once per
    distinct (robot, problem, optimizer, budget); failures are remembered the same way.
    """
    if not isinstance(doc, dict):
        raise invalid(prefix, "a job spec must be a JSON object", "dict_type")
    memo = SpecCache.attach(cache if cache is not None else {}, repr(prefix))
    doc = resolve_robot(doc, memo.memo_lookup(lookup), prefix)
    light = dict(doc)  # the document to validate, with already-validated parts substituted

    robot_doc = doc.get("robot")
    built: Robot | LeggedRobot | None = None
    if isinstance(robot_doc, dict):
        rkey = memo.key(robot_doc)
        entry = memo.robots.get(rkey)
        if entry is None:
            urdf = robot_doc.get("urdf")
            memo.charge(len(urdf) if isinstance(urdf, str) else 0, (*prefix, "robot"))
            try:
                memo.count("robot_builds")
                entry = BuiltRobot(*build_inline_robot(robot_doc, (*prefix, "robot")))
            except RequestValidationError as exc:
                entry = list(exc.errors())
            memo.robots[rkey] = entry
        if isinstance(entry, list):
            raise validation_error(entry)
        doc = {**doc, "robot": entry.document}
        light["robot"] = entry.robot.spec
        built = entry.robot
    else:
        rkey = "ref:" + json.dumps(robot_doc)

    keys = {f: memo.key(doc[f]) for f in _MODEL_FIELDS if isinstance(doc.get(f), dict)}
    for f, key in keys.items():
        if (f, key) in memo.failures:
            raise validation_error(memo.failures[(f, key)])
        if (f, key) in memo.models:
            light[f] = memo.models[(f, key)]
    spec = _parse(light, doc, prefix, keys, memo)

    pkey = keys.get("problem", "none")
    size_key = (rkey, pkey, keys.get("optimizer", "none"), memo.key(doc.get("budget")))
    found = memo.sizes.get(size_key)
    if found is None:
        if (rkey, pkey) not in memo.problems:
            csv = getattr(spec.problem, "csv", None)
            memo.charge(len(csv) if isinstance(csv, str) else 0, (*prefix, "problem"))
        try:
            memo.count("prepares")
            found = _prepare_and_size(spec, doc, prefix, built, memo.problems, (rkey, pkey))
        except RequestValidationError as exc:
            found = list(exc.errors())
        memo.sizes[size_key] = found
    if isinstance(found, list):
        raise validation_error(found)
    total, size, facts = found

    reason = settings.check_job_size(
        size.population, size.generations, size.samples, size.peak_bytes
    )
    if reason is not None and reason.startswith("memory"):
        raise _memory_error(reason, size, doc, prefix)
    if reason is not None:
        raise invalid(_size_loc(reason, doc, prefix), f"job too large: {reason}", "job_too_large")
    return CheckedJob(spec=doc, total_generations=total, size=size, facts=facts)


def _parse(
    light: dict[str, Any],
    doc: dict[str, Any],
    prefix: Loc,
    keys: dict[str, str],
    memo: SpecCache,
) -> JobSpec:
    """``parse_job_spec(light)``; remembers the validated ``problem`` / ``optimizer`` models
    (and the errors of a bad one) under their content keys."""
    try:
        spec = parse_job_spec(light)
    except ValidationError as exc:
        errors = _job_errors(exc, doc, prefix)
        for f, key in keys.items():
            mine = [e for e in errors if e["loc"][len(prefix) : len(prefix) + 1] == [f]]
            if mine:
                memo.failures[(f, key)] = mine
        raise validation_error(errors) from None
    except ArithmeticError as exc:  # a validator overflowing (e.g. T / dt with dt = 1e-320)
        log.warning("job spec validation overflowed: %r", exc)
        raise invalid(
            (*prefix, "problem"),
            f"a number is out of range ({type(exc).__name__}: {exc}): a step, resolution or "
            "duration too close to 0 or too large; use values of a physical size",
        ) from None
    for f, key in keys.items():
        memo.models[(f, key)] = getattr(spec, f)
    return spec


def _prepare_and_size(
    spec: JobSpec,
    doc: dict[str, Any],
    prefix: Loc,
    robot: Robot | LeggedRobot | None,
    problems: dict[tuple[str, str], Any],
    problem_key: tuple[str, str],
) -> tuple[int, JobSize, dict[str, Any]]:
    """``legcore.runner.prepare`` + ``job_size`` (+ ``job_facts``) reusing an already built
    robot and study problem; errors as 422s located under ``prefix``."""
    try:
        prepared = prepare(spec, robot=robot, build_problem=problem_builder(problems, problem_key))
        size = job_size(prepared)
        facts = job_facts(prepared)
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
    return (int(total) if total is not None else int(size.generations)), size, facts


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
    from legcore.studies.registry import studies

    return {kind: {"problem": {"kind": kind}} for kind in sorted(studies())}


__all__: Sequence[str] = [
    "CheckedJob",
    "job_facts",
    "RobotLookup",
    "check_job_spec",
    "example_specs",
    "resolve_robot",
    "stored_references",
]
