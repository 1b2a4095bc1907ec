"""Broker-independent recovery: requeue jobs whose lease expired, re-send lost messages.

Embedded brokers lose a message when a worker is killed mid-task, and Redis may deliver one
twice; neither matters because (1) every running job holds a lease that its worker renews, and
this reaper puts jobs with an expired lease back to ``queued`` and re-sends their message, and
(2) a job sitting in ``queued`` for longer than ``stale_after_s`` (its message was lost before
any worker saw it) gets its message re-sent. Duplicates are harmless: the claim decides.
Every worker process runs :class:`Reaper` in a background thread; so does ``legopt serve``.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from datetime import UTC, datetime, timedelta

from sqlalchemy import select

from services.store.lifecycle import requeue_expired
from services.store.session import session_scope
from services.store.settings import Settings, get_settings
from services.store.tables import JOBS, JobStatus

log = logging.getLogger("legopt.reaper")


def reap_once(
    enqueue: Callable[[str], None],
    settings: Settings | None = None,
    *,
    stale_after_s: float | None = None,
    now: datetime | None = None,
) -> list[str]:
    """One pass; returns the ids whose message was (re-)sent."""
    settings = settings or get_settings()
    now = now or datetime.now(UTC)
    stale_after_s = stale_after_s if stale_after_s is not None else 2 * settings.lease_seconds
    with session_scope(immediate=True) as s:
        report = requeue_expired(s, now, max_attempts=settings.max_attempts)
    cutoff = now - timedelta(seconds=stale_after_s)
    with session_scope() as s:
        stale = list(
            s.execute(
                select(JOBS.c.id).where(
                    JOBS.c.status == JobStatus.QUEUED,
                    JOBS.c.cancel_requested.is_(False),
                    JOBS.c.created_at < cutoff,
                    JOBS.c.attempt_count == 0,
                )
            ).scalars()
        )
    resend = sorted(set(report.requeued) | set(stale))
    for job_id in resend:
        enqueue(job_id)
    if resend or report.failed or report.cancelled:
        log.info(
            "reaper: re-sent %s, failed %s, cancelled %s", resend, report.failed, report.cancelled
        )
    return resend


class Reaper(threading.Thread):
    """Calls :func:`reap_once` every ``period_s`` seconds until ``stop()``."""

    def __init__(
        self,
        enqueue: Callable[[str], None],
        settings: Settings | None = None,
        period_s: float | None = None,
    ) -> None:
        super().__init__(name="legopt-reaper", daemon=True)
        self.settings = settings or get_settings()
        self.period_s = period_s if period_s is not None else self.settings.lease_seconds / 2
        self.enqueue = enqueue
        self._stop_event = threading.Event()

    def run(self) -> None:
        while not self._stop_event.wait(self.period_s):
            try:
                reap_once(self.enqueue, self.settings)
            except Exception:
                log.exception("reaper pass failed")

    def stop(self) -> None:
        self._stop_event.set()
