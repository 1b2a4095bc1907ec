"""A running job, live: its current front (the last stored generation's) and a stream of
Server-Sent Events that says when it changed, so the job page redraws within a second of a new
generation instead of polling. Pages that cannot hold a stream (or are refused one: at most
``MAX_STREAMS`` per API process) poll as before. A sweep has a stream too: its jobs' counts
per status and its progress, so the sweep page updates the same way."""

from __future__ import annotations

import asyncio
import json
import threading
from collections.abc import AsyncIterator, Callable
from functools import partial
from typing import Any

from fastapi import APIRouter, HTTPException, status
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import StreamingResponse
from pydantic import BaseModel, Field

from services.api.dashboard_schemas import Quantity, quantities
from services.api.deps import ApiContext, Context, CurrentKey
from services.api.lookups import OwnedJob
from services.api.schemas import ErrorOut
from services.store import repository as repo
from services.store.front_codec import decode_front
from services.store.tables import GENERATIONS

router = APIRouter(tags=["dashboard"])

#: How often (s) a stream reads the job's progress row.
POLL_S = 0.25
#: A comment line this often (s) keeps proxies from closing a quiet stream.
KEEPALIVE_S = 15.0
#: Streams one API process holds at once; beyond, 429 (the page polls).
MAX_STREAMS = 64


class _Open:
    """Streams open in this process (counted by the streams themselves while they run, so a
    stream whose client left before it started holds nothing)."""

    def __init__(self) -> None:
        self.n = 0
        self.lock = threading.Lock()

    def add(self, k: int) -> None:
        with self.lock:
            self.n += k


_open = _Open()

_404: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorOut, "description": "No such job (among yours)."}
}


class LiveFrontOut(BaseModel):
    """The front of the last generation stored so far (objective vectors only)."""

    job_id: str
    generation: int | None = Field(description="The generation the front is of (null: none).")
    objectives: list[Quantity]
    points: list[list[float | None]] = Field(description="Objective vectors (minimised form).")


def _latest_front(ctx: ApiContext, job_id: str) -> tuple[int | None, list[list[float | None]]]:
    from sqlalchemy import select

    stmt = (
        select(GENERATIONS.c.generation, GENERATIONS.c.front_packed)
        .where(GENERATIONS.c.job_id == job_id, GENERATIONS.c.front_packed.is_not(None))
        .order_by(GENERATIONS.c.generation.desc())
        .limit(1)
    )
    with ctx.read() as session:
        row = session.execute(stmt).first()
    if row is None:
        return None, []
    return int(row.generation), decode_front(row.front_packed)


@router.get(
    "/jobs/{job_id}/front/live",
    response_model=LiveFrontOut,
    summary="The current front of a job, also while it runs",
    responses=_404,
)
async def get_live_front(job: OwnedJob, ctx: Context) -> LiveFrontOut:
    """The objective vectors of the last stored generation's front (at most 300 points)."""
    generation, points = await run_in_threadpool(_latest_front, ctx, job.id)
    facts = job.facts if isinstance(job.facts, dict) else {}
    names = [str(n) for n in facts.get("objectives") or ()]
    if points and len(names) != len(points[0]):
        names = [f"f{j + 1}" for j in range(len(points[0]))]
    kind = facts.get("kind") if isinstance(facts.get("kind"), str) else None
    return LiveFrontOut(
        job_id=job.id, generation=generation, objectives=quantities(names, kind), points=points
    )


def _state(ctx: ApiContext, job_id: str) -> dict[str, Any] | None:
    with ctx.read() as session:
        job = repo.get_job(session, job_id)
    if job is None:
        return None
    return {
        "status": job.status.value,
        "generation": job.progress_generation,
        "total_generations": job.total_generations,
        "terminal": job.status.is_terminal,
    }


async def _events(
    ctx: ApiContext, read: Callable[[], dict[str, Any] | None]
) -> AsyncIterator[bytes]:
    """``progress`` events (JSON: ``read()``, run in the thread pool) on every change, until
    its ``terminal`` is true; ``gone`` when ``read()`` finds nothing (deleted meanwhile)."""
    loop = asyncio.get_running_loop()
    started = last_sent = loop.time()
    previous: dict[str, Any] | None = None
    _open.add(1)
    try:
        yield f"retry: {int(1000 * POLL_S * 4)}\n\n".encode()
        while loop.time() - started < ctx.settings.event_stream_s:
            state = await run_in_threadpool(read)
            if state is None:  # deleted meanwhile
                yield b"event: gone\ndata: {}\n\n"
                return
            if state != previous:
                previous = state
                last_sent = loop.time()
                yield f"event: progress\ndata: {json.dumps(state)}\n\n".encode()
                if state["terminal"]:
                    return
            elif loop.time() - last_sent >= KEEPALIVE_S:
                last_sent = loop.time()
                yield b": keep-alive\n\n"
            await asyncio.sleep(POLL_S)
    finally:
        _open.add(-1)


def _event_stream(
    ctx: ApiContext, read: Callable[[], dict[str, Any] | None], poll: str
) -> StreamingResponse:
    """The Server-Sent Events response of ``_events``; 429 naming ``poll`` (what to poll
    instead) when ``MAX_STREAMS`` streams are open on this server."""
    if _open.n >= MAX_STREAMS:
        raise HTTPException(
            status.HTTP_429_TOO_MANY_REQUESTS,
            f"{MAX_STREAMS} event streams are open on this server: poll {poll}",
            headers={"Retry-After": "5"},
        )
    return StreamingResponse(
        _events(ctx, read),
        media_type="text/event-stream",
        headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"},
    )


@router.get(
    "/jobs/{job_id}/events",
    response_class=StreamingResponse,
    summary="Server-Sent Events: the job's progress, pushed as it changes",
    responses={
        200: {"content": {"text/event-stream": {}}, "description": "`progress` events."},
        **_404,
        429: {"model": ErrorOut, "description": "Too many streams open: poll instead."},
    },
)
async def job_events(job: OwnedJob, ctx: Context) -> StreamingResponse:
    """An ``event: progress`` (``{"status", "generation", "total_generations", "terminal"}``)
    when the stream opens and whenever the job's status or generation changes; the stream ends
    after the job's terminal event (or after ``event_stream_s`` of the settings: reconnect)."""
    return _event_stream(ctx, partial(_state, ctx, job.id), f"GET /jobs/{job.id}")


# --------------------------------------------------------------------------- a sweep, live


def _sweep_state(ctx: ApiContext, sweep_id: str, owner_key_id: str) -> dict[str, Any] | None:
    """The sweep's jobs per status and its progress (the mean of its jobs' fractions of
    generations done, a succeeded job counting 1), in one grouped query; None: no such sweep."""
    from sqlalchemy import Float, case, cast, func, select

    from services.api.schemas import sweep_state
    from services.store.states import JobStatus
    from services.store.tables import JOBS

    fraction = case(
        (JOBS.c.total_generations > 0,
         cast(JOBS.c.progress_generation, Float) / JOBS.c.total_generations),
        else_=0.0,
    )  # fmt: skip
    stmt = (
        select(
            JOBS.c.status,
            func.count(),
            func.coalesce(func.sum(JOBS.c.progress_generation), 0),
            func.coalesce(func.sum(JOBS.c.total_generations), 0),
            func.coalesce(func.sum(fraction), 0.0),
        )
        .where(JOBS.c.sweep_id == sweep_id, JOBS.c.owner_key_id == owner_key_id)
        .group_by(JOBS.c.status)
    )
    with ctx.read() as session:
        if repo.get_sweep(session, sweep_id, owner_key_id=owner_key_id) is None:
            return None
        rows = session.execute(stmt).all()
    counts = {s: 0 for s in JobStatus}
    generation = total = 0
    done = 0.0
    for status_, n, gens, totals, fractions in rows:
        st = JobStatus(status_)
        counts[st] = int(n)
        generation += int(gens)
        total += int(totals)
        done += float(n) if st is JobStatus.SUCCEEDED else min(float(fractions), float(n))
    n_jobs = sum(counts.values())
    state = sweep_state(counts)
    return {
        "state": state,
        "n_jobs": n_jobs,
        "counts": {s.value: n for s, n in counts.items()},
        "generation": generation,
        "total_generations": total,
        "progress": round(done / n_jobs, 6) if n_jobs else 0.0,
        "terminal": state in ("finished", "empty"),
    }


@router.get(
    "/sweeps/{sweep_id}/events",
    response_class=StreamingResponse,
    summary="Server-Sent Events: the sweep's job counts and progress, pushed as they change",
    responses={
        200: {"content": {"text/event-stream": {}}, "description": "`progress` events."},
        404: {"model": ErrorOut, "description": "No such sweep (among yours)."},
        429: {"model": ErrorOut, "description": "Too many streams open: poll instead."},
    },
)
async def sweep_events(sweep_id: str, key: CurrentKey, ctx: Context) -> StreamingResponse:
    """An ``event: progress`` (``{"state", "n_jobs", "counts", "generation",
    "total_generations", "progress", "terminal"}``: ``counts`` per job status, ``generation``
    and ``total_generations`` summed over the jobs, ``progress`` the mean of the jobs' fractions
    done) when the stream opens and whenever one of them changes; the stream ends after the
    event of the finished sweep (or after ``event_stream_s`` of the settings: reconnect). The
    limit of open streams is shared with the jobs' streams."""
    from services.api.errors import not_found

    with ctx.read() as session:
        sweep = repo.get_sweep(session, sweep_id, owner_key_id=key.id)
        if sweep is None:
            raise not_found("sweep", sweep_id)
    read = partial(_sweep_state, ctx, sweep.id, key.id)
    return _event_stream(ctx, read, f"GET /sweeps/{sweep.id}")


__all__ = ["LiveFrontOut", "router"]
