"""Dispatch that cannot lose or flood: the API's immediate send and the elected dispatcher.

The database is the source of truth (``services.store.dispatch``): every queued job is due for
a queue message until one is sent, and every send is claimed in the database first.

- ``send_now(job_ids, send)``: the API, right after committing new jobs, claims and sends
  their messages (low latency). If it crashes in between, or the broker is down, the jobs stay
  due and the dispatcher sends them.
- ``Dispatcher``: a thread in every worker process (and ``legopt serve``); through a service
  lease in the database only one of them works at a time. Each pass (every
  ``dispatch_period_s``): requeue jobs whose lease expired (their worker died), send the
  messages of new and requeued jobs, and re-send the messages the broker lost: when the broker
  holds fewer messages than there are queued jobs sent, in two passes running (a message a
  worker has just taken, its claim not yet committed, is missing for one pass only), the jobs
  sent longest ago (more than a lease ago) are re-sent, at most that many. So a lost message
  is re-sent about once, a job waiting behind busy workers is never re-sent (≤ 1.1 messages
  per job over a 10⁴-job sweep), and a queued job waits at most about a lease and two passes
  when a worker is idle. Where the broker cannot tell its depth, due jobs are re-sent on a
  backoff of leases instead (``services.store.dispatch``).

``send`` and ``queue_depth`` are injected (Celery's in ``services.worker.tasks``), so nothing
here imports Celery and the API can use ``send_now``.
"""

from __future__ import annotations

import logging
import os
import socket
import threading
import uuid
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime, timedelta

from sqlalchemy.orm import Session, sessionmaker

from services.store.dispatch import (
    backoff_schedule,
    claim_sends,
    queued_sent_count,
    release_lead,
    release_sends,
    try_lead,
)
from services.store.lifecycle import requeue_expired
from services.store.session import session_scope
from services.store.settings import Settings, get_settings

log = logging.getLogger("legopt.dispatch")

ROLE = "dispatcher"

Send = Callable[[str], None]
QueueDepth = Callable[[], int | None]


def process_actor(kind: str) -> str:
    """A name for this process in events and leases: ``kind@host:pid:random``."""
    return f"{kind}@{socket.gethostname()}:{os.getpid()}:{uuid.uuid4().hex[:6]}"


@dataclass
class PassReport:
    """What one dispatcher pass did (``leader`` False: another process holds the role)."""

    leader: bool
    sent: list[str] = field(default_factory=list)
    failed_sends: list[str] = field(default_factory=list)
    requeued: tuple[str, ...] = ()
    failed: tuple[str, ...] = ()
    cancelled: tuple[str, ...] = ()
    broker_depth: int | None = None
    #: Queued jobs sent whose message the broker did not hold at this pass (None: unknown).
    shortfall: int | None = None


Bind = sessionmaker[Session] | None


def _send_claimed(
    ids: Sequence[str],
    send: Send,
    actor: str,
    settings: Settings,
    bind: Bind = None,
    now: datetime | None = None,
) -> list[str]:
    """Send the claimed ``ids`` (their ``dispatched`` events were recorded with the claim);
    give failed ones back and withdraw their events. Returns the unsent."""
    unsent: list[str] = []
    for i, job_id in enumerate(ids):
        try:
            send(job_id)
        except Exception as exc:
            log.warning("sending job %s failed: %s: %s", job_id, type(exc).__name__, exc)
            unsent = list(ids[i:])  # the broker is down: stop, keep the rest due
            break
    if unsent:
        claimed_at = now or datetime.now(UTC)
        retry_at = claimed_at + timedelta(seconds=settings.dispatch_period_s)
        with session_scope(bind, immediate=True) as s:
            release_sends(s, unsent, retry_at=retry_at, actor=actor, claimed_at=claimed_at)
    return unsent


def send_now(
    job_ids: Sequence[str],
    send: Send,
    *,
    actor: str,
    settings: Settings | None = None,
    bind: Bind = None,
) -> list[str]:
    """Claim and send the messages of just-committed jobs; returns the ids not sent (they stay
    due and the dispatcher retries them). ``bind``: the session factory (default: the
    process's)."""
    settings = settings or get_settings()
    backoff = backoff_schedule(settings.lease_seconds)
    now = datetime.now(UTC)
    with session_scope(bind, immediate=True) as s:
        ids = claim_sends(s, job_ids=list(job_ids), backoff_s=backoff, actor=actor, now=now)
    return _send_claimed(ids, send, actor, settings, bind, now)


def dispatch_pass(
    send: Send,
    queue_depth: QueueDepth,
    *,
    actor: str,
    settings: Settings | None = None,
    now: datetime | None = None,
    bind: Bind = None,
    previous_shortfall: int | None = None,
) -> PassReport:
    """One pass of the dispatcher (see the module docstring); does nothing unless ``actor``
    holds (or takes) the dispatcher role. ``bind``: the session factory (default: the
    process's). ``previous_shortfall``: the last pass's ``shortfall`` (lost messages are
    re-sent only when two passes running found them missing)."""
    settings = settings or get_settings()
    now = now or datetime.now(UTC)
    ttl = max(3.0 * settings.dispatch_period_s, settings.lease_seconds / 2)
    with session_scope(bind, immediate=True) as s:
        if not try_lead(s, ROLE, actor, ttl, now=now):
            return PassReport(leader=False)
    with session_scope(bind, immediate=True) as s:
        reaped = requeue_expired(s, now, max_attempts=settings.max_attempts, actor=actor)
    report = PassReport(
        leader=True, requeued=reaped.requeued, failed=reaped.failed, cancelled=reaped.cancelled
    )
    depth = queue_depth()
    report.broker_depth = depth
    stale_before, stale_limit = None, 0
    if depth is not None:
        with session_scope(bind) as s:  # counted after the depth: a claim between the two
            missing = max(0, queued_sent_count(s) - depth)  # makes it smaller, not larger
        report.shortfall = missing
        confirmed = min(missing, previous_shortfall or 0)
        if confirmed > 0:
            stale_before = now - timedelta(seconds=settings.lease_seconds)
            stale_limit = confirmed
    with session_scope(bind, immediate=True) as s:
        ids = claim_sends(
            s,
            backoff_s=backoff_schedule(settings.lease_seconds),
            stale_before=stale_before,
            stale_limit=stale_limit,
            resend=depth is None,
            actor=actor,
            now=now,
        )
    if ids:
        report.failed_sends = _send_claimed(ids, send, actor, settings, bind, now)
        report.sent = [i for i in ids if i not in set(report.failed_sends)]
    if report.sent or report.failed_sends or report.requeued or report.failed or report.cancelled:
        log.info(
            "dispatcher: sent %d, send failed %d, requeued %s, failed %s, cancelled %s "
            "(broker depth %s)",
            len(report.sent), len(report.failed_sends), list(report.requeued),
            list(report.failed), list(report.cancelled), depth,
        )  # fmt: skip
    return report


class Dispatcher(threading.Thread):
    """Runs :func:`dispatch_pass` every ``settings.dispatch_period_s`` until :meth:`stop`.

    Start it in every worker process and server; the database elects one active at a time.
    """

    def __init__(
        self,
        send: Send,
        queue_depth: QueueDepth,
        settings: Settings | None = None,
        *,
        actor: str | None = None,
    ) -> None:
        super().__init__(name="legopt-dispatcher", daemon=True)
        self.settings = settings or get_settings()
        self.send, self.queue_depth = send, queue_depth
        self.actor = actor or process_actor("dispatcher")
        self._stop_event = threading.Event()

    def run(self) -> None:
        shortfall: int | None = None
        while not self._stop_event.wait(self.settings.dispatch_period_s):
            try:
                report = dispatch_pass(
                    self.send, self.queue_depth, actor=self.actor, settings=self.settings,
                    previous_shortfall=shortfall,
                )  # fmt: skip
                shortfall = report.shortfall
            except Exception:
                log.exception("dispatcher pass failed (retrying next period)")
        try:
            with session_scope(immediate=True) as s:
                release_lead(s, ROLE, self.actor)
        except Exception:
            log.warning("dispatcher: could not release its role", exc_info=True)

    def stop(self, timeout: float | None = 5.0) -> None:
        """Stop after the current pass and release the role."""
        self._stop_event.set()
        if self.is_alive() and threading.current_thread() is not self:
            self.join(timeout)


__all__ = ["Dispatcher", "PassReport", "ROLE", "dispatch_pass", "process_actor", "send_now"]
