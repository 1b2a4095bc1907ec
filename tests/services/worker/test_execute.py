"""The job executor in-process on a real SQLite database: failures end as ``failed`` with a
message naming the field (the worker never raises), a broken recording is only a warning, and a
job resumed from a checkpoint ends exactly where the uninterrupted run ends."""

from __future__ import annotations

import json
from datetime import timedelta
from typing import Any

import pytest

from legcore.optimizers import to_jsonable
from legcore.runner import prepare
from services.store import api_keys
from services.store import output_queries as oq
from services.store import repository as repo
from services.store.keys import generate_api_key
from services.store.lifecycle import claim_job, requeue_expired
from services.store.progress import latest_checkpoint, save_checkpoint
from services.store.session import session_scope
from services.store.settings import Settings
from services.store.sql import now_utc
from services.worker import execute, recycling

SPEC: dict[str, Any] = {
    "problem": {"kind": "quadruped_gait"},
    "budget": {"generations": 6},
    "seed": 3,
    "record": False,
}


def _job(spec: dict[str, Any], total: int = 6) -> str:
    with session_scope() as s:
        key = api_keys.create_api_key(s, name="t", key_hash=generate_api_key()[1])
        return repo.create_job(s, owner_key_id=key.id, spec=spec, total_generations=total).id


def _get(job_id: str) -> Any:
    with session_scope() as s:
        return repo.get_job(s, job_id)


def test_unrunnable_spec_fails_with_the_field_and_the_worker_survives(settings: Settings) -> None:
    bad = {**SPEC, "problem": {"kind": "quadruped_gait", "step_lenght": 0.1}}
    job_id = _job(bad)
    outcome = execute.execute_job(job_id, settings, wid="w1")
    assert outcome.status == "failed"
    job = _get(job_id)
    assert job.status == "failed"
    assert "problem.step_lenght" in job.error_message
    assert "Extra inputs are not permitted" in job.error_message


def test_a_failing_recording_is_a_warning_not_a_failure(
    settings: Settings, monkeypatch: pytest.MonkeyPatch
) -> None:
    from services.recording import writer

    def broken(*_: Any, **__: Any) -> None:
        raise OSError("disk full")

    monkeypatch.setattr(writer, "write_recording", broken)
    job_id = _job({**SPEC, "record": True})
    assert execute.execute_job(job_id, settings, wid="w1").status == "succeeded"
    job = _get(job_id)
    assert job.status == "succeeded"
    assert any("recording failed: OSError: disk full" in w for w in job.warnings)
    with session_scope() as s:
        assert oq.get_artifact(s, job_id, "recording") is None
        assert oq.get_artifact(s, job_id, "result") is not None


def test_resume_from_checkpoint_ends_where_the_uninterrupted_run_ends(settings: Settings) -> None:
    reference = _job(SPEC)
    assert execute.execute_job(reference, settings, wid="w1").status == "succeeded"

    # A second job: worker "dead" claims it, runs 3 generations, checkpoints, and vanishes.
    job_id = _job(SPEC)
    t0 = now_utc()
    with session_scope() as s:
        assert claim_job(s, job_id, "dead", settings.lease_seconds, now=t0) is not None
    prepared = prepare(SPEC)
    run = prepared.new_run()
    for _ in range(3):
        run.step()
    blob = json.dumps(to_jsonable(run.state_dict())).encode()
    with session_scope() as s:
        save_checkpoint(s, job_id, "dead", generation=3, state=blob)
        report = requeue_expired(s, t0 + timedelta(seconds=settings.lease_seconds + 1))
    assert report.requeued == (job_id,)

    outcome = execute.execute_job(job_id, settings, wid="w2")
    assert outcome.status == "succeeded" and outcome.resumed_from == 3
    with session_scope() as s:
        a, b = oq.get_result(s, reference), oq.get_result(s, job_id)
        job = repo.get_job(s, job_id)
    assert b.best_x == a.best_x and b.objectives == a.objectives and b.metrics == a.metrics
    assert job.attempt_count == 2
    assert any("resumed from the checkpoint of generation 3" in w for w in job.warnings)


def test_a_cancelled_job_is_not_run(settings: Settings) -> None:
    job_id = _job(SPEC)
    with session_scope() as s:
        from services.store.lifecycle import request_cancel

        request_cancel(s, job_id)
    assert execute.execute_job(job_id, settings, wid="w1").status == "not-claimed"
    assert _get(job_id).status == "cancelled"


def test_progress_rows_are_all_written_when_batched(
    settings: Settings, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Rows are flushed in batches (every 0.5 s or at a checkpoint); none is lost at the end.
    The final state is checkpointed when the last checkpoint is ``CHECKPOINT_MIN_S`` old (a
    job shorter than that has none: re-running it costs less than its checkpoint)."""
    sparse = settings.with_overrides(checkpoint_every=1000)
    for min_s, final in ((execute.CHECKPOINT_MIN_S, None), (0.0, 8)):
        monkeypatch.setattr(execute, "CHECKPOINT_MIN_S", min_s)
        job_id = _job({**SPEC, "budget": {"generations": 8}}, total=8)
        assert execute.execute_job(job_id, sparse, wid="w1").status == "succeeded"
        with session_scope() as s:
            rows = oq.list_generations(s, job_id)
            ckpt = latest_checkpoint(s, job_id)
        assert [r.generation for r in rows] == list(range(1, 9))
        assert (ckpt and ckpt.generation) == final


def test_a_stale_worker_never_overwrites_the_winners_artifacts(
    settings: Settings, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Defect 6: a worker paused past its lease and resumed wrote its recording over the
    winner's (same fixed path) before finish_job refused it: the download then answered 500
    forever. Now each attempt writes under its own directory and only the lease holder's
    files are recorded; the loser removes its own."""
    from services.store.artifacts import ArtifactStore

    job_id = _job({**SPEC, "record": True})
    real_store = execute._store_result
    paused: dict[str, Any] = {}

    def stale_store(jid: str, wid: str, *args: Any) -> None:
        if wid == "stale":  # paused before its artifacts: meanwhile the lease expires...
            paused["args"] = (jid, wid, *args)
            raise execute.LeaseLostError("pretend the lease ran out while paused")
        real_store(jid, wid, *args)

    monkeypatch.setattr(execute, "_store_result", stale_store)
    assert execute.execute_job(job_id, settings, wid="stale").status == "lease-lost"
    with session_scope() as s:  # the stale worker's lease expired
        requeue_expired(s, now_utc() + timedelta(seconds=settings.lease_seconds + 1))
    assert execute.execute_job(job_id, settings, wid="winner").status == "succeeded"
    with session_scope() as s:
        art = oq.get_artifact(s, job_id, "recording")
    assert art is not None
    store = ArtifactStore.from_settings(settings)
    winner_bytes = store.read(art.relative_path, art.sha256)
    # ... and the stale worker resumes: it writes its own files, then finish_job refuses it
    with pytest.raises(execute.LeaseLostError):
        real_store(*paused["args"])
    assert store.read(art.relative_path, art.sha256) == winner_bytes  # checksum still holds
    attempts = sorted(p.name for p in (store.root / job_id).iterdir())
    assert attempts == [art.relative_path.split("/")[1]]  # the loser's directory is gone


def test_a_solo_worker_past_its_memory_limit_stops_after_the_job(
    settings: Settings, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Worker recycling without forking: past ``worker_max_memory_mb`` a solo worker asks
    Celery for a warm shutdown after its job (``serve`` or compose starts a fresh one)."""
    from celery.worker import state

    assert recycling.resident_mb() > 10  # the real one reads /proc
    monkeypatch.setattr(state, "should_stop", None)
    monkeypatch.setattr(recycling, "resident_mb", lambda: 500.0)
    recycling.recycle_if_large(settings.with_overrides(worker_max_memory_mb=1000))
    assert state.should_stop is None
    recycling.recycle_if_large(settings.with_overrides(worker_max_memory_mb=0))  # off
    assert state.should_stop is None
    recycling.recycle_if_large(settings.with_overrides(worker_max_memory_mb=100))
    assert state.should_stop == 0
