"""Idempotency keys of POST requests: a retried request returns what the first one created.

A client sends ``Idempotency-Key: <its own unique string>`` with POST /jobs or /sweeps. The
route looks the key up (per API key) inside its write transaction and, when it is new, records
it *before* creating anything, so two concurrent requests with one key cannot both create: the
second waits on the unique constraint and then finds the first one's record.
"""

from __future__ import annotations

import hashlib
import json
from datetime import datetime
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from services.store.records import IdempotencyRecord
from services.store.sql import fetch_one, insert_or_conflict, now_utc
from services.store.tables import IDEMPOTENCY_KEYS

MAX_KEY_LENGTH = 200


def request_fingerprint(body: Any) -> str:
    """SHA-256 of the canonical JSON of a request body (keys sorted)."""
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def find_idempotent(session: Session, owner_key_id: str, key: str) -> IdempotencyRecord | None:
    """What a request with this key already created for this API key, or None."""
    stmt = select(IDEMPOTENCY_KEYS).where(
        IDEMPOTENCY_KEYS.c.owner_key_id == owner_key_id, IDEMPOTENCY_KEYS.c.key == key
    )
    return fetch_one(session, IdempotencyRecord, stmt)


def remember_idempotent(
    session: Session,
    owner_key_id: str,
    key: str,
    *,
    request_sha256: str,
    resource_kind: str,
    resource_id: str,
    now: datetime | None = None,
) -> IdempotencyRecord | None:
    """Record the key for a resource about to be created; None when it is new (go on and
    create), else the record a concurrent request committed first (return its resource)."""
    from services.store.errors import ConflictError

    try:
        insert_or_conflict(
            session,
            IDEMPOTENCY_KEYS,
            {
                "owner_key_id": owner_key_id,
                "key": key,
                "request_sha256": request_sha256,
                "resource_kind": resource_kind,
                "resource_id": resource_id,
                "created_at": now_utc(now),
            },
            "idempotency key already used",
        )
    except ConflictError:
        return find_idempotent(session, owner_key_id, key)
    return None


__all__ = [
    "MAX_KEY_LENGTH",
    "find_idempotent",
    "remember_idempotent",
    "request_fingerprint",
]
