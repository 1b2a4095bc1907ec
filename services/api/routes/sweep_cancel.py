"""``POST /sweeps/{id}/cancel``: cancel every unfinished job of a sweep in one request; and
``DELETE /sweeps/{id}``: delete a finished sweep with its jobs.

One write transaction: the sweep's queued and running jobs are listed, then all go through the
store's job cancellation at once (``lifecycle.request_cancels``, what ``POST /jobs/{id}/cancel``
calls for one job): a queued job becomes ``cancelled`` at once, a running one gets
``cancel_requested`` and its worker stops after its current generation. Finished jobs are left
as they are, so the request is idempotent: a repeat cancels nothing more and says so.

``DELETE /sweeps/{id}``: once every job of the sweep finished, deletes each job with its
artifacts exactly as ``DELETE /jobs/{id}`` does (``job_deletion.delete_jobs``), then the sweep,
in one transaction; while any job is queued or running, a 409 says how many and to cancel first.
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, HTTPException, Response, status
from pydantic import Field
from sqlalchemy.orm import Session

from services.api.deps import Context, CurrentKey
from services.api.errors import not_found
from services.api.job_deletion import delete_jobs
from services.api.schemas import ErrorOut, SweepSummary
from services.store import lifecycle
from services.store import repository as repo
from services.store.records import JobRecord
from services.store.states import JobStatus

__all__ = ["SweepCancelled", "router", "unfinished_job_ids"]

router = APIRouter(tags=["sweeps"])

#: Jobs listed per query while the unfinished ones are collected.
_PAGE = 1000


class SweepCancelled(SweepSummary):
    """The sweep after ``POST /sweeps/{id}/cancel`` (counts and state) and what the request did:
    ``cancelled + stopping + already_finished == n_jobs``."""

    cancelled: int = Field(description="Queued jobs this request cancelled.")
    stopping: int = Field(
        description="Running jobs asked to stop (``cancel_requested``): each becomes "
        "``cancelled`` after its current generation."
    )
    already_finished: int = Field(
        description="Jobs already succeeded, failed or cancelled: left as they are."
    )


def unfinished_job_ids(session: Session, owner_key_id: str, sweep_id: str) -> list[str]:
    """Ids of the sweep's queued and running jobs (all of them, read page by page)."""
    ids: list[str] = []
    while True:
        page = repo.list_jobs(
            session,
            owner_key_id=owner_key_id,
            sweep_id=sweep_id,
            status=(JobStatus.QUEUED, JobStatus.RUNNING),
            limit=_PAGE,
            offset=len(ids),
        )
        ids += [j.id for j in page.items]
        if len(page.items) < _PAGE:  # the last page (``total`` is capped: not a bound)
            return ids


_RESPONSES: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorOut, "description": "No such sweep (among yours)."}
}


@router.post(
    "/sweeps/{sweep_id}/cancel",
    status_code=status.HTTP_202_ACCEPTED,
    response_model=SweepCancelled,
    summary="Cancel every unfinished job of a sweep",
    responses=_RESPONSES,
)
def cancel_sweep(sweep_id: str, key: CurrentKey, ctx: Context) -> SweepCancelled:
    """In one transaction, every queued job of the sweep is cancelled and every running one
    asked to stop after its current generation (as ``POST /jobs/{id}/cancel`` does one job);
    finished jobs are left alone, so a repeat is harmless (``cancelled`` 0). Answers the
    sweep's counts afterwards and how many jobs were cancelled, are stopping, or had already
    finished."""
    with ctx.write() as session:
        sweep = repo.get_sweep(session, sweep_id, owner_key_id=key.id)
        if sweep is None:
            raise not_found("sweep", sweep_id)
        ids = unfinished_job_ids(session, key.id, sweep.id)
        cancelled, stopping = lifecycle.request_cancels(session, ids, owner_key_id=key.id)
        counts = repo.count_jobs_by_status(session, owner_key_id=key.id, sweep_id=sweep.id)
    summary = SweepSummary.from_record(sweep, counts)
    return SweepCancelled(
        **summary.model_dump(),
        cancelled=len(cancelled),
        stopping=len(stopping),
        already_finished=summary.n_jobs - len(cancelled) - len(stopping),
    )


@router.delete(
    "/sweeps/{sweep_id}",
    status_code=status.HTTP_204_NO_CONTENT,
    summary="Delete a finished sweep: every job of it and everything stored for them",
    responses={
        **_RESPONSES,
        409: {"model": ErrorOut, "description": "A job of the sweep is still queued or running."},
    },
)
def delete_sweep(sweep_id: str, key: CurrentKey, ctx: Context) -> Response:
    """Deletes every job of the sweep as ``DELETE /jobs/{id}`` deletes one (its progress,
    front, result, events and artifact files, which frees storage quota), then the sweep, in
    one transaction. While any job is queued or running nothing is deleted: a 409 says how
    many, and ``POST /sweeps/{id}/cancel`` stops them."""

    def find(session: Session) -> tuple[JobRecord, ...]:
        sweep = repo.get_sweep(session, sweep_id, owner_key_id=key.id)
        if sweep is None:
            raise not_found("sweep", sweep_id)
        jobs = repo.sweep_jobs(session, sweep.id, owner_key_id=key.id)
        running = sum(not j.is_terminal for j in jobs)
        if running:
            raise HTTPException(
                status.HTTP_409_CONFLICT,
                f"sweep {sweep.id} has {running} unfinished job{'s' if running > 1 else ''} "
                f"(queued or running): cancel it first: POST /sweeps/{sweep.id}/cancel",
            )
        return jobs

    delete_jobs(
        ctx,
        key.id,
        find,
        then=lambda session: repo.delete_sweep(session, sweep_id, owner_key_id=key.id),
    )
    return Response(status_code=status.HTTP_204_NO_CONTENT)
