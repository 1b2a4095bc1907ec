"""Job lifecycle: claims, leases, progress, checkpoints, cancellation, outcome, reaper."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import numpy as np
import pytest
from sqlalchemy import Engine, func, select

from services.store import (
    ArtifactIn,
    BaselineIn,
    JobRecord,
    JobStatus,
    LeaseLostError,
    ParetoPointIn,
    ResultIn,
    claim_job,
    create_api_key,
    create_job,
    expired_leases,
    fail_job,
    finish_job,
    get_artifact,
    get_job,
    get_result,
    heartbeat,
    is_cancel_requested,
    latest_checkpoint,
    list_artifacts,
    list_baselines,
    list_generations,
    list_pareto,
    mark_cancelled,
    record_generation,
    request_cancel,
    requeue_expired,
    save_checkpoint,
    session_scope,
)
from services.store.tables import GENERATIONS

T0 = datetime(2026, 3, 1, 8, 0, tzinfo=UTC)
LEASE = 30.0


def _job(engine: Engine, total_generations: int = 10) -> JobRecord:
    with session_scope(engine) as s:
        key = create_api_key(s, name="k", key_hash=f"h-{datetime.now().timestamp()}")
        return create_job(s, owner_key_id=key.id, spec={"seed": 1}, total_generations=10)


def _claim(engine: Engine, job_id: str, worker: str, at: datetime = T0, **kw: object):
    with session_scope(engine) as s:
        return claim_job(s, job_id, worker, LEASE, now=at, **kw)  # type: ignore[arg-type]


def _get(engine: Engine, job_id: str) -> JobRecord:
    with session_scope(engine) as s:
        job = get_job(s, job_id)
    assert job is not None
    return job


def _running(engine: Engine, worker: str = "w1") -> JobRecord:
    job = _job(engine)
    assert _claim(engine, job.id, worker) is not None
    return job


def test_claim_is_exclusive(engine: Engine) -> None:
    job = _job(engine)
    first = _claim(engine, job.id, "w1")
    second = _claim(engine, job.id, "w2")  # e.g. a re-delivered message
    assert first is not None and second is None
    assert first.status is JobStatus.RUNNING and first.lease_owner == "w1"
    assert first.attempt_count == 1 and first.started_at == T0 and first.heartbeat_at == T0
    assert first.lease_expires_at == T0 + timedelta(seconds=LEASE)
    assert _claim(engine, job.id, "w1") is None  # not even by the owner: it is running
    assert _claim(engine, "no-such-job", "w1") is None


def test_expired_lease_is_reclaimed_with_attempt_plus_one(engine: Engine) -> None:
    job = _running(engine, "w1")
    assert _claim(engine, job.id, "w2", T0 + timedelta(seconds=LEASE - 1)) is None
    later = T0 + timedelta(seconds=LEASE + 1)
    again = _claim(engine, job.id, "w2", later)
    assert again is not None and again.lease_owner == "w2" and again.attempt_count == 2
    assert again.started_at == T0  # first start kept
    assert again.lease_expires_at == later + timedelta(seconds=LEASE)
    with session_scope(engine) as s:  # the old worker has lost it
        assert not heartbeat(s, job.id, "w1", LEASE, now=later)
    much_later = later + timedelta(seconds=10 * LEASE)
    assert _claim(engine, job.id, "w3", much_later, max_attempts=2) is None
    assert _claim(engine, job.id, "w3", much_later, max_attempts=3) is not None


def test_heartbeat_only_by_the_owner(engine: Engine) -> None:
    job = _running(engine, "w1")
    t = T0 + timedelta(seconds=20)
    with session_scope(engine) as s:
        assert not heartbeat(s, job.id, "intruder", LEASE, now=t)
        assert heartbeat(s, job.id, "w1", LEASE, now=t)
    rec = _get(engine, job.id)
    assert rec.heartbeat_at == t and rec.lease_expires_at == t + timedelta(seconds=LEASE)
    # the extended lease protects the job from a reclaim at the old expiry
    assert _claim(engine, job.id, "w2", T0 + timedelta(seconds=LEASE + 1)) is None


def test_record_generation_is_idempotent_and_advances_progress(engine: Engine) -> None:
    job = _running(engine)

    def record(gen: int, best: object) -> bool:
        with session_scope(engine) as s:
            return record_generation(
                s,
                job.id,
                "w1",
                generation=gen,
                n_evals=100,
                best=best,
                wall_time_s=0.5,
                hypervolume=float("nan") if gen == 0 else 1.0 + gen,
            )

    assert record(0, [3.0])
    assert record(1, np.array([2.5]))
    assert not record(1, [999.0])  # resumed job re-running generation 1: ignored
    assert record(2, [2.0])
    assert not record(1, [999.0])  # an older generation does not move progress back
    with session_scope(engine) as s:
        rows = list_generations(s, job.id)
        n = s.execute(select(func.count()).select_from(GENERATIONS)).scalar_one()
        assert [g.generation for g in list_generations(s, job.id, after=0)] == [1, 2]
    assert n == 3 and [g.best for g in rows] == [[3.0], [2.5], [2.0]]
    assert rows[0].hypervolume is None and rows[1].hypervolume == 2.0
    rec = _get(engine, job.id)
    assert rec.progress_generation == 2 and rec.best_objective == [2.0]
    assert rec.progress == pytest.approx(0.2)
    with pytest.raises(LeaseLostError):
        with session_scope(engine) as s:
            record_generation(s, job.id, "w2", generation=3, n_evals=1, best=[0.0], wall_time_s=0.1)
    assert _get(engine, job.id).progress_generation == 2


def test_checkpoint_keeps_the_latest(engine: Engine) -> None:
    job = _running(engine)
    with session_scope(engine) as s:
        assert latest_checkpoint(s, job.id) is None
        save_checkpoint(s, job.id, "w1", generation=1, state=b"one")
        save_checkpoint(s, job.id, "w1", generation=3, state=b"three")
        save_checkpoint(s, job.id, "w1", generation=2, state=b"stale")  # ignored
    with session_scope(engine) as s:
        cp = latest_checkpoint(s, job.id)
        assert cp is not None and (cp.generation, cp.state) == (3, b"three")
        with pytest.raises(LeaseLostError):
            save_checkpoint(s, job.id, "w2", generation=4, state=b"x")
    # the next worker resumes from it after a reclaim
    assert _claim(engine, job.id, "w2", T0 + timedelta(hours=1)) is not None
    with session_scope(engine) as s:
        cp = latest_checkpoint(s, job.id)
        assert cp is not None and cp.state == b"three"


def test_cancel_queued_and_running_jobs(engine: Engine) -> None:
    queued = _job(engine)
    with session_scope(engine) as s:
        rec = request_cancel(s, queued.id)
        assert rec is not None and rec.status is JobStatus.CANCELLED
        assert rec.finished_at is not None and is_cancel_requested(s, queued.id)
    assert _claim(engine, queued.id, "w1") is None

    running = _running(engine, "w1")
    with session_scope(engine) as s:
        assert not is_cancel_requested(s, running.id)
        rec = request_cancel(s, running.id, owner_key_id=running.owner_key_id)
        assert rec is not None and rec.status is JobStatus.RUNNING and rec.cancel_requested
        assert is_cancel_requested(s, running.id)
        assert request_cancel(s, running.id, owner_key_id="someone-else") is None
        assert request_cancel(s, "missing") is None
        assert is_cancel_requested(s, "missing")  # a deleted job: stop too
        with pytest.raises(LeaseLostError):
            mark_cancelled(s, running.id, "w2")
        done = mark_cancelled(s, running.id, "w1")
    assert done.status is JobStatus.CANCELLED and done.lease_expires_at is None
    # a cancel-requested job whose worker died is not reclaimed
    assert _claim(engine, running.id, "w2", T0 + timedelta(hours=1)) is None


def _outputs(pareto_indices: list[int]) -> dict[str, object]:
    return {
        "result": ResultIn(
            best_x=np.array([0.1, 0.2]),
            objectives=[1.5],
            metrics={"energy_J": 12.0},
            summary={"evals": 100},
        ),
        "pareto": [
            ParetoPointIn(index=i, x=[float(i)], objectives=[float(i), 1.0 - i])
            for i in pareto_indices
        ],
        "baselines": [BaselineIn(name="parabolic", metrics={"E": 20.0})],
        "artifacts": [ArtifactIn("recording", "j/recording.rrd", "ab" * 32, 1234)],
    }


def test_finish_job_writes_everything(engine: Engine) -> None:
    job = _running(engine)
    t = T0 + timedelta(seconds=5)
    with session_scope(engine) as s:
        done = finish_job(
            s, job.id, "w1", warnings=["3 samples unreachable"], now=t, **_outputs([0, 1, 2])
        )  # type: ignore[arg-type]
    assert done.status is JobStatus.SUCCEEDED and done.finished_at == t
    assert done.progress_generation == done.total_generations and done.progress == 1.0
    assert done.warnings == ["3 samples unreachable"] and done.lease_expires_at is None
    with session_scope(engine) as s:
        result = get_result(s, job.id)
        assert result is not None and result.best_x == [0.1, 0.2]
        assert result.metrics == {"energy_J": 12.0}
        assert [p.index for p in list_pareto(s, job.id)] == [0, 1, 2]
        assert list_pareto(s, job.id)[2].objectives == [2.0, -1.0]
        assert [b.name for b in list_baselines(s, job.id)] == ["parabolic"]
        art = get_artifact(s, job.id, "recording")
        assert art is not None and art.size_bytes == 1234 and list_artifacts(s, job.id) == (art,)
    assert _claim(engine, job.id, "w2", T0 + timedelta(hours=1)) is None  # finished for good


def test_finish_job_is_atomic(engine: Engine) -> None:
    job = _running(engine)
    with pytest.raises(Exception, match="(?i)unique|duplicate"):
        with session_scope(engine) as s:
            finish_job(s, job.id, "w1", **_outputs([0, 1, 1]))  # type: ignore[arg-type]
    rec = _get(engine, job.id)
    assert rec.status is JobStatus.RUNNING and rec.lease_owner == "w1"
    assert rec.finished_at is None
    with session_scope(engine) as s:
        assert get_result(s, job.id) is None
        assert list_pareto(s, job.id) == () and list_baselines(s, job.id) == ()
        assert list_artifacts(s, job.id) == ()

    # atomic even when the caller catches the error and commits its own transaction
    with session_scope(engine) as s:
        with pytest.raises(Exception, match="(?i)unique|duplicate"):
            finish_job(s, job.id, "w1", **_outputs([0, 0]))  # type: ignore[arg-type]
        heartbeat(s, job.id, "w1", LEASE, now=T0 + timedelta(seconds=1))
    with session_scope(engine) as s:
        assert get_result(s, job.id) is None and list_pareto(s, job.id) == ()
        assert _get(engine, job.id).status is JobStatus.RUNNING

    with pytest.raises(LeaseLostError):  # not the owner: nothing written
        with session_scope(engine) as s:
            finish_job(s, job.id, "w2", **_outputs([0]))  # type: ignore[arg-type]
    with session_scope(engine) as s:
        assert get_result(s, job.id) is None
        finish_job(s, job.id, "w1", **_outputs([0, 1]))  # type: ignore[arg-type]
    assert _get(engine, job.id).status is JobStatus.SUCCEEDED


def test_fail_job(engine: Engine) -> None:
    job = _running(engine)
    with session_scope(engine) as s:
        with pytest.raises(LeaseLostError):
            fail_job(s, job.id, "w2", "nope")
        rec = fail_job(s, job.id, "w1", "IK failed for 12 of 225 path points: move the path")
    assert rec.status is JobStatus.FAILED and rec.error_message.startswith("IK failed")
    queued = _job(engine)
    with session_scope(engine) as s:
        assert fail_job(s, queued.id, None, "spec refers to a deleted robot").status == "failed"
        with pytest.raises(LeaseLostError):
            fail_job(s, queued.id, None, "again")


def test_reaper_requeues_cancels_and_fails(engine: Engine) -> None:
    alive, dead, cancelled, poison = (_running(engine, f"w{i}") for i in range(4))
    with session_scope(engine) as s:
        heartbeat(s, alive.id, "w0", LEASE, now=T0 + timedelta(seconds=25))
        request_cancel(s, cancelled.id)
    for _ in range(2):  # the poison job killed two more workers
        t = _get(engine, poison.id).lease_expires_at + timedelta(seconds=1)  # type: ignore[operator]
        assert _claim(engine, poison.id, "wx", t) is not None
    now = T0 + timedelta(seconds=LEASE + 1)
    with session_scope(engine) as s:
        assert set(expired_leases(s, now)) == {dead.id, cancelled.id}
    later = T0 + timedelta(hours=1)
    with session_scope(engine) as s:
        report = requeue_expired(s, later, max_attempts=3)
    assert report.cancelled == (cancelled.id,)
    assert report.failed == (poison.id,)
    assert set(report.requeued) == {alive.id, dead.id}
    requeued = _get(engine, dead.id)
    assert requeued.status is JobStatus.QUEUED and requeued.lease_owner is None
    assert requeued.attempt_count == 1
    assert _get(engine, cancelled.id).status is JobStatus.CANCELLED
    failed = _get(engine, poison.id)
    assert failed.status is JobStatus.FAILED and "stopped responding 3 times" in (
        failed.error_message or ""
    )
    again = _claim(engine, dead.id, "w9", later)
    assert again is not None and again.attempt_count == 2
    with session_scope(engine) as s:
        assert expired_leases(s, later) == ()
        assert requeue_expired(s, later).requeued == ()


def test_lease_length_must_be_positive(engine: Engine) -> None:
    job = _job(engine)
    with pytest.raises(ValueError):
        _claim_with_lease(engine, job.id, 0)


def _claim_with_lease(engine: Engine, job_id: str, lease: float) -> None:
    with session_scope(engine) as s:
        claim_job(s, job_id, "w", lease)
