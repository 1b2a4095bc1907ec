"""The FastAPI application: ``create_app(settings, enqueue)``, served under ``/api/v1``.

Run it with ``uvicorn services.api.app:app`` (settings from the ``LEGOPT_*`` environment).
``app`` is created on first access, and the database engine on the first request that needs
it, so importing this module never touches the database.

Tests build their own app, e.g.
``create_app(Settings.from_env(env={}, data_dir=tmp), enqueue=sent.append)``:
``enqueue(job_id)`` is called once per job after the job row is committed; by default it is
``services.worker.tasks.enqueue`` (Celery, imported on first use).
"""

from __future__ import annotations

import threading
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Any

from fastapi import APIRouter, Depends, FastAPI

from services.api import validation_pool
from services.api.body_limit import DEFAULT_MAX_BODY_BYTES, BodySizeLimitMiddleware
from services.api.deps import API_KEY_HEADER, ApiContext, Enqueue, current_key, default_enqueue
from services.api.errors import install_error_handlers
from services.api.json_guard import JsonGuardMiddleware
from services.api.rate_limit import RateLimiter
from services.api.routes import health, jobs, keys, robots, studies, sweep_cancel, sweeps
from services.api.routes.dashboard_routers import DASHBOARD_ROUTERS
from services.api.schemas import ErrorOut
from services.api.security_headers import SecurityHeadersMiddleware
from services.store.settings import Settings, get_settings
from services.web import mount_dashboard

API_PREFIX = "/api/v1"

DESCRIPTION = f"""
Trajectory optimisation of legged-robot limbs and serial manipulators (GA, HKA, MOEA/D,
NSGA-II on the five seed studies), run by workers; results, Pareto fronts and Rerun recordings.

Every endpoint except `/health`, `/ready` and these docs needs the `{API_KEY_HEADER}` header.
Resources belong to the key that created them; another key gets 404.
Listings take `limit` and `offset` and answer `{{items, total, limit, offset}}`.
Validation errors are 422 `{{"detail": [{{"loc": [...], "msg": ..., "type": ...}}]}}` with the
location of the offending field (every 422 has this shape); other errors are
`{{"detail": "message"}}`. Every response carries `X-Content-Type-Options: nosniff`.
"""


def create_app(
    settings: Settings | None = None,
    enqueue: Enqueue | None = None,
    *,
    max_body_bytes: int = DEFAULT_MAX_BODY_BYTES,
    max_sweep_jobs: int | None = None,
) -> FastAPI:
    """Build the API.

    Args:
        settings: database URL, artifact directory and job size limits (default
            ``get_settings()``, i.e. the ``LEGOPT_*`` environment).
        enqueue: ``enqueue(job_id)`` sends a committed job's message to the workers (default:
            Celery via ``services.worker.tasks.enqueue``), after the send is claimed in the
            database. If it raises, the job stays queued and due, and the dispatcher of the
            workers sends it once the broker answers.
        max_body_bytes: larger request bodies are refused with 413.
        max_sweep_jobs: a sweep expanding to more jobs is refused with 422 (default
            ``settings.max_sweep_jobs``, ``LEGOPT_MAX_SWEEP_JOBS``).
    """
    settings = settings if settings is not None else get_settings()
    ctx = ApiContext(
        settings=settings,
        enqueue=enqueue if enqueue is not None else default_enqueue,
        max_sweep_jobs=max_sweep_jobs if max_sweep_jobs is not None else settings.max_sweep_jobs,
        prefix=API_PREFIX,
        rate_limiter=RateLimiter(settings.rate_limit_per_s, settings.rate_limit_burst),
    )

    @asynccontextmanager
    async def lifespan(_app: FastAPI) -> AsyncIterator[None]:
        if threading.current_thread() is threading.main_thread():
            ctx.warmup.start(settings)  # a server: warm its validation processes
        else:
            ctx.warmup.done.set()  # an in-process test client: nothing to warm
        yield
        # A server (uvicorn runs the event loop on the main thread, and re-raises SIGTERM after
        # this, so atexit never runs) stops its validation processes here; an in-process test
        # client (its own thread) leaves the shared pool to the next one.
        if threading.current_thread() is threading.main_thread():
            validation_pool.shutdown()
        ctx.close()

    app = FastAPI(
        title="LegOpt",
        version="1",
        description=DESCRIPTION,
        openapi_url=f"{API_PREFIX}/openapi.json",
        docs_url=None,  # served by mount_dashboard from local files (no CDN)
        redoc_url=None,
        lifespan=lifespan,
    )
    app.state.context = ctx
    app.add_middleware(JsonGuardMiddleware)  # depth / NaN checks, inside the size limit
    app.add_middleware(BodySizeLimitMiddleware, max_bytes=max_body_bytes)
    app.add_middleware(SecurityHeadersMiddleware)  # outermost: every response, 413s included
    install_error_handlers(app)

    app.include_router(health.router, prefix=API_PREFIX)
    errors: dict[int | str, dict[str, Any]] = {
        401: {"model": ErrorOut, "description": f"Missing or invalid {API_KEY_HEADER}."},
        413: {"model": ErrorOut, "description": "Request body too large."},
    }
    protected = APIRouter(prefix=API_PREFIX, dependencies=[Depends(current_key)], responses=errors)
    protected.include_router(robots.router)
    protected.include_router(jobs.router)
    protected.include_router(sweeps.router)
    protected.include_router(sweep_cancel.router)
    protected.include_router(keys.router)
    protected.include_router(studies.router)
    for router in DASHBOARD_ROUTERS:
        protected.include_router(router)
    app.include_router(protected)
    mount_dashboard(app, settings, API_PREFIX)  # /, /docs, /static, /viewer, {API_PREFIX}/docs
    return app


_app: FastAPI | None = None


def __getattr__(name: str) -> Any:
    """``services.api.app.app``: the app of the environment's settings, built on first access."""
    global _app
    if name == "app":
        if _app is None:
            _app = create_app()
        return _app
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["API_PREFIX", "create_app"]
