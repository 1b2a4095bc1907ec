"""``GET /health`` (liveness, no database) and ``GET /ready`` (database and schema)."""

from __future__ import annotations

import logging

from fastapi import APIRouter, HTTPException, status

from services.api.deps import Context
from services.api.schemas import ErrorOut, HealthOut, ReadyOut
from services.store import migrate

log = logging.getLogger("legopt.api")

router = APIRouter(tags=["health"])


@router.get("/health", response_model=HealthOut, summary="Liveness (no database access)")
def health() -> HealthOut:
    """The process answers."""
    return HealthOut()


@router.get(
    "/ready",
    response_model=ReadyOut,
    summary="Readiness: database reachable and migrated to the head revision",
    responses={503: {"model": ErrorOut, "description": "Database unreachable or not migrated."}},
)
def ready(ctx: Context) -> ReadyOut:
    """200 when the database answers and its schema is at the head revision, else 503."""
    url = ctx.settings.database_url
    try:
        current = migrate.current_revision(url)
        head = migrate.head_revision()
    except Exception as exc:
        log.warning("readiness: database unreachable: %s", exc)
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE,
            f"database unreachable: {type(exc).__name__}: {exc}",
        ) from None
    if current != head:
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE,
            f"database schema is at revision {current or 'none'}, the code needs {head}: "
            "run `legopt db upgrade`",
        )
    return ReadyOut(revision=head)
