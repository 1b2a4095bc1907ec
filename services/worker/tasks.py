"""The Celery task and the broker side of dispatch. A message carries only the job id;
everything else is in the database."""

from __future__ import annotations

import logging

from celery import signals

from services.store.dispatcher import Dispatcher
from services.store.settings import get_settings
from services.worker.celery_app import QUEUE, app
from services.worker.execute import execute_job
from services.worker.recycling import recycle_if_large

__all__ = ["enqueue", "queue_depth", "run_job"]

log = logging.getLogger("legopt.worker")


@app.task(name="legopt.run_job", acks_late=True, reject_on_worker_lost=True)
def run_job(job_id: str) -> dict[str, str]:
    """Run job ``job_id`` (a re-delivered or duplicate message is harmless: the claim decides)."""
    outcome = execute_job(job_id)
    recycle_if_large(get_settings())
    return {"job_id": outcome.job_id, "status": outcome.status}


def enqueue(job_id: str) -> None:
    """Send job ``job_id``'s message to the workers. Call it only through
    ``services.store.dispatcher`` (``send_now`` / the dispatcher), which claims the send in
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


_DISPATCHER: list[Dispatcher] = []


@signals.worker_ready.connect
def _start_dispatcher(**_: object) -> None:
    """Every worker process also runs a dispatcher thread; the database elects one active at a
    time (recovery never waits on the broker). It runs in the worker's main process: the
    engine's lock is fork-safe (``services.store.session``), so a prefork child forked while
    it works starts clean."""
    dispatcher = Dispatcher(enqueue, queue_depth)
    dispatcher.start()
    _DISPATCHER.append(dispatcher)


@signals.worker_shutdown.connect
def _stop_dispatcher(**_: object) -> None:
    """Release the dispatcher role at a clean shutdown so another worker takes it at once."""
    while _DISPATCHER:
        dispatcher = _DISPATCHER.pop()
        dispatcher.stop()
