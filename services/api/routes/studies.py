"""``GET /studies``: the study kinds, their parameters, and which robots each accepts.

For every kind (built-in or registered by a plug-in, see docs/plugins.md): its parameter JSON
Schema and defaults (what ``problem`` of a job spec takes), the default robot, optimiser and
budget, what it needs from a robot in words, and for each catalog robot and each of the
caller's stored robots whether the study accepts it with its default task and, if not, which
field to change and why — the answer a job with that robot and the default task gets from
``POST /jobs`` (one function: :mod:`services.api.study_fits`).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query
from pydantic import BaseModel, Field, JsonValue

from legcore.robots import LeggedRobot, Robot, catalog
from legcore.studies.registry import needs_text, plugin_errors, studies
from legcore.studies.study import Study
from services.api.deps import Context, CurrentKey
from services.api.errors import invalid
from services.api.spec_cache import build_robot_cached
from services.api.study_fits import fit_of
from services.store import repository as repo

router = APIRouter(tags=["studies"])

#: Stored robots checked per request (the caller's first ones by name).
MAX_STORED_ROBOTS = 100


RobotOrigin = Literal["catalog", "stored"]


class RobotFit(BaseModel):
    """Whether a study accepts one robot with its default task (the answer ``POST /jobs``
    gives: :mod:`services.api.study_fits`)."""

    robot: str = Field(description="Catalog name, or the stored robot's name.")
    id: str = Field(description="What a job spec's `robot` takes: the catalog name or the id.")
    source: RobotOrigin
    accepted: bool
    field: str | None = Field(
        default=None,
        description="What to change when refused: `robot` (a missing capability) "
        "or the study parameter the pre-flight check names.",
    )
    reason: str | None = Field(
        description="Why the study refuses the robot (the missing capability, or why its default "
        "task cannot work on it and what to give instead)."
    )


class OptimizerDefault(BaseModel):
    """The optimiser a study runs when a job names none: its kind and the seed's settings."""

    kind: str
    params: dict[str, JsonValue] = Field(description="The optimiser's own parameters.")


class StudyOut(BaseModel):
    """One study kind."""

    kind: str
    title: str
    description: str
    seed_paper: str = Field(description="The seed paper whose settings are the defaults.")
    plugin: str | None = Field(description="The distribution that registered it (plug-ins).")
    robot_kinds: list[str] = Field(description="serial and/or legged")
    needs: list[str] = Field(description="What it needs from a robot: one line per alternative.")
    default_robot: str
    default_optimizer: OptimizerDefault
    default_generations: int
    # A JSON Schema document and a document it describes: each study's own, so any JSON.
    params_schema: dict[str, JsonValue] = Field(description="JSON Schema of the job's `problem`.")
    defaults: dict[str, JsonValue] = Field(description="`problem` with every default filled in.")
    robot_relative: list[str] = Field(
        default_factory=list,
        description="The parameters whose default is derived from the "
        "robot a job runs on (null in `defaults`; each job's result says the value and the rule).",
    )
    robots: list[RobotFit]


class StudiesOut(BaseModel):
    """``GET /studies``."""

    items: list[StudyOut]
    stored_robots_checked: int = Field(description="How many of your robots were checked.")
    stored_robots_total: int
    plugin_errors: dict[str, str] = Field(
        description="Plug-ins that could not be loaded (entry point -> error)."
    )


def _fit(study: Study, name: str, ident: str, source: RobotOrigin, robot: Any) -> RobotFit:
    if isinstance(robot, str):  # the robot could not be built
        return RobotFit(
            robot=name, id=ident, source=source, accepted=False, field="robot", reason=robot
        )
    v = fit_of(robot, study.kind)
    return RobotFit(
        robot=name,
        id=ident,
        source=source,
        accepted=v.accepted,
        field=v.field,
        reason=v.reason,
    )


def _stored(spec: Any) -> Robot | LeggedRobot | str:
    try:
        if isinstance(spec, dict) and "catalog" in spec:
            return catalog.get(str(spec["catalog"]))
        return build_robot_cached(spec)
    except Exception as exc:  # stored robots were validated; an upgrade may still refuse one
        return f"the robot cannot be built: {type(exc).__name__}: {exc}"


@router.get("/studies", response_model=StudiesOut, summary="Study kinds, parameters and robots")
def list_studies(
    key: CurrentKey,
    ctx: Context,
    kind: Annotated[str | None, Query(description="Only this study kind.", max_length=100)] = None,
    robots: Annotated[
        bool, Query(description="Check the catalog robots and yours against each kind.")
    ] = True,
) -> StudiesOut:
    """Every study kind (built-in and plug-ins) with its parameter schema and defaults, and for
    each catalog robot and each of your stored robots (your first 100 by name) whether it is
    accepted, with the reason when it is not."""
    known = studies()
    if kind is not None and kind not in known:
        raise invalid(("query", "kind"), f"unknown study {kind!r}; expected one of {sorted(known)}")
    chosen = [known[kind]] if kind is not None else list(known.values())
    candidates: list[tuple[str, str, RobotOrigin, Any]] = []
    checked = total = 0
    if robots:
        candidates = [(n, n, "catalog", catalog.get(n)) for n in catalog.names()]
        with ctx.read() as session:
            page = repo.list_robots(session, owner_key_id=key.id, limit=MAX_STORED_ROBOTS)
            records = [(r.name, r.id, r.spec) for r in page.items]
            total = page.total
        candidates += [(name, rid, "stored", _stored(spec)) for name, rid, spec in records]
        checked = len(records)
    items = [
        StudyOut(
            kind=s.kind,
            title=s.title,
            description=s.description,
            seed_paper=s.seed_paper,
            plugin=s.plugin,
            robot_kinds=list(s.robot_kinds),
            needs=needs_text(s),
            default_robot=s.default_robot,
            default_optimizer=OptimizerDefault.model_validate(s.default_optimizer),
            default_generations=s.default_generations,
            params_schema=s.params.model_json_schema(),
            defaults=s.params.model_validate({}).model_dump(mode="json"),
            robot_relative=list(s.robot_relative),
            robots=[_fit(s, *c) for c in candidates],
        )
        for s in chosen
    ]
    return StudiesOut(
        items=items,
        stored_robots_checked=checked,
        stored_robots_total=total,
        plugin_errors=plugin_errors(),
    )
