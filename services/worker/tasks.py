"""The Celery task. The message carries only the job id; everything else is in the database."""

from __future__ import annotations

from services.worker.celery_app import app
from services.worker.execute import run_payload

__all__ = ["enqueue", "run_job"]


@app.task(name="legopt.run_job", acks_late=True, reject_on_worker_lost=True)
def run_job(job_id: str) -> dict[str, str]:
    """Run job ``job_id`` (a re-delivered or duplicate message is harmless: the claim decides)."""
    return run_payload(job_id)


def enqueue(job_id: str) -> None:
    """Send job ``job_id`` to the workers (call after the job row is committed)."""
    run_job.apply_async(args=[job_id])
