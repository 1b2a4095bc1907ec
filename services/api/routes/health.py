"""``GET /health`` (liveness, no database) and ``GET /ready`` (database, schema and a warm
validation)."""

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
    summary="Readiness: database migrated, validation warm",
    responses={
        503: {
            "model": ErrorOut,
            "description": "Database unreachable or not migrated, or the validation processes "
            "still warming up (a few seconds after start).",
        }
    },
)
def ready(ctx: Context) -> ReadyOut:
    """200 when the database answers, its schema is at the head revision and the validation
    processes are warm (``services.api.warmup``), else 503 saying which."""
    if not ctx.warmup.done.is_set():
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE,
            "warming up: the validation processes are loading the studies' kernels "
            "(LEGOPT_API_WARMUP); ready in a few seconds",
            headers={"Retry-After": "1"},
        )
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
    return ReadyOut(revision=head, warmup_s=ctx.warmup.seconds)
