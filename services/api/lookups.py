"""What the routes share: the caller's job, sweep or robot by id (404 when missing or another
key's; the job of the path also as the FastAPI dependency ``OwnedJob``), an index of the path
(a front point's, a trial's), the jobs page's filters (a FastAPI dependency), a sweep's cell
table and writing the labels of a key's new jobs. Routes import these from here, never from
one another."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any

from fastapi import Depends, HTTPException, Query, status
from sqlalchemy.orm import Session

from services.api.deps import ApiContext, Context, CurrentKey
from services.api.errors import invalid, not_found
from services.api.quantities import describe
from services.api.sweep_cells import CellTable, build_cells
from services.api.sweeps import swept_paths
from services.api.validation import RobotLookup
from services.store import dashboard_queries as dq
from services.store import output_queries as oq
from services.store import repository as repo
from services.store.records import JobRecord, SweepRecord
from services.store.specs import shown_value, spec_value
from services.store.states import JobStatus


def owned_job(session: Session, job_id: str, owner_key_id: str) -> JobRecord:
    """The caller's job ``job_id``; 404 when missing or another key's."""
    job = repo.get_job(session, job_id, owner_key_id=owner_key_id)
    if job is None:
        raise not_found("job", job_id)
    return job


def path_job(job_id: str, key: CurrentKey, ctx: Context) -> JobRecord:
    """The caller's job of the path's ``job_id``, read in a transaction of its own; 404 when
    missing or another key's (``owned_job``)."""
    with ctx.read() as session:
        return owned_job(session, job_id, key.id)


#: The caller's job of the path's ``job_id`` (its frozen record), for a route that needs
#: nothing else from the database in the same transaction; 404 when missing or another key's.
OwnedJob = Annotated[JobRecord, Depends(path_job)]


def path_index(job: JobRecord, text: str, what: str) -> int:
    """The index ``text`` of the path (read as text: a job of another key is a 404 whatever it
    is) as an int: ASCII digits only, at most 9 of them (a Unicode digit such as '²' passes
    ``str.isdigit()`` and breaks ``int()``); else 404 ``job <id> has no <what> '<text>'``."""
    if not (text.isascii() and text.isdigit()) or len(text) > 9:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"job {job.id} has no {what} {text!r}")
    return int(text)


def owned_sweep_jobs(
    session: Session, key_id: str, sweep_id: str
) -> tuple[SweepRecord, list[JobRecord]]:
    sweep = repo.get_sweep(session, sweep_id, owner_key_id=key_id)
    if sweep is None:
        raise not_found("sweep", sweep_id)
    return sweep, list(repo.sweep_jobs(session, sweep.id, owner_key_id=key_id))


@dataclass(frozen=True)
class SweepCells:
    """A sweep, its jobs (sweep order), the succeeded ones' result briefs and final fronts,
    its study kind and its cells."""

    sweep: SweepRecord
    jobs: list[JobRecord]
    results: dict[str, tuple[Any, Any]]
    fronts: dict[str, Any]
    kind: str | None
    table: CellTable


def sweep_cells(ctx: ApiContext, key_id: str, sweep_id: str) -> SweepCells:
    """The caller's sweep ``sweep_id`` (404 when missing or another key's) and its cells
    (shared by the sweep page, the cells export and the sweep-jobs export)."""
    with ctx.read() as session:
        sweep, jobs = owned_sweep_jobs(session, key_id, sweep_id)
        done = [j.id for j in jobs if j.status is JobStatus.SUCCEEDED]
        results = oq.result_briefs(session, done)
        fronts = oq.fronts_of(session, done)
    axes = sweep.axes if isinstance(sweep.axes, dict) else {}
    swept = swept_paths(axes.get("grid"), axes.get("list"), axes.get("seeds"))

    def value(job: JobRecord, path: str) -> Any:
        return shown_value(job.spec or sweep.base_spec, job.overrides, path)

    kind = study_kind(sweep)
    table = build_cells(
        jobs, value, swept, results, fronts, sense=lambda n: describe(n, kind)["sense"]
    )
    return SweepCells(sweep, jobs, results, fronts, kind, table)


def cell_table(ctx: ApiContext, key_id: str, sweep_id: str) -> tuple[SweepRecord, CellTable]:
    """The sweep and its cells (the sweep page and the cells export)."""
    found = sweep_cells(ctx, key_id, sweep_id)
    return found.sweep, found.table


def study_kind(sweep: SweepRecord) -> str | None:
    """The study kind of a sweep's base spec."""
    return spec_value(sweep.base_spec, None, "problem.kind")


def robot_lookup(session: Session, owner_key_id: str) -> RobotLookup:
    """Resolve a job's ``robot`` reference among the caller's stored robots (id, then name)
    into the document it stands for: a catalog name or an inline spec."""

    def lookup(reference: str) -> str | dict[str, Any] | None:
        record = repo.get_robot(session, reference, owner_key_id=owner_key_id)
        if record is None:
            record = repo.get_robot_by_name(session, owner_key_id=owner_key_id, name=reference)
        if record is None:
            return None
        spec = record.spec
        if isinstance(spec, dict) and "catalog" in spec:
            return str(spec["catalog"])
        return dict(spec) if isinstance(spec, dict) else None

    return lookup


def study_defaults(kind: str) -> tuple[str, str] | None:
    """A study kind's default robot and optimizer kind (what a job's labels show when its spec
    names neither), from the study registry; None for an unknown kind."""
    from legcore.studies.registry import studies

    study = studies().get(kind)
    if study is None:
        return None
    return str(study.default_robot), str(study.default_optimizer.get("kind", ""))


def sync_labels(ctx: ApiContext, owner_key_id: str) -> None:
    """Write the labels of the key's new jobs (a read first: the write lock only when some are
    missing)."""
    with ctx.read() as session:
        missing = dq.missing_labels(session, owner_key_id)
    if missing:
        with ctx.write() as session:
            dq.sync_labels(session, owner_key_id, study_defaults)


#: The 422 of a search with no word an index answers.
SHORT_SEARCH = (
    "words of fewer than 3 characters are matched only next to a longer word (a trigram "
    "index answers words of 3 or more): add a longer word, or use the kind / optimizer / "
    "robot filters"
)


def job_filter(
    status_: Annotated[
        list[JobStatus] | None, Query(alias="status", description="Only these statuses.")
    ] = None,
    kind: Annotated[str | None, Query(max_length=64, description="Study kind.")] = None,
    optimizer: Annotated[str | None, Query(max_length=32, description="Optimizer kind.")] = None,
    robot: Annotated[str | None, Query(max_length=200, description="Robot name.")] = None,
    sweep_id: Annotated[str | None, Query(max_length=64, description="Only this sweep.")] = None,
    tag: Annotated[str | None, Query(max_length=100, description="Jobs with this tag.")] = None,
    q: Annotated[
        str | None,
        Query(
            max_length=200,
            description="Words matched in name, kind, robot, optimizer, tags, seed "
            "(`seed=3`), job and sweep ids (a word shaped like an id — a whole id, or its start "
            "through the first dash — finds the jobs whose id or sweep id starts with it). "
            "At least one word of 3 characters or more: shorter words are matched only next "
            "to a longer one (a 422 otherwise).",
        ),
    ] = None,  # fmt: skip
    feasible: Annotated[
        bool | None,
        Query(
            description="Only succeeded jobs whose optimum is feasible (true) / infeasible (false)."
        ),
    ] = None,  # fmt: skip
) -> dq.JobFilter:
    """The filters of the jobs page (query parameters). A search ``q`` whose words are all
    shorter than 3 characters is a 422 naming ``query.q``: no trigram index can answer it, so
    it would read every label of the key (0.6 s at 10^6 jobs). Refused on every store, even
    one without a search index (where every search scans), so that the API answers the same
    everywhere; the store itself still runs such a search (by LIKE)."""
    if dq.unindexed_search(q):
        raise invalid(("query", "q"), SHORT_SEARCH)
    return dq.JobFilter(
        status=tuple(status_ or ()),
        kind=kind or None,
        optimizer=optimizer or None,
        robot=robot or None,
        sweep_id=sweep_id or None,
        tag=tag or None,
        search=(q or "").strip() or None,
        feasible=feasible,
    )


Filters = Annotated[dq.JobFilter, Depends(job_filter)]


__all__ = [
    "Filters",
    "OwnedJob",
    "SweepCells",
    "cell_table",
    "sweep_cells",
    "job_filter",
    "owned_job",
    "owned_sweep_jobs",
    "path_index",
    "path_job",
    "robot_lookup",
    "study_defaults",
    "study_kind",
    "sync_labels",
]
