"""What POST /jobs and POST /sweeps share: idempotency keys and quotas.

- ``Idempotency-Key`` header: a client that retries a POST whose answer it never got (the
  connection dropped, the API restarted) sends the same key and gets the resource the first
  request created, not a second one. The same key with a different body is a 422.
- Quotas: jobs queued or running, worker CPU seconds per hour and stored bytes per API key
  (``services.store.quotas``); over a quota the request is refused with 429, a message that
  says what is used, the limit, and what to do, and ``Retry-After`` (whole seconds: 30 for
  active jobs, until the next UTC hour for CPU seconds, 60 for storage; see the constants of
  ``services.store.quotas``). The check locks the key until the caller's transaction ends, so
  the jobs must be stored in that same transaction (``ApiContext.write()``).
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import Header, HTTPException, status
from sqlalchemy.orm import Session

from services.api.errors import invalid
from services.api.rate_limit import retry_after_header
from services.store.idempotency import MAX_KEY_LENGTH, find_idempotent, remember_idempotent
from services.store.quotas import quota_refusal
from services.store.records import ApiKeyRecord, IdempotencyRecord
from services.store.settings import Settings

IDEMPOTENCY_HEADER = "Idempotency-Key"

IdempotencyKey = Annotated[
    str | None,
    Header(
        alias=IDEMPOTENCY_HEADER,
        min_length=1,
        max_length=MAX_KEY_LENGTH,
        pattern=r"^[\x21-\x7e]+$",
        description="Any unique string of yours (e.g. a UUID): retrying the request with the "
        "same key returns what the first one created instead of creating it again.",
    ),
]


class Replay(Exception):
    """The request repeats an earlier one: answer with ``record``'s resource."""

    def __init__(self, record: IdempotencyRecord) -> None:
        super().__init__(record.resource_id)
        self.record = record


def check_replay(
    session: Session,
    key: ApiKeyRecord,
    idempotency_key: str | None,
    fingerprint: str,
    kind: str,
) -> None:
    """Raise ``Replay`` when ``idempotency_key`` was used for this very request; 422 when it
    was used for another one."""
    if idempotency_key is None:
        return
    record = find_idempotent(session, key.id, idempotency_key)
    if record is not None:
        raise _replay_or_mismatch(record, fingerprint, kind)


def remember(
    session: Session,
    key: ApiKeyRecord,
    idempotency_key: str | None,
    fingerprint: str,
    kind: str,
    resource_id: str,
) -> None:
    """Record the key for the resource created in this transaction; raise ``Replay`` (the
    caller's transaction then rolls back) if a concurrent request committed it first."""
    if idempotency_key is None:
        return
    earlier = remember_idempotent(
        session,
        key.id,
        idempotency_key,
        request_sha256=fingerprint,
        resource_kind=kind,
        resource_id=resource_id,
    )
    if earlier is not None:
        raise _replay_or_mismatch(earlier, fingerprint, kind)


def _replay_or_mismatch(record: IdempotencyRecord, fingerprint: str, kind: str) -> Exception:
    if record.request_sha256 == fingerprint and record.resource_kind == kind:
        return Replay(record)
    return invalid(
        ("header", IDEMPOTENCY_HEADER),
        f"this Idempotency-Key was already used on {record.created_at.isoformat()} for a "
        f"different request (it created {record.resource_kind} {record.resource_id}); use a "
        "new key for a new request",
        "idempotency_key_reused",
    )


def check_quota(
    session: Session, key: ApiKeyRecord, settings: Settings, *, new_jobs: int, new_bytes: int
) -> None:
    """429 with ``Retry-After`` (seconds) when the key may not add ``new_jobs`` jobs storing
    ``new_bytes`` bytes. Holds the key's quota lock until ``session``'s transaction ends: store
    the jobs in it."""
    refusal = quota_refusal(session, key, settings, new_jobs=new_jobs, new_bytes=new_bytes)
    if refusal is not None:
        raise HTTPException(
            status.HTTP_429_TOO_MANY_REQUESTS,
            f"quota exceeded: {refusal.message}",
            headers={"Retry-After": retry_after_header(refusal.retry_after_s)},
        )


def replay_headers() -> dict[str, Any]:
    """Headers marking a replayed answer."""
    return {"Idempotent-Replayed": "true"}


__all__ = [
    "IDEMPOTENCY_HEADER",
    "IdempotencyKey",
    "Replay",
    "check_quota",
    "check_replay",
    "remember",
    "replay_headers",
]
