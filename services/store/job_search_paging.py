"""How the jobs page (``services.store.dashboard_queries``) finds and pages its rows: the word
search by index (SQLite's FTS5 trigram table, PostgreSQL's pg_trgm index), the sort columns
and the keyset cursors, so a page is an index range scan at any depth.

Like ``services.store.repository``: every function takes the ``Session`` first and never
commits.
"""

from __future__ import annotations

import base64
import binascii
import itertools
import json
from datetime import datetime
from typing import Any

from sqlalchemy import (
    ColumnElement,
    FromClause,
    Select,
    column,
    literal,
    literal_column,
    or_,
    select,
    table,
    tuple_,
)
from sqlalchemy.ext.compiler import compiles
from sqlalchemy.orm import Session
from sqlalchemy.sql.compiler import SQLCompiler
from sqlalchemy.sql.selectable import Join

from services.store.id_prefix import id_prefix_condition, id_prefix_range
from services.store.search_index import MIN_INDEXED_WORD, SEARCH_FTS
from services.store.sql import capped_count
from services.store.states import JobStatus
from services.store.tables import JOB_LABELS, JOBS


def _like(text: str) -> str:
    """A LIKE pattern matching ``text`` anywhere (``%``, ``_`` and ``\\`` escaped)."""
    escaped = text.replace("\\", "\\\\").replace("%", "\\%").replace("_", "\\_")
    return f"%{escaped}%"


def _search_words(search: str | None) -> list[str]:
    """The words of a search (lower-cased, at most 8): a job matches when its text contains
    every one."""
    return [w.lower() for w in (search or "").split()[:8]]


def unindexed_search(search: str | None) -> bool:
    """True when a search has words and none of them is one an index answers: every word is
    shorter than ``MIN_INDEXED_WORD`` (no trigram in it), so on any store it would read every
    label of the key. Short words beside a longer one are fine: they are checked on its
    matches. (The API refuses such a search, 422; the store still runs it, by LIKE.)"""
    words = _search_words(search)
    return bool(words) and all(len(w) < MIN_INDEXED_WORD for w in words)


# ----------------------------------------------------------------- word search by index
# PostgreSQL answers the LIKE of each word from the pg_trgm GIN index (revision 0009): the query
# does not change. SQLite answers words of 3 characters or more from the FTS5 trigram table
# ``job_labels_fts`` (a phrase of a word matches where LIKE '%word%' does, the text and words
# being lower-cased); shorter words — which no trigram can answer — and stores without the
# table (SQLite without FTS5 / trigram) keep LIKE. The matches drive the query (``_CrossJoin``:
# SQLite's planner, without statistics, would otherwise walk the key's whole index and probe
# each row): counted up to COUNT_CAP + 1, then sorted by their keys alone and the
# page's rows read. A word in more of the key's jobs than the cap is frequent enough that
# walking the page's order and checking each row by LIKE finds a page sooner than sorting every
# match, so that page is read the old way.
#
# A word shaped like an id (``_id_words``: a job or sweep id, whole or its start through the
# first dash) is answered by the primary key's range and the sweep index's instead, on every
# store: its trigrams are those of ids, whose lists grow with the store, while the jobs whose id
# or sweep id starts with the word are found in O(1) (a sweep's jobs: O(sweep)). Within an id
# such a word can only stand at the start (its dash must meet the id's first dash), so this
# finds every job whose id or sweep id contains it; what it does not find is a job whose *name,
# robot or tags* contain another job's id — LIKE would (``search_index`` False still does).
# Every word is still checked by LIKE on the rows found, so it never finds more than LIKE.

_FTS = table(SEARCH_FTS, column("rowid"))
_HAS_FTS = "legopt_search_fts"  # key of the answer in a DBAPI connection's info


class _CrossJoin(Join):
    """``left CROSS JOIN right ON onclause``: SQLite keeps ``left`` as the outer loop."""

    inherit_cache = True


@compiles(_CrossJoin, "sqlite")
def _compile_cross_join(element: _CrossJoin, compiler: SQLCompiler, **kw: Any) -> str:
    kw.pop("asfrom", None)
    linter = kw.get("from_linter")
    if linter is not None:  # as SQLCompiler.visit_join: the two sides are joined
        linter.edges.update(
            itertools.product(element.left._from_objects, element.right._from_objects)
        )
    left = compiler.process(element.left, asfrom=True, **kw)
    right = compiler.process(element.right, asfrom=True, **kw)
    assert element.onclause is not None
    return f"{left} CROSS JOIN {right} ON {compiler.process(element.onclause, **kw)}"


def _search_fts(session: Session) -> bool:
    """True if this SQLite store has the FTS table of the search (asked once per connection)."""
    conn = session.connection()
    if conn.dialect.name != "sqlite":
        return False
    if _HAS_FTS not in conn.info:
        found = conn.exec_driver_sql(
            "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?", (SEARCH_FTS,)
        ).first()
        conn.info[_HAS_FTS] = found is not None
    return bool(conn.info[_HAS_FTS])


def _fts_query(words: list[str]) -> str | None:
    """The FTS5 query of the words an index can answer (each one a quoted phrase: every
    character literal), None when there is none."""
    long = [w for w in words if len(w) >= MIN_INDEXED_WORD]
    return " ".join('"' + w.replace('"', '""') + '"' for w in long) or None


def _fts_driven(query: str, mixed: bool) -> tuple[FromClause, ColumnElement[bool]]:
    """The FROM clause that walks the FTS matches first (then their labels by rowid, then
    their jobs when ``mixed``) and the MATCH condition."""
    rowid: ColumnElement[int] = literal_column(f"{JOB_LABELS.name}.rowid")
    source: FromClause = _CrossJoin(_FTS, JOB_LABELS, _FTS.c.rowid == rowid)
    if mixed:
        source = _CrossJoin(source, JOBS, JOBS.c.id == JOB_LABELS.c.job_id)
    return source, literal_column(SEARCH_FTS).match(query)


#: An id word has at least this many characters: 8 hex digits and the id's first dash (8 hex
#: digits alone — the short id — may as well be a date or a commit in a name: trigrams).
MIN_ID_WORD = 9


def _id_words(words: list[str]) -> list[str]:
    """The words of a search shaped like a job or sweep id (``services.store.tables.new_id``):
    a UUID, or its first ``MIN_ID_WORD`` characters or more, in the UUID's shape."""
    return [w for w in words if MIN_ID_WORD <= len(w) and id_prefix_range(w) is not None]


#: The jobs an id word finds (an alias: the query may join the jobs table again); made once,
#: its columns' proxies cost more to build than the query to run.
_BY_ID = JOBS.alias("by_id")


def _id_driven(word: str, mixed: bool) -> FromClause:
    """The FROM clause that walks the jobs whose id or sweep id starts with the id word ``word``
    first (ranges of the primary key and of the sweep index), then their labels (then their
    jobs again, when ``mixed``): O(1) at any store size, O(sweep) for a sweep's id."""
    found = _BY_ID
    hits = select(found.c.id).where(
        or_(id_prefix_condition(found.c.id, word), id_prefix_condition(found.c.sweep_id, word))
    )
    ids = hits.subquery("id_hits")
    source: FromClause = _CrossJoin(ids, JOB_LABELS, JOB_LABELS.c.job_id == ids.c.id)
    if mixed:
        source = _CrossJoin(source, JOBS, JOBS.c.id == JOB_LABELS.c.job_id)
    return source


def _count(
    session: Session, source: FromClause, where: list[ColumnElement[bool]], cap: int
) -> int:
    """The rows of ``source`` matching ``where``, counted up to ``cap + 1``."""
    return capped_count(session, select(literal(1)).select_from(source).where(*where), cap)


def _rows_by_id(session: Session, ids: list[str], labels: list[Any]) -> list[Any]:
    """The page rows (job and ``labels``) of ``ids``, in that order."""
    if not ids:
        return []
    joined = JOB_LABELS.join(JOBS, JOBS.c.id == JOB_LABELS.c.job_id)
    q = select(JOBS, *labels).select_from(joined).where(JOB_LABELS.c.job_id.in_(ids))
    found = {r["id"]: r for r in session.execute(q).mappings()}
    return [found[i] for i in ids if i in found]


# --------------------------------------------------------------------------- keyset paging


def _sort_column(sort: str, by_labels: bool) -> ColumnElement[Any]:
    """The column a sort key orders by (``created``: the table driving the query's own)."""
    created = JOB_LABELS.c.created_at if by_labels else JOBS.c.created_at
    return {
        "created": created,
        "finished": JOBS.c.finished_at,
        "status": JOBS.c.status,
        "kind": JOB_LABELS.c.kind,
        "robot": JOB_LABELS.c.robot,
        "optimizer": JOB_LABELS.c.optimizer,
        "progress": JOBS.c.progress_generation,
        "best": JOBS.c.best_value,
    }[sort]


#: Sort keys whose column is the jobs table's.
_JOB_SORTS = frozenset({"finished", "status", "progress", "best"})

#: Sort keys whose column can be NULL (a job not finished, no generation yet): NULLs come last
#: in either direction.
NULLABLE_SORTS = frozenset({"finished", "best"})


def encode_cursor(sort: str, value: Any, created_at: datetime, job_id: str) -> str:
    """The opaque keyset cursor after the job ``(value, created_at, job_id)`` of a ``sort``
    order (``value``: the job's sort column; unused for ``created``)."""
    if isinstance(value, datetime):
        value = value.isoformat()
    elif isinstance(value, JobStatus):
        value = value.value
    raw = json.dumps([sort, value, created_at.isoformat(), job_id]).encode()
    return base64.urlsafe_b64encode(raw).decode().rstrip("=")


def decode_cursor(cursor: str, sort: str = "created") -> tuple[Any, datetime, str]:
    """``(value, created_at, job_id)`` of a cursor of the ``sort`` order; ValueError when it is
    not one of ours or belongs to another order."""
    try:
        raw = base64.urlsafe_b64decode(cursor + "=" * (-len(cursor) % 4))
        of_sort, value, at, job_id = json.loads(raw)
        created = datetime.fromisoformat(at)
    except (ValueError, TypeError, binascii.Error, json.JSONDecodeError):
        raise ValueError("not a cursor of this listing: use next_cursor of a page") from None
    if of_sort != sort:
        raise ValueError(f"cursor of the sort {of_sort!r}, not {sort!r}: start again without it")
    if value is not None and sort == "finished":
        try:
            value = datetime.fromisoformat(str(value))
        except ValueError:
            raise ValueError("not a cursor of this listing: use next_cursor of a page") from None
    try:
        if sort == "status":
            value = JobStatus(value)
        elif sort in ("progress", "best") and value is not None:
            value = int(value) if sort == "progress" else float(value)
        elif sort in ("kind", "robot", "optimizer"):
            value = str(value)
    except (ValueError, TypeError):
        raise ValueError("not a cursor of this listing: use next_cursor of a page") from None
    return value, created, str(job_id)


def _row_value(row: Any, sort: str) -> Any:
    """The sort column's value of a result row (for the next page's cursor)."""
    if sort == "best":
        return row["best_value"]
    return {
        "created": None,
        "finished": row["finished_at"],
        "status": row["status"],
        "kind": row["kind"],
        "robot": row["robot"],
        "optimizer": row["optimizer"],
        "progress": row["progress_generation"],
    }[sort]


class _Order:
    """A page order: ``(column, created_at, id)`` all ascending or all descending (``created``:
    ``(created_at, id)``), NULLs of a nullable column last. Each column has an index ending
    in ``(created_at, id)``, so a keyset page is an index range scan at any depth."""

    def __init__(self, sort: str, descending: bool, by_labels: bool) -> None:
        self.sort = sort
        self.descending = descending
        self.column = _sort_column(sort, by_labels)
        self.created = JOB_LABELS.c.created_at if by_labels else JOBS.c.created_at
        self.ident = JOB_LABELS.c.job_id if by_labels else JOBS.c.id
        self.nullable = sort in NULLABLE_SORTS

    def keys(self, with_column: bool = True) -> list[ColumnElement[Any]]:
        cols: list[ColumnElement[Any]] = [self.created, self.ident]
        return [self.column, *cols] if with_column and self.sort != "created" else cols

    def order_by(self, with_column: bool = True, nulls_last: bool = False) -> list[Any]:
        out: list[Any] = []
        for c in self.keys(with_column):
            o = c.desc() if self.descending else c.asc()
            out.append(o.nulls_last() if nulls_last and c is self.column else o)
        return out

    def after(self, values: list[Any], with_column: bool = True) -> ColumnElement[bool]:
        """Rows after ``values`` (the keys of the previous page's last row) in this order."""
        cols = self.keys(with_column)
        typed = [literal(v, type_=c.type) for c, v in zip(cols, values, strict=True)]
        left, right = tuple_(*cols), tuple_(*typed)
        return left < right if self.descending else left > right


def _keyset_rows(
    session: Session, stmt: Select[Any], order: _Order, limit: int, cursor: str | None
) -> list[Any]:
    """A page after ``cursor`` (or the first page) by index range scans: for a nullable
    column, first the rows with a value, then (when the page is not full) those without."""
    value, at, last = decode_cursor(cursor, order.sort) if cursor else (None, None, None)
    if not order.nullable:
        keys = [at, last] if order.sort == "created" else [value, at, last]
        q = stmt if cursor is None else stmt.where(order.after(keys))
        return list(session.execute(q.order_by(*order.order_by()).limit(limit)).mappings())
    rows: list[Any] = []
    if cursor is None or value is not None:
        q = stmt.where(order.column.is_not(None))
        if cursor is not None:
            q = q.where(order.after([value, at, last]))
        rows = list(session.execute(q.order_by(*order.order_by()).limit(limit)).mappings())
    if len(rows) < limit:
        q = stmt.where(order.column.is_(None))
        if cursor is not None and value is None:
            q = q.where(order.after([at, last], with_column=False))
        q = q.order_by(*order.order_by(with_column=False)).limit(limit - len(rows))
        rows += list(session.execute(q).mappings())
    return rows


__all__ = [
    "MIN_ID_WORD",
    "NULLABLE_SORTS",
    "decode_cursor",
    "encode_cursor",
    "unindexed_search",
]
