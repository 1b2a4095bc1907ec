"""The store's API keys: create, read, revoke, delete (the raw key never; its hash from
:func:`services.store.keys.hash_api_key`).

Like :mod:`services.store.repository`: the ``Session`` first, never a commit (wrap calls in
``session_scope()``), frozen records back (:class:`~services.store.records.ApiKeyRecord`).
"""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import delete, select, update
from sqlalchemy.orm import Session

from services.store.records import ApiKeyRecord, Page
from services.store.sql import fetch_one, fetch_page, insert_or_conflict, now_utc, rowcount
from services.store.states import KeyRole
from services.store.tables import API_KEYS, new_id
from services.store.types import as_utc

__all__ = [
    "create_api_key",
    "delete_api_key",
    "get_api_key",
    "get_api_key_by_hash",
    "list_api_keys",
    "revoke_api_key",
]


def create_api_key(
    session: Session,
    *,
    name: str,
    key_hash: str,
    role: KeyRole | str = KeyRole.USER,
    expires_at: datetime | None = None,
    max_active_jobs: int | None = None,
    max_cpu_seconds_per_hour: float | None = None,
    max_storage_bytes: int | None = None,
    now: datetime | None = None,
) -> ApiKeyRecord:
    """Store a new API key by its hash (``keys.hash_api_key``); ConflictError if the hash exists.

    ``role``: ``user`` or ``admin``; ``expires_at``: after it the key is refused; the ``max_*``
    quotas override the settings' defaults for this key.
    """
    key_id = new_id()
    insert_or_conflict(
        session,
        API_KEYS,
        {
            "id": key_id,
            "name": name,
            "key_hash": key_hash,
            "created_at": now_utc(now),
            "role": KeyRole(role),
            "expires_at": None if expires_at is None else as_utc(expires_at),
            "max_active_jobs": max_active_jobs,
            "max_cpu_seconds_per_hour": max_cpu_seconds_per_hour,
            "max_storage_bytes": max_storage_bytes,
        },
        "an API key with this hash already exists",
    )
    record = get_api_key(session, key_id)
    assert record is not None
    return record


def revoke_api_key(session: Session, key_id: str, *, now: datetime | None = None) -> bool:
    """Mark a key revoked (it is refused from now on; its resources stay). True if it existed
    and was not revoked yet."""
    stmt = (
        update(API_KEYS)
        .where(API_KEYS.c.id == key_id, API_KEYS.c.revoked_at.is_(None))
        .values(revoked_at=now_utc(now))
    )
    return rowcount(session.execute(stmt)) > 0


def get_api_key(session: Session, key_id: str) -> ApiKeyRecord | None:
    """The API key with this id, or None."""
    return fetch_one(session, ApiKeyRecord, select(API_KEYS).where(API_KEYS.c.id == key_id))


def get_api_key_by_hash(session: Session, key_hash: str) -> ApiKeyRecord | None:
    """The API key whose hash is ``key_hash`` (authentication lookup), or None."""
    stmt = select(API_KEYS).where(API_KEYS.c.key_hash == key_hash)
    return fetch_one(session, ApiKeyRecord, stmt)


def list_api_keys(session: Session, *, limit: int = 50, offset: int = 0) -> Page[ApiKeyRecord]:
    """API keys, oldest first."""
    return fetch_page(
        session,
        ApiKeyRecord,
        select(API_KEYS),
        (API_KEYS.c.created_at, API_KEYS.c.id),
        limit,
        offset,
    )


def delete_api_key(session: Session, key_id: str) -> bool:
    """Delete an API key and everything it owns (cascade). True if it existed."""
    return rowcount(session.execute(delete(API_KEYS).where(API_KEYS.c.id == key_id))) > 0
