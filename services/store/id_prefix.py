"""A filter on an id column by prefix, on the primary key's index (``legopt status 2253``).

Ids are lowercase UUID strings (``services.store.tables.new_id``). A prefix is turned into the
closed range of every UUID that starts with it — the prefix completed with ``0`` and with
``f`` in the UUID's shape (``2253`` → ``22530000-0000-…`` .. ``2253ffff-ffff-…``) — so the
database answers it with a range scan of the id's B-tree in any collation (hex digits sort the
same way in all of them, and every id has its dashes at the same places), plus a ``LIKE
'prefix%'`` on the few rows of that range. A prefix no UUID can start with (a letter beyond
``f``, a dash out of place, too long) matches nothing.

The owner of the rows is then a filter on the rows of that range (``owned_with_prefix``),
written so that no index of the owner's drives the query instead — SQLite would otherwise walk
every job of the owner (30 ms at 5·10⁴ jobs) rather than the few of the range (PostgreSQL
takes the primary key's range either way).
"""

from __future__ import annotations

from sqlalchemy import ColumnElement, Table, and_, false

__all__ = ["UUID_SHAPE", "id_prefix_condition", "id_prefix_range", "owned_with_prefix"]

#: Where a UUID's dashes are (``x`` = one hex digit).
UUID_SHAPE = "xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx"
_HEX = frozenset("0123456789abcdef")


def id_prefix_range(prefix: str) -> tuple[str, str] | None:
    """``(lowest, highest)`` UUID starting with ``prefix`` (case-insensitive), or None when no
    UUID can start with it."""
    p = prefix.lower()
    if len(p) > len(UUID_SHAPE):
        return None
    for ch, shape in zip(p, UUID_SHAPE, strict=False):
        if (shape == "-") != (ch == "-") or (shape == "x" and ch not in _HEX):
            return None
    rest = UUID_SHAPE[len(p) :]
    return p + rest.replace("x", "0"), p + rest.replace("x", "f")


def id_prefix_condition(column: ColumnElement[str], prefix: str) -> ColumnElement[bool]:
    """``column`` starts with ``prefix`` (case-insensitive), as an index range (a whole id:
    equal to it)."""
    bounds = id_prefix_range(prefix)
    if bounds is None:
        return false()
    low, high = bounds
    if len(prefix) == len(UUID_SHAPE):
        return column == low
    return and_(column >= low, column <= high, column.startswith(low[: len(prefix)]))


def owned_with_prefix(
    table: Table, owner_key_id: str | None, prefix: str
) -> list[ColumnElement[bool]]:
    """The conditions "owned by ``owner_key_id`` (when given) and id starts with ``prefix``",
    the id's range driving the query (the owner compared as ``owner || ''``, which no index
    answers)."""
    conditions = [id_prefix_condition(table.c.id, prefix)]
    if owner_key_id is not None:
        conditions.append(table.c.owner_key_id.concat("") == owner_key_id)
    return conditions
