"""Dependencies of the routes: the app context (settings, database, artifacts, queue), the
caller's API key, and pagination parameters.

The database engine is created lazily on first use (importing the app or building it never
touches the database); ``ApiContext.read()`` / ``write()`` are transactions: ``write()`` takes
the SQLite write lock at ``BEGIN`` (see ``services.store.session``) and commits when its block
ends, so a route enqueues only after the block, i.e. after the commit.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Annotated

from fastapi import Depends, HTTPException, Query, Request, Security, status
from fastapi.security import APIKeyHeader
from sqlalchemy import Engine
from sqlalchemy.orm import Session, sessionmaker

from services.api.rate_limit import (
    COST_BYTES,
    RateLimiter,
    request_cost,
    retry_after_header,
)
from services.api.schemas import DEFAULT_LIMIT, MAX_LIMIT
from services.api.sweeps import MAX_SWEEP_JOBS
from services.api.warmup import Warmup
from services.store.api_keys import get_api_key_by_hash
from services.store.artifacts import ArtifactStore
from services.store.keys import hash_api_key
from services.store.records import ApiKeyRecord
from services.store.session import engine_from_settings, make_session_factory, session_scope
from services.store.settings import Settings
from services.store.sql import now_utc

log = logging.getLogger("legopt.api")

Enqueue = Callable[[str], None]

#: Largest offset / generation cursor accepted (keeps SQL integers in range).
MAX_OFFSET = 1_000_000_000

API_KEY_HEADER = "X-API-Key"


def default_enqueue(job_id: str) -> None:
    """Send the job's message to the Celery workers (imported lazily: the API does not need
    Celery until it sends)."""
    from services.worker.tasks import enqueue

    enqueue(job_id)


def _api_actor() -> str:
    from services.store.dispatcher import process_actor

    return process_actor("api")


@dataclass
class ApiContext:
    """Everything the routes share: settings, the lazily-built database, artifacts, the queue
    (``enqueue(job_id)``), the sweep size limit and the URL prefix of the API."""

    settings: Settings
    enqueue: Enqueue = default_enqueue
    max_sweep_jobs: int = MAX_SWEEP_JOBS
    prefix: str = "/api/v1"
    actor: str = field(default_factory=_api_actor)
    rate_limiter: RateLimiter | None = None
    warmup: Warmup = field(default_factory=Warmup)
    _engine: Engine | None = field(default=None, init=False, repr=False)
    _factory: sessionmaker[Session] | None = field(default=None, init=False, repr=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, init=False, repr=False)

    @property
    def session_factory(self) -> sessionmaker[Session]:
        """Session factory over the settings' database (engine built on first use)."""
        with self._lock:
            if self._factory is None:
                self._engine = engine_from_settings(self.settings)
                self._factory = make_session_factory(self._engine)
            return self._factory

    @property
    def artifacts(self) -> ArtifactStore:
        """The artifact store of the settings."""
        return ArtifactStore.from_settings(self.settings)

    @contextmanager
    def read(self) -> Iterator[Session]:
        """A read transaction."""
        with session_scope(self.session_factory) as session:
            yield session

    @contextmanager
    def write(self) -> Iterator[Session]:
        """A write transaction (committed when the block ends, rolled back if it raises)."""
        with session_scope(self.session_factory, immediate=True) as session:
            yield session

    def send_jobs(self, job_ids: Sequence[str]) -> None:
        """Send the messages of committed jobs now (claimed in the database first). A job whose
        message cannot be sent (broker down) stays queued and due: the dispatcher sends it
        when the broker is back, so an accepted job is never lost."""
        from services.store.dispatcher import send_now

        unsent = send_now(
            job_ids, self.enqueue, actor=self.actor, settings=self.settings,
            bind=self.session_factory,
        )  # fmt: skip
        if unsent:
            log.warning(
                "%d job(s) stay queued until the broker answers (the dispatcher retries)",
                len(unsent),
            )

    def close(self) -> None:
        """Dispose of the engine (app shutdown); a later use builds a new one."""
        with self._lock:
            if self._engine is not None:
                self._engine.dispose()
            self._engine = self._factory = None


def get_context(request: Request) -> ApiContext:
    """The context of the app serving ``request``."""
    ctx: ApiContext = request.app.state.context
    return ctx


Context = Annotated[ApiContext, Depends(get_context)]

_api_key = APIKeyHeader(
    name=API_KEY_HEADER,
    auto_error=False,
    description="Your API key (`legopt keys create NAME` prints one).",
)


def current_key(
    ctx: Context, request: Request, raw_key: Annotated[str | None, Security(_api_key)] = None
) -> ApiKeyRecord:
    """The API key of the caller (looked up by its hash); 401 when missing or unknown; 429
    past its request rate (a large body costs more, ``rate_limit.request_cost``)."""
    if not raw_key:
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            f"missing {API_KEY_HEADER} header",
            headers={"WWW-Authenticate": API_KEY_HEADER},
        )
    with ctx.read() as session:
        key = get_api_key_by_hash(session, hash_api_key(raw_key))
    if key is None:
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "invalid API key",
            headers={"WWW-Authenticate": API_KEY_HEADER},
        )
    reason = key.invalid_reason(now_utc())
    if reason is not None:
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            f"{reason}: ask an admin for a new key (`legopt keys create`)",
            headers={"WWW-Authenticate": API_KEY_HEADER},
        )
    if ctx.rate_limiter is not None:
        cost = request_cost(request.headers.get("content-length"))
        wait = ctx.rate_limiter.acquire(key.id, cost=cost)
        if wait > 0:
            raise HTTPException(
                status.HTTP_429_TOO_MANY_REQUESTS,
                f"too many requests for this API key: at most {ctx.settings.rate_limit_per_s:g} "
                f"per second (bursts of {ctx.settings.rate_limit_burst}; a request counts 1 "
                f"plus 1 per {COST_BYTES // 1024} KiB of its body); retry in "
                f"{retry_after_header(wait)} s",
                headers={"Retry-After": retry_after_header(wait)},
            )
    return key


CurrentKey = Annotated[ApiKeyRecord, Depends(current_key)]


def admin_key(key: CurrentKey) -> ApiKeyRecord:
    """The caller's key if it is an admin key; 403 otherwise."""
    if not key.is_admin:
        raise HTTPException(
            status.HTTP_403_FORBIDDEN,
            "this route needs an admin API key (`legopt keys create --admin`)",
        )
    return key


AdminKey = Annotated[ApiKeyRecord, Depends(admin_key)]


@dataclass(frozen=True)
class PageParams:
    """``limit`` / ``offset`` of a listing."""

    limit: int
    offset: int


def page_params(
    limit: Annotated[int, Query(ge=1, le=MAX_LIMIT, description="Page size.")] = DEFAULT_LIMIT,
    offset: Annotated[int, Query(ge=0, le=MAX_OFFSET, description="Items to skip.")] = 0,
) -> PageParams:
    """Pagination query parameters."""
    return PageParams(limit=limit, offset=offset)


Pagination = Annotated[PageParams, Depends(page_params)]

#: ``id_prefix`` of the job and sweep lists: what ``legopt status 2253`` resolves, as a range
#: scan of the primary key (``services.store.id_prefix``).
IdPrefix = Annotated[
    str | None,
    Query(
        max_length=36,
        description="Only ids starting with this (case-insensitive; a prefix no id can have "
        "matches nothing).",
    ),
]

__all__ = [
    "API_KEY_HEADER",
    "AdminKey",
    "ApiContext",
    "Context",
    "CurrentKey",
    "Enqueue",
    "IdPrefix",
    "MAX_OFFSET",
    "PageParams",
    "Pagination",
    "current_key",
    "default_enqueue",
    "get_context",
    "page_params",
]
