"""Reads of the web dashboard: a page of jobs filtered, sorted and searched in SQL, their
labels, hypervolumes and sweep members; the hypervolume reference point of a running job.

The jobs page must stay fast at 10^5 jobs per key, so nothing here walks a key's jobs in
Python. What a listing shows of a job's spec (study kind, robot, optimizer, name, seed, tags)
lives in ``job_labels``, one row per job written once by :func:`sync_labels` (a spec never
changes after submission). Every sortable column has an index ``(owner, column, created_at,
id)`` (``services.store.tables``), so every order pages by keyset (``cursor``) in O(page)
at any depth (the search by index and the keyset paging: ``job_search_paging``); ``offset``
still works, in O(offset).

Like ``services.store.repository``: every function takes the ``Session`` first and never
commits.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from datetime import timedelta
from typing import Any, Literal

from sqlalchemy import ColumnElement, FromClause, Select, func, insert, literal, select
from sqlalchemy.orm import Session

from services.store.job_search_paging import (
    _JOB_SORTS,
    _count,
    _fts_driven,
    _fts_query,
    _id_driven,
    _id_words,
    _keyset_rows,
    _like,
    _Order,
    _row_value,
    _rows_by_id,
    _search_fts,
    _search_words,
    encode_cursor,
    unindexed_search,
)
from services.store.records import JobRecord
from services.store.search_index import MIN_INDEXED_WORD
from services.store.sql import COUNT_CAP
from services.store.states import JobStatus
from services.store.tables import JOB_LABELS, JOBS, SWEEPS

#: Jobs created this long before the newest labelled one are checked again for a label (a
#: transaction that committed late); PostgreSQL commits a job within ms of its created_at.
LABEL_SLACK = timedelta(seconds=60)

SortKey = Literal["created", "finished", "status", "kind", "robot", "optimizer", "progress", "best"]
SORT_KEYS: tuple[str, ...] = (
    "created", "finished", "status", "kind", "robot", "optimizer", "progress", "best",
)  # fmt: skip


# --------------------------------------------------------------------------- labels


#: A study kind's default robot and optimizer kind, or None for a kind nobody knows. The
#: store knows no study: the caller (the API, from the study registry) hands this in.
StudyDefaults = Callable[[str], "tuple[str, str] | None"]


def label_values(
    base: Any, overrides: Mapping[str, Any] | None, defaults: StudyDefaults
) -> dict[str, Any]:
    """The labels of a job whose spec is ``base`` with ``overrides`` applied: ``kind``,
    ``robot`` (catalog or robot name; the study's default robot when none), ``optimizer``
    (the study's default when none), ``name``, ``seed`` and ``tags`` (comma-joined);
    ``defaults(kind)`` gives the study's default robot and optimizer."""
    from services.store.specs import spec_value

    kind = str(spec_value(base, overrides, "problem.kind") or "")
    default_robot, default_optimizer = defaults(kind) or ("", "")
    robot = spec_value(base, overrides, "robot")
    if isinstance(robot, dict):
        robot = robot.get("name") or robot.get("catalog") or "inline"
    if robot is None:
        robot = default_robot
    optimizer = spec_value(base, overrides, "optimizer.kind")
    if optimizer is None:
        optimizer = default_optimizer
    name = spec_value(base, overrides, "name")
    seed = spec_value(base, overrides, "seed")
    tags = spec_value(base, overrides, "tags")
    tag_list = [str(t) for t in tags] if isinstance(tags, list) else []
    return {
        "kind": kind[:64],
        "robot": str(robot)[:200],
        "optimizer": str(optimizer)[:32],
        "name": None if name is None else str(name)[:200],
        "seed": int(seed) if isinstance(seed, int) else 0,
        "tags": ",".join(tag_list),
    }


def _search_text(job_id: str, sweep_id: str | None, labels: Mapping[str, Any]) -> str:
    parts = [labels.get("name") or "", labels["kind"], labels["robot"], labels["optimizer"],
             labels["tags"], f"seed={labels['seed']}", job_id, sweep_id or ""]  # fmt: skip
    return " ".join(p for p in parts if p).lower()


def sync_labels(
    session: Session, owner_key_id: str, defaults: StudyDefaults, *, full: bool = False
) -> int:
    """Write the missing ``job_labels`` rows of a key's jobs; the number written
    (``defaults``: as for :func:`label_values`).

    Only jobs created since the newest labelled one (less ``LABEL_SLACK``) are looked at, so
    the cost is that of the new jobs, not of all of them; ``full`` checks every job (after an
    upgrade from a database without labels, the first call is full anyway)."""
    newest = session.execute(
        select(func.max(JOB_LABELS.c.created_at)).where(JOB_LABELS.c.owner_key_id == owner_key_id)
    ).scalar_one_or_none()
    stmt = (
        select(JOBS.c.id, JOBS.c.sweep_id, JOBS.c.spec, JOBS.c.overrides, JOBS.c.created_at)
        .outerjoin(JOB_LABELS, JOB_LABELS.c.job_id == JOBS.c.id)
        .where(JOBS.c.owner_key_id == owner_key_id, JOB_LABELS.c.job_id.is_(None))
    )
    if newest is not None and not full:
        stmt = stmt.where(JOBS.c.created_at >= newest - LABEL_SLACK)
    missing = session.execute(stmt).all()
    if not missing:
        return 0
    sweep_ids = {r.sweep_id for r in missing if r.spec is None and r.sweep_id is not None}
    bases: dict[str, Any] = {}
    if sweep_ids:
        rows = session.execute(
            select(SWEEPS.c.id, SWEEPS.c.base_spec).where(SWEEPS.c.id.in_(sweep_ids))
        )
        bases = {r[0]: r[1] for r in rows}
    values = []
    for r in missing:
        base = r.spec if r.spec is not None else bases.get(r.sweep_id or "", {})
        labels = label_values(base, None if r.spec is not None else r.overrides, defaults)
        values.append(
            {
                "job_id": r.id,
                "owner_key_id": owner_key_id,
                "created_at": r.created_at,
                **labels,
                "search": _search_text(r.id, r.sweep_id, labels),
            }
        )
    for start in range(0, len(values), 500):
        session.execute(insert(JOB_LABELS), values[start : start + 500])
    return len(values)


def missing_labels(session: Session, owner_key_id: str) -> bool:
    """True if :func:`sync_labels` has something to write (a cheap read first, so listings
    take the write lock only when jobs were added)."""
    newest = session.execute(
        select(func.max(JOB_LABELS.c.created_at)).where(JOB_LABELS.c.owner_key_id == owner_key_id)
    ).scalar_one_or_none()
    stmt = (
        select(JOBS.c.id)
        .outerjoin(JOB_LABELS, JOB_LABELS.c.job_id == JOBS.c.id)
        .where(JOBS.c.owner_key_id == owner_key_id, JOB_LABELS.c.job_id.is_(None))
    )
    if newest is not None:
        stmt = stmt.where(JOBS.c.created_at >= newest - LABEL_SLACK)
    return session.execute(stmt.limit(1)).first() is not None


# --------------------------------------------------------------------------- the jobs page


@dataclass(frozen=True)
class JobFilter:
    """What a jobs page shows: statuses, study kind, optimizer, robot (exact), sweep, tag, a
    free-text ``search`` (matched, case-insensitively, against name, kind, robot, optimizer,
    tags, seed, job and sweep ids) and the verdict (``feasible`` True / False: succeeded jobs
    whose optimum was found feasible / infeasible; None: any)."""

    status: tuple[JobStatus, ...] = ()
    kind: str | None = None
    optimizer: str | None = None
    robot: str | None = None
    sweep_id: str | None = None
    tag: str | None = None
    search: str | None = None
    feasible: bool | None = None


@dataclass(frozen=True)
class JobRow:
    """One line of the jobs page: the job and its labels."""

    job: JobRecord
    name: str | None
    kind: str
    robot: str
    optimizer: str
    seed: int
    tags: tuple[str, ...]


@dataclass(frozen=True)
class JobRowPage:
    """A page of jobs: the rows, how many match (``total_exact`` False: at least ``total``,
    the count stopped at ``COUNT_CAP + 1``; or not counted, -1), and the keyset cursor of
    the next page (None on the last page)."""

    items: tuple[JobRow, ...]
    total: int
    limit: int
    offset: int
    next_cursor: str | None
    total_exact: bool = True


def _label_filtered(f: JobFilter) -> bool:
    """True when a filter needs the labels (then they drive the query), False when the jobs
    table's own indexes answer it (status, sweep, or none)."""
    return bool(f.kind or f.optimizer or f.robot or f.tag or f.search)


def _conditions(
    owner_key_id: str, f: JobFilter, by_labels: bool, indexed: bool = False
) -> list[ColumnElement[bool]]:
    """The WHERE of a filter; ``indexed``: the search's long words are matched by the FTS
    table (``_fts_driven``), only the short ones here."""
    owner = JOB_LABELS.c.owner_key_id if by_labels else JOBS.c.owner_key_id
    c: list[ColumnElement[bool]] = [owner == owner_key_id]
    if f.status:
        c.append(JOBS.c.status.in_(list(f.status)))
    if f.kind:
        c.append(JOB_LABELS.c.kind == f.kind)
    if f.optimizer:
        c.append(JOB_LABELS.c.optimizer == f.optimizer)
    if f.robot:
        c.append(JOB_LABELS.c.robot == f.robot)
    if f.sweep_id:
        c.append(JOBS.c.sweep_id == f.sweep_id)
    if f.feasible is not None:
        c.append(JOBS.c.feasible == bool(f.feasible))
    if f.tag:
        tags = literal(",") + JOB_LABELS.c.tags + literal(",")
        c.append(tags.like(_like(f",{f.tag},"), escape="\\"))
    for word in _search_words(f.search):
        if not (indexed and len(word) >= MIN_INDEXED_WORD):
            # the pattern inline, not a parameter: PostgreSQL then plans each search for its
            # words (the trigram index for a rare one, the page's order for a frequent one),
            # never a generic plan that would read the index for a word it cannot answer
            pattern = literal(_like(word), literal_execute=True)
            c.append(JOB_LABELS.c.search.like(pattern, escape="\\"))
    return c


def list_job_rows(
    session: Session,
    owner_key_id: str,
    f: JobFilter = JobFilter(),  # noqa: B008 - frozen
    *,
    sort: str = "created",
    descending: bool = True,
    limit: int = 50,
    offset: int = 0,
    cursor: str | None = None,
    count: bool = True,
    search_index: bool = True,
) -> JobRowPage:
    """A page of a key's jobs (labels synced first by the caller: :func:`sync_labels`).

    Filters on labels (kind, optimizer, robot, tag, search) walk the labels' indexes; status
    and sweep filters alone walk the jobs table's ``(owner, status, created_at)`` and
    ``(owner, created_at)`` indexes. Every order is ``(sort column, created_at, id)``, NULLs
    last; ``cursor`` (a page's ``next_cursor``, same sort and order) continues after the last
    row of the previous page in O(limit) whatever the depth; ``offset`` pages by counting
    (O(offset)). ``total`` counts at most ``COUNT_CAP + 1`` matches (``total_exact``
    False when it stopped there; ``count`` False: not at all, -1; the export streams pages
    without it). A search reads its index and a word shaped like an id the primary key (see
    "word search by index" in ``job_search_paging``); ``search_index`` False matches every
    word by LIKE instead (the reference of the tests and the benchmark: the same rows, but
    that an id word finds ids, not a name or tag containing one)."""
    if sort not in SORT_KEYS:
        raise ValueError(f"sort: expected one of {', '.join(SORT_KEYS)}, got {sort!r}")
    by_labels = _label_filtered(f) or sort in ("kind", "robot", "optimizer")
    # conditions on both tables
    mixed = by_labels and bool(f.status or f.sweep_id or f.feasible is not None)
    labels = [JOB_LABELS.c[c] for c in ("name", "kind", "robot", "optimizer", "seed", "tags")]
    total = -1
    stmt: Select[Any] | None = None
    keys_first = False  # stmt selects the page's ids: its rows are read after the sort
    words = _search_words(f.search) if search_index else []
    driven = _driven_by_index(session, owner_key_id, f, by_labels, words)
    if driven is not None:
        by_id = bool(_id_words(words))
        n = -1
        if count or not by_id:
            n = _count(session, *driven(mixed), COUNT_CAP)
            total = n if count else -1
        # an id's rows are few (a sweep's at most): always sorted; a word in more jobs than
        # the cap: walk the page's order (LIKE), below
        if by_id or n <= COUNT_CAP:
            source, where = driven(mixed or sort in _JOB_SORTS)
            stmt = select(JOB_LABELS.c.job_id.label("id")).select_from(source).where(*where)
            keys_first = True
    if stmt is None:
        conditions = _conditions(owner_key_id, f, by_labels)
        joined = (
            JOB_LABELS.join(JOBS, JOBS.c.id == JOB_LABELS.c.job_id)
            if by_labels
            else JOBS.join(JOB_LABELS, JOB_LABELS.c.job_id == JOBS.c.id)
        )
        stmt = select(JOBS, *labels).select_from(joined).where(*conditions)
        if count and total < 0:
            source = joined if mixed else JOB_LABELS if by_labels else JOBS
            total = _count(session, source, conditions, COUNT_CAP)
    order = _Order(sort, descending, by_labels)
    if cursor is not None or offset == 0:  # one more row than asked: is there a next page?
        rows = _keyset_rows(session, stmt, order, limit + 1, cursor)
        offset = 0
    else:
        page = stmt.order_by(*order.order_by(nulls_last=True)).limit(limit + 1).offset(offset)
        rows = list(session.execute(page).mappings())
    if keys_first:
        rows = _rows_by_id(session, [r["id"] for r in rows], labels)
    more, rows = len(rows) > limit, rows[:limit]
    items = tuple(
        JobRow(
            job=_job_record(r),
            name=r["name"],
            kind=r["kind"],
            robot=r["robot"],
            optimizer=r["optimizer"],
            seed=int(r["seed"]),
            tags=tuple(t for t in (r["tags"] or "").split(",") if t),
        )
        for r in rows
    )
    next_cursor = None
    if more:
        last = rows[-1]
        next_cursor = encode_cursor(sort, _row_value(last, sort), last["created_at"], last["id"])
    exact = 0 <= total <= COUNT_CAP
    return JobRowPage(items, total, limit, offset, next_cursor, total_exact=exact)


#: ``driven(mixed)``: the FROM clause a search's index drives (with the jobs table when
#: ``mixed``) and its WHERE.
_Driven = Callable[[bool], "tuple[FromClause, list[ColumnElement[bool]]]"]


def _driven_by_index(
    session: Session, owner_key_id: str, f: JobFilter, by_labels: bool, words: list[str]
) -> _Driven | None:
    """How a search's index drives the query: from the jobs of an id word (every store), else
    from the FTS matches of its long words (SQLite with the FTS table); None: by LIKE."""
    ids = _id_words(words)
    if ids:  # every word is checked by LIKE on the few rows the id finds
        conditions = _conditions(owner_key_id, f, by_labels)
        return lambda mixed: (_id_driven(ids[0], mixed), conditions)
    fts = _fts_query(words)
    if fts is None or not _search_fts(session):
        return None
    conditions = _conditions(owner_key_id, f, by_labels, indexed=True)

    def by_fts(mixed: bool) -> tuple[FromClause, list[ColumnElement[bool]]]:
        source, match = _fts_driven(fts, mixed)
        return source, [match, *conditions]

    return by_fts


def _job_record(row: Any) -> JobRecord:
    from services.store.sql import to_record

    return to_record(JobRecord, row)


__all__ = [
    "COUNT_CAP",
    "LABEL_SLACK",
    "SORT_KEYS",
    "JobFilter",
    "JobRow",
    "JobRowPage",
    "StudyDefaults",
    "label_values",
    "list_job_rows",
    "missing_labels",
    "sync_labels",
    "unindexed_search",
]
