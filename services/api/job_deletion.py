"""Deleting finished jobs and everything stored for them: what ``DELETE /jobs/{id}`` and
``DELETE /sweeps/{id}`` both do to each job.

One write transaction deletes the jobs' rows (progress, front, trials, result, events and
artifact rows cascade with the job), which frees their storage quota; after it committed, their
artifact files (recordings, ``result.json``) are removed from the artifact store. A queued or
running job is never deleted: it must be cancelled first (409).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from fastapi import HTTPException, status
from sqlalchemy.orm import Session

from services.api.deps import ApiContext
from services.store import repository as repo
from services.store.records import JobRecord

__all__ = ["delete_jobs", "unfinished"]


def unfinished(job: JobRecord) -> HTTPException:
    """The 409 of deleting a queued or running job."""
    return HTTPException(
        status.HTTP_409_CONFLICT,
        f"job {job.id} is {job.status.value}: cancel it first (POST /jobs/{job.id}/cancel)",
    )


def delete_jobs(
    ctx: ApiContext,
    owner_key_id: str,
    find: Callable[[Session], Sequence[JobRecord]],
    then: Callable[[Session], object] | None = None,
) -> list[JobRecord]:
    """Delete the jobs ``find`` picks (of ``owner_key_id``) and their artifacts; the deleted
    jobs. In one write transaction: ``find(session)`` (raising its route's 404 or 409), each
    job's rows, then ``then(session)`` (what goes with the jobs: a sweep's row); after the
    commit, each job's artifact files. A job not finished is a 409 and nothing is deleted."""
    with ctx.write() as session:
        jobs = list(find(session))
        for job in jobs:
            if not job.is_terminal:
                raise unfinished(job)
            repo.delete_job(session, job.id, owner_key_id=owner_key_id)
        if then is not None:
            then(session)
    for job in jobs:
        ctx.artifacts.delete_job(job.id)
    return jobs
