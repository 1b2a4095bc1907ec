"""Dispatch outbox, elected dispatcher and the audit trail (issue 8, defects 2, 7 and 11).

Each test drives ``services.store.dispatcher.dispatch_pass`` with a fake broker (a list of
sent ids and a queue depth) on SQLite and PostgreSQL, with a simulated clock.
"""

from __future__ import annotations

import threading
from datetime import UTC, datetime, timedelta

import pytest
from sqlalchemy import Engine

from services.store import claim_job, create_api_key, create_job, session_scope
from services.store.dispatch import claim_sends, lead_holder, try_lead
from services.store.dispatcher import PassReport, dispatch_pass, send_now
from services.store.events import count_events, list_events
from services.store.session import make_session_factory
from services.store.settings import Settings
from services.store.states import JobEventKind

T0 = datetime(2026, 11, 23, 12, 0, 0, tzinfo=UTC)
LEASE = 4.0


def _settings() -> Settings:
    return Settings.from_env(
        env={}, lease_seconds=LEASE, heartbeat_seconds=1.0, dispatch_period_s=1.0
    )


def _jobs(engine: Engine, n: int, now: datetime = T0) -> list[str]:
    with session_scope(engine) as s:
        key = create_api_key(s, name="k", key_hash=f"h{now.timestamp()}")
        return [
            create_job(s, owner_key_id=key.id, spec={"i": i}, now=now).id for i in range(n)
        ]


class FakeBroker:
    """Records sends; ``lose()`` drops every queued message (a Redis restart)."""

    def __init__(self) -> None:
        self.sent: list[str] = []
        self.queue: list[str] = []
        self.down = False
        self.shortfall: int | None = None  # the last pass's (what the Dispatcher carries)

    def send(self, job_id: str) -> None:
        if self.down:
            raise ConnectionError("broker down")
        self.sent.append(job_id)
        self.queue.append(job_id)

    def depth(self) -> int | None:
        return None if self.down else len(self.queue)

    def take(self) -> str:
        return self.queue.pop(0)

    def lose(self) -> None:
        self.queue.clear()


def _pass(engine: Engine, broker: FakeBroker, now: datetime, actor: str = "d1") -> PassReport:
    report = dispatch_pass(
        broker.send,
        broker.depth,
        actor=actor,
        settings=_settings(),
        now=now,
        bind=make_session_factory(engine),
        previous_shortfall=broker.shortfall,
    )
    if report.leader:
        broker.shortfall = report.shortfall
    return report


def test_submitted_jobs_are_due_at_once_and_sent_once(engine: Engine) -> None:
    ids = _jobs(engine, 3)
    broker = FakeBroker()
    _pass(engine, broker, T0)
    assert sorted(broker.sent) == sorted(ids)
    _pass(engine, broker, T0 + timedelta(seconds=1))  # messages still queued: nothing re-sent
    assert len(broker.sent) == 3
    with session_scope(engine) as s:
        assert count_events(s, JobEventKind.DISPATCHED, ids) == dict.fromkeys(ids, 1)
        assert [e.kind for e in list_events(s, ids[0])] == ["submitted", "dispatched"]


def test_concurrent_senders_claim_each_send_once(engine: Engine) -> None:
    """The API's immediate send and the dispatcher race for the same due job: one sends."""
    ids = _jobs(engine, 20)
    won: list[list[str]] = [[], []]

    def claim(k: int) -> None:
        with session_scope(engine, immediate=True) as s:
            won[k] = claim_sends(s, backoff_s=(8.0,), now=T0)

    threads = [threading.Thread(target=claim, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(30)
    assert sorted(won[0] + won[1]) == sorted(ids)


def test_requeued_job_whose_resend_failed_is_sent_when_the_broker_is_back(
    engine: Engine,
) -> None:
    """Defect 2: the old reaper committed the requeue, then sent; a failed send (or a lost
    message) left the job queued forever because only never-claimed jobs were rescued."""
    (job_id,) = _jobs(engine, 1)
    broker = FakeBroker()
    _pass(engine, broker, T0)
    broker.take()
    with session_scope(engine, immediate=True) as s:
        assert claim_job(s, job_id, "w1", LEASE, now=T0) is not None  # then w1 dies
    broker.down = True
    t = T0 + timedelta(seconds=LEASE + 1)
    report = _pass(engine, broker, t)
    assert report.requeued == (job_id,) and report.failed_sends == [job_id]
    broker.down = False
    _pass(engine, broker, t + timedelta(seconds=2))
    assert broker.sent == [job_id, job_id]


def test_requeued_job_whose_message_was_lost_is_resent_after_a_lease(engine: Engine) -> None:
    """Defect 2, second form: the re-send succeeded but the broker lost it (205 s queued)."""
    (job_id,) = _jobs(engine, 1)
    broker = FakeBroker()
    _pass(engine, broker, T0)
    broker.take()
    with session_scope(engine, immediate=True) as s:
        claim_job(s, job_id, "w1", LEASE, now=T0)
    t = T0 + timedelta(seconds=LEASE + 1)
    _pass(engine, broker, t)  # requeued and re-sent
    assert broker.sent.count(job_id) == 2
    broker.lose()  # e.g. Redis restarted without persistence
    _pass(engine, broker, t + timedelta(seconds=LEASE / 2))  # not yet: may be in flight
    assert broker.sent.count(job_id) == 2
    _pass(engine, broker, t + timedelta(seconds=LEASE + 0.5))  # a lease later: re-sent
    assert broker.sent.count(job_id) == 3


def test_lost_messages_are_resent_only_for_the_missing_count(engine: Engine) -> None:
    """With a backlog in the broker, only as many jobs as messages are missing are re-sent,
    the ones sent longest ago first."""
    ids = _jobs(engine, 5)
    broker = FakeBroker()
    _pass(engine, broker, T0)
    broker.queue.remove(ids[0])  # two messages lost; three still wait behind busy workers
    broker.queue.remove(ids[1])
    _pass(engine, broker, T0 + timedelta(seconds=LEASE))  # missing: maybe just taken
    assert len(broker.sent) == 5
    _pass(engine, broker, T0 + timedelta(seconds=LEASE + 1))  # still missing: lost
    assert len(broker.sent) == 7  # two re-sends, not five


def test_a_lost_message_is_resent_once_its_timed_resend_is_past(engine: Engine) -> None:
    """CI found jobs queued forever after a Redis restart: their messages were lost while the
    broker was down, and by the time it was back their timed re-send was past due — the due
    path skips sent jobs while the broker can tell its depth, and the lost-message path skipped
    due ones. A lost message is re-sent whatever its timer says."""
    ids = _jobs(engine, 3)
    broker = FakeBroker()
    _pass(engine, broker, T0)
    broker.lose()  # Redis killed with the three messages in it
    broker.down = True
    t = T0 + timedelta(seconds=3 * LEASE)  # past the first timed re-send (2 leases)
    _pass(engine, broker, t)  # down: the timed re-send fails and is given back
    broker.down = False
    _pass(engine, broker, t + timedelta(seconds=1))  # back: three missing (maybe in flight)
    assert broker.queue == []
    _pass(engine, broker, t + timedelta(seconds=LEASE + 1))  # a lease after the last attempt
    assert sorted(broker.queue) == sorted(ids)  # still missing: lost, re-sent


def test_a_message_taken_but_not_yet_claimed_is_not_resent(engine: Engine) -> None:
    """A worker has taken a message and not yet committed its claim: for that one pass the
    broker holds one message fewer than there are queued jobs sent. Not a loss."""
    ids = _jobs(engine, 3)
    broker = FakeBroker()
    _pass(engine, broker, T0)
    t = T0 + timedelta(seconds=2 * LEASE)
    taken = broker.take()  # in flight
    assert _pass(engine, broker, t).shortfall == 1
    with session_scope(engine, immediate=True) as s:
        assert claim_job(s, taken, "w1", LEASE, now=t) is not None  # the claim lands
    assert _pass(engine, broker, t + timedelta(seconds=1)).shortfall == 0
    assert sorted(broker.sent) == sorted(ids)  # nothing re-sent


def test_where_the_broker_cannot_tell_its_depth_due_jobs_are_resent_on_a_backoff(
    engine: Engine,
) -> None:
    ids = _jobs(engine, 2)
    broker = FakeBroker()
    _pass(engine, broker, T0)
    blind = FakeBroker()
    blind.depth = lambda: None  # type: ignore[method-assign]
    _pass(engine, blind, T0 + timedelta(seconds=2 * LEASE))  # 2 leases after the send
    assert sorted(blind.sent) == sorted(ids)


@pytest.mark.slow
def test_one_dispatcher_among_many_and_bounded_duplicates(engine: Engine) -> None:
    """Defect 7: every worker's reaper re-sent every long-queued job on every pass (343
    messages for 22 jobs). Now 4 processes pass every second for 10 minutes over 22 jobs
    queued behind busy workers: one leads, and each job gets few messages."""
    ids = _jobs(engine, 22)
    broker = FakeBroker()
    actors = ["w1", "w2", "w3", "api"]
    leaders = set()
    for second in range(300):
        for actor in actors:
            report = _pass(engine, broker, T0 + timedelta(seconds=second), actor)
            if report.leader:
                leaders.add(actor)
    assert len(leaders) == 1
    per_job = [broker.sent.count(i) for i in ids]
    # the broker says it holds every message: no job is re-sent, however long it waits
    assert per_job == [1] * len(ids), per_job
    with session_scope(engine) as s:
        assert sum(count_events(s, JobEventKind.DISPATCHED, ids).values()) == len(broker.sent)


def test_send_now_failure_leaves_the_job_due(engine: Engine) -> None:
    ids = _jobs(engine, 2)
    broker = FakeBroker()
    broker.down = True
    unsent = send_now(
        ids, broker.send, actor="api", settings=_settings(), bind=make_session_factory(engine)
    )
    assert sorted(unsent) == sorted(ids)
    with session_scope(engine) as s:  # a failed publish withdraws its event
        assert not any(count_events(s, JobEventKind.DISPATCHED, ids).values())
    broker.down = False
    _pass(engine, broker, datetime.now(UTC) + timedelta(seconds=2))
    assert sorted(broker.sent) == sorted(ids)
    with session_scope(engine) as s:
        assert count_events(s, JobEventKind.DISPATCHED, ids) == dict.fromkeys(ids, 1)


class _Killed(BaseException):
    """The sending process dies right after its publish (kill -9 of the API)."""


def test_sender_killed_after_its_publish_leaves_the_dispatched_event(engine: Engine) -> None:
    """CI found a job claimed without any 'dispatched' event: the API was killed between its
    publish and recording the event. The event is recorded with the claim, before the send."""
    (job_id,) = _jobs(engine, 1)
    broker = FakeBroker()

    def send_then_die(jid: str) -> None:
        broker.send(jid)
        raise _Killed

    with pytest.raises(_Killed):
        send_now([job_id], send_then_die, actor="api", settings=_settings(),
                 bind=make_session_factory(engine))  # fmt: skip
    assert broker.sent == [job_id]
    with session_scope(engine) as s:
        assert count_events(s, JobEventKind.DISPATCHED, [job_id]) == {job_id: 1}


def test_dispatcher_role_moves_when_its_holder_stops(engine: Engine) -> None:
    with session_scope(engine, immediate=True) as s:
        assert try_lead(s, "dispatcher", "a", 3.0, now=T0)
    with session_scope(engine, immediate=True) as s:
        assert not try_lead(s, "dispatcher", "b", 3.0, now=T0 + timedelta(seconds=1))
        assert try_lead(s, "dispatcher", "a", 3.0, now=T0 + timedelta(seconds=2))
    with session_scope(engine, immediate=True) as s:  # a paused (SIGSTOP) past its lease
        assert try_lead(s, "dispatcher", "b", 3.0, now=T0 + timedelta(seconds=6))
    with session_scope(engine, immediate=True) as s:  # a resumes: it lost the role
        assert not try_lead(s, "dispatcher", "a", 3.0, now=T0 + timedelta(seconds=7))
        holder = lead_holder(s, "dispatcher")
    assert holder is not None and holder[0] == "b"


@pytest.mark.parametrize("n", [1])
def test_terminal_exactly_once_in_the_events(engine: Engine, n: int) -> None:
    from services.store import fail_job, request_cancel

    ids = _jobs(engine, 2)
    with session_scope(engine, immediate=True) as s:
        claim_job(s, ids[0], "w", LEASE)
        fail_job(s, ids[0], "w", "boom")
        request_cancel(s, ids[1])
        request_cancel(s, ids[1])  # twice: still one terminal event
    with session_scope(engine) as s:
        kinds = [[e.kind.value for e in list_events(s, i)] for i in ids]
    assert kinds[0] == ["submitted", "claimed", "failed"]
    assert kinds[1] == ["submitted", "cancelled"]
