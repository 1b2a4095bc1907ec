"""Robot models: store (validated and built), list, read, validate; the seed catalog."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query, Response, status
from pydantic import BaseModel, Field

from legcore.robots import LeggedRobot, Robot, catalog
from services.api.deps import Context, CurrentKey, Pagination
from services.api.errors import invalid, not_found
from services.api.robot_validation import RobotInfo, robot_info, summarize_robot
from services.api.schemas import (
    CatalogEntry,
    ErrorOut,
    Page,
    RobotCreate,
    RobotDetail,
    RobotOut,
    RobotSummaryOut,
    RobotValidate,
    RobotValidation,
)
from services.api.spec_cache import build_robot_cached
from services.api.study_fits import StudyFitOut, robot_fits
from services.api.submission import (
    IdempotencyKey,
    Replay,
    check_replay,
    remember,
    replay_headers,
)
from services.api.validation_pool import check_robot
from services.store import repository as repo
from services.store.idempotency import request_fingerprint
from services.store.records import RobotRecord

router = APIRouter(tags=["robots"])


class LegOut(BaseModel):
    """One leg of a legged robot."""

    name: str
    n_joints: int
    joint_names: list[str]
    foot_frame: str = Field(description="The URDF frame (link) the leg ends at.")
    hip: list[float] = Field(description="Hip joint origin in the body frame, m.")


class CapabilitiesOut(BaseModel):
    """What the robot offers a study (a study refuses a robot by naming a missing one)."""

    kind: Literal["serial", "legged"]
    serial_chain: bool = Field(description="One serial chain (an arm, or one leg).")
    n_actuated: int = Field(description="Moving joints (all legs together).")
    joint_names: list[str]
    end_frame: str | None = Field(description="The chain's tool/foot frame (serial robots).")
    legs: list[LegOut]
    ik_family: str | None = Field(description="Closed-form IK that applies, if any.")
    electrical: bool = Field(description="Kt, Ke and R on every joint: electrical energy.")
    electrical_joints: int
    torque_limits: bool = Field(description="A finite torque limit on every joint.")
    prismatic: int = Field(description="Number of prismatic joints.")
    floating_base: bool = Field(description="The whole robot's model has a free-flyer root.")

    @classmethod
    def of(cls, caps: dict[str, Any]) -> CapabilitiesOut:
        """From legcore's ``Capabilities.as_dict()`` (``RobotInfo.capabilities``)."""
        return cls.model_validate({k: v for k, v in caps.items() if k != "name"})


class RobotDetailOut(RobotDetail):
    """A robot with its spec, the summary of its built model and its capabilities; from
    ``GET /robots/{id}`` also whether each study kind accepts it."""

    capabilities: CapabilitiesOut
    studies: list[StudyFitOut] | None = Field(
        default=None, description="Per study kind: accepted with its default task (and the rules "
        "that task was derived by), or the field to change and why — the answer `POST /jobs` "
        "gives. Listed by `GET /robots/{id}` (null in the answers of create)."
    )


class RobotValidationOut(RobotValidation):
    """``POST /robots/validate``: the model was validated and built; what it offers."""

    capabilities: CapabilitiesOut


_404: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorOut, "description": "No such robot (among yours)."}
}


def _out(record: RobotRecord) -> RobotOut:
    spec = record.spec if isinstance(record.spec, dict) else {}
    return RobotOut(
        id=record.id,
        name=record.name,
        source=record.source_kind.value,
        catalog=spec.get("catalog"),
        created_at=record.created_at,
    )


def _detail(base: RobotOut, info: RobotInfo) -> RobotDetailOut:
    """A robot's detail from its ``RobotInfo`` (plain data: what a validation process, or
    this process for a stored robot, found building it)."""
    return RobotDetailOut(
        **base.model_dump(),
        spec=info.spec,
        inline_spec=info.inline_spec,
        summary=RobotSummaryOut.from_summary(info.summary),
        capabilities=CapabilitiesOut.of(info.capabilities),
    )


def _catalog_out(name: str) -> RobotOut:
    return RobotOut(id=name, name=name, source="catalog", catalog=name, builtin=True)


def _stored_model(spec: dict[str, Any]) -> Robot | LeggedRobot:
    """The model of a stored robot (a catalog entry or an inline spec, built once per process
    for the last few distinct documents)."""
    return catalog.get(spec["catalog"]) if "catalog" in spec else build_robot_cached(spec)


@router.post(
    "/robots",
    status_code=status.HTTP_201_CREATED,
    response_model=RobotDetailOut,
    summary="Store a robot model (validated and built first)",
    responses={409: {"model": ErrorOut, "description": "You already have a robot of this name."}},
)
def create_robot(
    body: RobotCreate,
    key: CurrentKey,
    ctx: Context,
    response: Response,
    idempotency_key: IdempotencyKey = None,
) -> RobotDetailOut:
    """Validate and build the model (a non-physical model is a 422 naming the field), then
    store it. Job specs can then use its id (or name) as ``robot``. Send an
    ``Idempotency-Key`` header to make retries safe: the same key returns the robot the first
    request stored (not a 409 for its name)."""
    if body.name in catalog.names():
        raise invalid(("body", "name"), f"{body.name!r} is a catalog robot's name; choose another")
    fingerprint = request_fingerprint(body.model_dump(mode="json"))
    try:
        with ctx.read() as session:
            check_replay(session, key, idempotency_key, fingerprint, "robot")
        info = check_robot(body.catalog, body.spec, settings=ctx.settings, key_id=key.id)
        with ctx.write() as session:
            check_replay(session, key, idempotency_key, fingerprint, "robot")
            record = repo.create_robot(
                session, owner_key_id=key.id, name=body.name, source_kind=info.source,
                spec=info.spec,
            )  # fmt: skip
            remember(session, key, idempotency_key, fingerprint, "robot", record.id)
    except Replay as replay:
        response.headers.update(replay_headers())
        response.headers["Location"] = f"{ctx.prefix}/robots/{replay.record.resource_id}"
        return get_robot(replay.record.resource_id, key, ctx)
    response.headers["Location"] = f"{ctx.prefix}/robots/{record.id}"
    return _detail(_out(record), info)


@router.post(
    "/robots/validate",
    response_model=RobotValidationOut,
    summary="Validate and build a robot model without storing it",
)
def validate_robot(body: RobotValidate, key: CurrentKey, ctx: Context) -> RobotValidationOut:
    """200 with a summary of the built model and its capabilities, or 422 naming the field."""
    info = check_robot(body.catalog, body.spec, settings=ctx.settings, key_id=key.id)
    return RobotValidationOut(
        source=info.source,  # type: ignore[arg-type]
        summary=RobotSummaryOut.from_summary(info.summary),
        capabilities=CapabilitiesOut.of(info.capabilities),
    )


@router.get("/robots", response_model=Page[RobotOut], summary="List your robots")
def list_robots(
    key: CurrentKey,
    ctx: Context,
    page: Pagination,
    include_catalog: Annotated[
        bool, Query(description="List the catalog robots first (their id is their name).")
    ] = False,
) -> Page[RobotOut]:
    """Your stored robots by name; with ``include_catalog`` the catalog entries come first."""
    builtin = [_catalog_out(n) for n in catalog.names()] if include_catalog else []
    items = builtin[page.offset : page.offset + page.limit]
    stored_offset = max(0, page.offset - len(builtin))
    stored_limit = page.limit - len(items)
    with ctx.read() as session:
        stored = repo.list_robots(
            session, owner_key_id=key.id, limit=max(1, stored_limit), offset=stored_offset
        )
    if stored_limit > 0:
        items += [_out(r) for r in stored.items]
    return Page[RobotOut](
        items=items, total=len(builtin) + stored.total, limit=page.limit, offset=page.offset
    )


@router.get(
    "/robots/{robot_id}",
    response_model=RobotDetailOut,
    summary="One robot (yours, or a catalog name) with its spec and model summary",
    responses=_404,
)
def get_robot(robot_id: str, key: CurrentKey, ctx: Context) -> RobotDetailOut:
    """Your robot ``robot_id``, or the catalog robot of that name, with its capabilities and
    whether each study kind accepts it with its default task (``studies``)."""
    if robot_id in catalog.names():
        base, spec = _catalog_out(robot_id), {"catalog": robot_id}
    else:
        with ctx.read() as session:
            record = repo.get_robot(session, robot_id, owner_key_id=key.id)
        if record is None:
            raise not_found("robot", robot_id)
        base, spec = _out(record), record.spec
    robot = _stored_model(spec)
    out = _detail(base, robot_info(base.source, spec, robot))
    return out.model_copy(update={"studies": robot_fits(robot)})


@router.delete(
    "/robots/{robot_id}",
    status_code=204,
    summary="Delete one of your stored robots",
    responses=_404,
)
def delete_robot(robot_id: str, key: CurrentKey, ctx: Context) -> Response:
    """Removes your stored robot ``robot_id`` (catalog robots cannot be deleted). Jobs that ran
    it are unaffected: a job keeps the robot document it ran, by content."""
    with ctx.write() as session:
        deleted = repo.delete_robot(session, robot_id, owner_key_id=key.id)
    if not deleted:
        raise not_found("robot", robot_id)
    return Response(status_code=204)


@router.get(
    "/catalog",
    response_model=list[CatalogEntry],
    summary="The catalog of the seed papers' robots",
)
def list_catalog(key: CurrentKey) -> list[CatalogEntry]:
    """Every catalog robot with its DOF and provenance (seed paper, tables, assumed values)."""
    out = []
    for name in catalog.names():
        s = summarize_robot(catalog.get(name))
        out.append(
            CatalogEntry(
                name=name,
                kind=s.kind,  # type: ignore[arg-type]
                nq=s.nq,
                n_legs=s.n_legs,
                joint_names=list(s.joint_names),
                source=catalog.source(name),
            )
        )
    return out
