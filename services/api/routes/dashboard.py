"""The dashboard's listings: the jobs page (filter, sort, search, paging in SQL), the choices
of its filters, and a robot's joints, limits, masses and the study kinds that accept it."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter, HTTPException, Query
from fastapi.concurrency import run_in_threadpool

from legcore.robots import LeggedRobot, Robot, catalog
from services.api.dashboard_schemas import (
    Choice,
    DashboardOptions,
    JobRowOut,
    JobRowPage,
    JointOut,
    RobotView,
    StudyFit,
)
from services.api.deps import MAX_OFFSET, Context, CurrentKey
from services.api.errors import VALIDATION_ERROR_SCHEMA, invalid, not_found
from services.api.lookups import Filters, sync_labels
from services.api.robot_validation import summarize_robot
from services.api.schemas import DEFAULT_LIMIT, MAX_LIMIT, ErrorOut
from services.api.spec_cache import build_robot_cached
from services.api.study_fits import robot_fits
from services.store import dashboard_queries as dq
from services.store import repository as repo
from services.store.states import JobStatus

router = APIRouter(tags=["dashboard"])

OPTIMIZERS = ("ga", "hka", "moead", "nsga2")


@router.get(
    "/dashboard/jobs",
    response_model=JobRowPage,
    summary="The jobs page: your jobs filtered, sorted and searched",
    responses={
        422: {
            "description": "A bad query: e.g. a search `q` of only words shorter than 3 "
            "characters (`query.q`), a cursor of another order (`query.cursor`).",
            "content": {"application/json": {"schema": VALIDATION_ERROR_SCHEMA}},
        },
    },
)
def dashboard_jobs(
    key: CurrentKey,
    ctx: Context,
    filters: Filters,
    sort: Annotated[
        Literal["created", "finished", "status", "kind", "robot", "optimizer", "progress", "best"],
        Query(description="Column to sort by."),
    ] = "created",
    order: Annotated[Literal["asc", "desc"], Query()] = "desc",
    limit: Annotated[int, Query(ge=1, le=MAX_LIMIT)] = DEFAULT_LIMIT,
    offset: Annotated[int, Query(ge=0, le=MAX_OFFSET)] = 0,
    cursor: Annotated[
        str | None,
        Query(
            max_length=300,
            description="`next_cursor` of the previous page (same sort and order).",
        ),
    ] = None,
) -> JobRowPage:
    """Study kind, robot, optimizer, status, the verdict of a succeeded job (`feasible`,
    `violations`), progress, best value so far, times and tags of each job. Everything is
    filtered, sorted and paged in the database (indexed), so a page costs about the same at
    10^5 jobs as at 10. Every order is the column, then newest first
    (NULLs last); pass `cursor` (the previous page's `next_cursor`) to page by keyset at any
    depth, or `offset` (which costs more the deeper it goes). `total` is counted up to 1 001
    (`total_exact` says whether it stopped there). A search `q` of only words shorter than 3
    characters is a 422 (`query.q`): no index answers it."""
    sync_labels(ctx, key.id)
    with ctx.read() as session:
        try:
            page = dq.list_job_rows(
                session, key.id, filters, sort=sort, descending=order == "desc",
                limit=limit, offset=offset, cursor=cursor,
            )  # fmt: skip
        except ValueError as exc:
            raise invalid(("query", "cursor"), str(exc)) from None
    return JobRowPage(
        items=[JobRowOut.from_row(r) for r in page.items],
        total=page.total,
        total_exact=page.total_exact,
        limit=page.limit,
        offset=page.offset,
        next_cursor=page.next_cursor,
    )


@router.get(
    "/dashboard/options",
    response_model=DashboardOptions,
    summary="What the jobs page's filters offer",
)
def dashboard_options(key: CurrentKey) -> DashboardOptions:
    """Study kinds (with their titles), optimizers, statuses and sort columns."""
    from legcore.studies.registry import studies

    return DashboardOptions(
        kinds=[Choice(value=k, label=s.title) for k, s in sorted(studies().items())],
        optimizers=[Choice(value=o, label=o.upper()) for o in OPTIMIZERS],
        statuses=[s.value for s in JobStatus],
        sorts=list(dq.SORT_KEYS),
    )


# --------------------------------------------------------------------------- robots


def _finite(v: Any) -> float | None:
    f = float(v)
    return f if f == f and abs(f) != float("inf") and abs(f) < 1e300 else None


def _joints(robot: Robot, leg: str | None = None) -> list[JointOut]:
    names = list(robot.model.names)[1:]
    return [
        JointOut(
            name=name,
            leg=leg,
            lower=_finite(robot.q_min[i]),
            upper=_finite(robot.q_max[i]),
            velocity=_finite(robot.qd_max[i]),
            acceleration=_finite(robot.qdd_max[i]),
            effort=_finite(robot.tau_max[i]),
            link_mass_kg=_finite(robot.chain.mass[i]) if i < robot.chain.n else None,
        )
        for i, name in enumerate(names)
    ]


def study_fits(robot: Robot | LeggedRobot) -> list[StudyFit]:
    """Each study kind, and whether it accepts ``robot`` with its default task — the answer
    ``POST /jobs`` gives (:mod:`services.api.study_fits`), with the reason when not."""
    return [StudyFit(kind=f.kind, title=f.title, accepts=f.accepted, field=f.field,
                     reason=f.reason, rules=f.rules, preset=f.preset)
            for f in robot_fits(robot)]


def _robot_view(ident: str, name: str, robot: Robot | LeggedRobot) -> RobotView:
    s = summarize_robot(robot)
    if isinstance(robot, LeggedRobot):
        joints = [j for leg in robot.legs for j in _joints(leg.robot, leg.name)]
        legs = [leg.name for leg in robot.legs]
    else:
        joints, legs = _joints(robot), []
    return RobotView(
        id=ident, name=name, kind=s.kind, nq=s.nq, mass_kg=s.mass_kg, legs=legs,
        joints=joints, studies=study_fits(robot),
    )  # fmt: skip


@router.get(
    "/dashboard/robots/{robot_id}",
    response_model=RobotView,
    summary="A robot's joints, limits, masses and the study kinds that accept it",
    responses={
        404: {"model": ErrorOut, "description": "No such robot (among yours)."},
        409: {"model": ErrorOut, "description": "Your stored robot cannot be built any more."},
    },
)
async def dashboard_robot(robot_id: str, key: CurrentKey, ctx: Context) -> RobotView:
    """Your robot ``robot_id`` or a catalog robot: per joint its position limits (rad or m),
    velocity and effort limits and the mass of the link it moves (kg); per study kind whether
    it accepts the robot with its default parameters, and why not."""
    if robot_id in catalog.names():
        robot = catalog.get(robot_id)
        return await run_in_threadpool(_robot_view, robot_id, robot_id, robot)

    def stored() -> RobotView:
        with ctx.read() as session:
            record = repo.get_robot(session, robot_id, owner_key_id=key.id)
        if record is None:
            raise not_found("robot", robot_id)
        spec = record.spec if isinstance(record.spec, dict) else {}
        if "catalog" in spec:
            built: Robot | LeggedRobot = catalog.get(str(spec["catalog"]))
        else:
            try:
                built = build_robot_cached(spec)
            except ValueError as exc:
                raise HTTPException(409, f"robot {record.name!r} cannot be built: {exc}") from None
        return _robot_view(record.id, record.name, built)

    return await run_in_threadpool(stored)
