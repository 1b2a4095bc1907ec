"""The Celery task and the broker side of dispatch. A message carries only the job id;
everything else is in the database."""

from __future__ import annotations

import logging

from services.worker.celery_app import QUEUE, app
from services.worker.execute import run_payload

__all__ = ["enqueue", "queue_depth", "run_job"]

log = logging.getLogger("legopt.worker")


@app.task(name="legopt.run_job", acks_late=True, reject_on_worker_lost=True)
def run_job(job_id: str) -> dict[str, str]:
    """Run job ``job_id`` (a re-delivered or duplicate message is harmless: the claim decides)."""
    return run_payload(job_id)


def enqueue(job_id: str) -> None:
    """Send job ``job_id``'s message to the workers. Call it only through
    ``services.worker.dispatcher`` (``send_now`` / the dispatcher), which claims the send in
    the database first."""
    run_job.apply_async(args=[job_id], retry=True, retry_policy={"max_retries": 2})


def queue_depth() -> int | None:
    """Messages waiting in the job queue (not those a worker holds), or None if the broker
    cannot say (down, or a transport without a size)."""
    try:
        with app.connection_for_read() as conn:
            conn.ensure_connection(max_retries=1)
            return int(conn.default_channel._size(QUEUE))
    except Exception as exc:
        log.debug("queue depth unavailable: %s", exc)
        return None
