"""The store's bottom layer: row <-> record conversion, paging, and INSERTs that tolerate
duplicates. Every other store module builds on these; this one imports no other store module
but records, errors and types (so no import circle can pass through it).

All functions take the caller's ``Session`` and never commit.
"""

from __future__ import annotations

import copy
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import fields
from datetime import datetime
from typing import Any, TypeVar

from sqlalchemy import ColumnElement, Select, Table, func, insert, select
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from services.store.errors import ConflictError
from services.store.records import Page
from services.store.types import as_utc, utcnow

R = TypeVar("R")

MAX_PAGE_SIZE = 1000
#: A listing of jobs (``GET /jobs``, the jobs page) counts its matches up to this many, then
#: says "more than" (its ``total`` is ``COUNT_CAP + 1``, its ``total_exact`` false): a count
#: costs what every match costs — an exact one of 10^6 rows ~55 ms, more than the page — and a
#: search's count what its matches cost, so a frequent word stops costing more once 1 001 are
#: found. The jobs page's search also stops sorting its matches there (it walks its order).
COUNT_CAP = 1_000


def now_utc(now: datetime | None = None) -> datetime:
    """``now`` converted to UTC (must be timezone-aware), or the current UTC time."""
    return utcnow() if now is None else as_utc(now)


def to_record(cls: type[R], row: Mapping[Any, Any]) -> R:
    """Build the frozen record ``cls`` from a row mapping, deep-copying JSON values."""
    values = {}
    for f in fields(cls):  # type: ignore[arg-type]
        value = row[f.name]
        if isinstance(value, dict | list):
            value = copy.deepcopy(value)
        values[f.name] = value
    return cls(**values)


def fetch_one(session: Session, cls: type[R], stmt: Select[Any]) -> R | None:
    """First row of ``stmt`` as a record, or None."""
    row = session.execute(stmt).mappings().first()
    return None if row is None else to_record(cls, row)


def fetch_all(session: Session, cls: type[R], stmt: Select[Any]) -> tuple[R, ...]:
    """All rows of ``stmt`` as records."""
    return tuple(to_record(cls, row) for row in session.execute(stmt).mappings())


def rowcount(result: Any) -> int:
    """Rows matched by an UPDATE or DELETE result."""
    return int(result.rowcount)


def check_page(limit: int, offset: int) -> None:
    if not 1 <= limit <= MAX_PAGE_SIZE:
        raise ValueError(f"limit must be in [1, {MAX_PAGE_SIZE}], got {limit}")
    if offset < 0:
        raise ValueError(f"offset must be >= 0, got {offset}")


def fetch_page(
    session: Session,
    cls: type[R],
    stmt: Select[Any],
    order_by: Iterable[ColumnElement[Any]],
    limit: int,
    offset: int,
    *,
    count_cap: int | None = None,
) -> Page[R]:
    """One page of ``stmt`` (ordered by ``order_by``) with the total count of its rows; with
    ``count_cap``, counted up to ``count_cap + 1`` (that value then means "more than
    ``count_cap``"), so the count costs no more as the table grows."""
    check_page(limit, offset)
    total = capped_count(session, stmt, count_cap)
    items = fetch_all(session, cls, stmt.order_by(*order_by).limit(limit).offset(offset))
    return Page(items=items, total=int(total), limit=limit, offset=offset)


def capped_count(session: Session, stmt: Select[Any], cap: int | None) -> int:
    """The rows of ``stmt``, counted up to ``cap + 1`` (that value then means "more than
    ``cap``"; None: exactly): at most ``cap + 1`` index entries read at any table size."""
    counted = stmt if cap is None else stmt.limit(cap + 1)
    return int(session.execute(select(func.count()).select_from(counted.subquery())).scalar_one())


def insert_or_conflict(session: Session, table: Table, values: dict[str, Any], what: str) -> None:
    """INSERT one row inside a SAVEPOINT; a unique violation raises ``ConflictError``.

    The savepoint keeps the caller's transaction usable after the conflict.
    """
    try:
        with session.begin_nested():
            session.execute(insert(table).values(**values))
    except IntegrityError as exc:
        raise ConflictError(what) from exc


def insert_ignoring_duplicates(
    session: Session, table: Table, values: dict[str, Any], keys: Sequence[str]
) -> bool:
    """INSERT unless a row with the same ``keys`` exists; True if a row was inserted."""
    dialect = session.get_bind().dialect.name
    if dialect in ("sqlite", "postgresql"):
        module = sqlite if dialect == "sqlite" else postgresql
        stmt = (
            module.insert(table)
            .values(**values)
            .on_conflict_do_nothing(index_elements=keys)
            .returning(table.c[keys[0]])
        )
        return session.execute(stmt).first() is not None
    try:
        with session.begin_nested():
            session.execute(insert(table).values(**values))
    except IntegrityError:
        return False
    return True


def insert_many_ignoring_duplicates(
    session: Session, table: Table, rows: Sequence[dict[str, Any]], keys: Sequence[str]
) -> None:
    """INSERT ``rows`` in one statement (``ON CONFLICT DO NOTHING``: a row whose ``keys``
    exist is skipped) — one round trip for a batch instead of one per row; other dialects
    insert them one by one (:func:`insert_ignoring_duplicates`)."""
    if not rows:
        return
    dialect = session.get_bind().dialect.name
    if dialect in ("sqlite", "postgresql"):
        module = sqlite if dialect == "sqlite" else postgresql
        stmt = module.insert(table).on_conflict_do_nothing(index_elements=list(keys))
        session.execute(stmt, list(rows))
        return
    for row in rows:
        insert_ignoring_duplicates(session, table, row, keys)


__all__ = [
    "MAX_PAGE_SIZE",
    "capped_count",
    "fetch_all",
    "fetch_one",
    "fetch_page",
    "insert_ignoring_duplicates",
    "insert_many_ignoring_duplicates",
    "insert_or_conflict",
    "now_utc",
    "rowcount",
    "to_record",
]
