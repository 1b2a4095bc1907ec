"""The worker's cheap path (issue 12): no query per generation for cancellation (the progress
write and the heartbeat answer it), the recording's fronts from memory (no read-back unless the
job was resumed), and checkpoints of fast generations at least ``CHECKPOINT_MIN_S`` apart."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from services.store import api_keys, lifecycle
from services.store import output_queries as oq
from services.store import repository as repo
from services.store.keys import generate_api_key
from services.store.lifecycle import request_cancel
from services.store.progress import latest_checkpoint
from services.store.session import session_scope
from services.store.settings import Settings
from services.worker import execute, generation_keep

SPEC: dict[str, Any] = {
    "problem": {"kind": "hexapod_workspace"},
    "optimizer": {"kind": "moead", "params": {"n_subproblems": 20, "n_neighbors": 5}},
    "budget": {"generations": 6},
    "seed": 1,
    "record": False,
}


def _job(spec: dict[str, Any]) -> str:
    with session_scope() as s:
        key = api_keys.create_api_key(s, name="t", key_hash=generate_api_key()[1])
        total = spec["budget"]["generations"]
        return repo.create_job(s, owner_key_id=key.id, spec=spec, total_generations=total).id


def _no_cancel_query(*_: Any, **__: Any) -> bool:
    raise AssertionError("the worker must not query cancel_requested per generation")


def test_a_cancel_seen_by_the_progress_write_stops_the_job(
    settings: Settings, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(lifecycle, "is_cancel_requested", _no_cancel_query)
    real = execute.record_generations
    calls: list[int] = []

    def cancel_then_record(s: Any, job_id: str, wid: str, rows: Any) -> bool:
        if not calls:  # the user cancels while generation 1 runs
            request_cancel(s, job_id)
        calls.append(len(rows))
        return real(s, job_id, wid, rows)

    monkeypatch.setattr(execute, "record_generations", cancel_then_record)
    job_id = _job(SPEC)
    outcome = execute.execute_job(job_id, settings, wid="w1")
    assert outcome.status == "cancelled" and calls == [1]
    with session_scope() as s:
        job = repo.get_job(s, job_id)
        assert job is not None and job.status == "cancelled" and job.progress_generation == 1
        assert [g.generation for g in oq.list_generations(s, job_id)] == [1]


def test_the_recording_gets_its_fronts_from_memory(
    settings: Settings, monkeypatch: pytest.MonkeyPatch
) -> None:
    from services.recording import writer

    seen: dict[str, Any] = {}

    def fake_write(
        result: Any, path: Path, *, recording_id: str, fronts: Any, **_: Any
    ) -> list[str]:
        seen["fronts"] = fronts
        path.write_bytes(b"rrd")
        return []

    def no_read_back(*_: Any, **__: Any) -> Any:
        raise AssertionError("the worker holds the fronts: no read-back")

    monkeypatch.setattr(writer, "write_recording", fake_write)
    monkeypatch.setattr(generation_keep, "list_generations", no_read_back)
    job_id = _job({**SPEC, "record": True})
    assert execute.execute_job(job_id, settings, wid="w1").status == "succeeded"
    fronts = seen["fronts"]
    assert sorted(fronts) == list(range(1, 7))
    monkeypatch.undo()
    with session_scope() as s:
        stored = {g.generation: g.front for g in oq.list_generations(s, job_id)}
    for g, F in fronts.items():  # exactly what the store keeps (NaN for None)
        np.testing.assert_array_equal(F, np.asarray(stored[g], dtype=float))


def test_fast_generations_are_checkpointed_at_most_once_a_second(
    settings: Settings, monkeypatch: pytest.MonkeyPatch
) -> None:
    saved: list[int] = []
    real = execute.save_checkpoint

    def spy(s: Any, job_id: str, wid: str, *, generation: int, state: bytes) -> None:
        saved.append(generation)
        real(s, job_id, wid, generation=generation, state=state)

    monkeypatch.setattr(execute, "save_checkpoint", spy)
    job_id = _job(SPEC)
    every_2 = settings.with_overrides(checkpoint_every=2)
    assert execute.execute_job(job_id, every_2, wid="w1").status == "succeeded"
    assert saved == []  # 6 generations of a few ms: none (the last keeps the spacing too)
    saved.clear()
    job_id = _job(SPEC)
    assert execute.execute_job(job_id, settings, wid="w1").status == "succeeded"
    assert saved == [1, 2, 3, 4, 5, 6]  # checkpoint_every = 1: every generation, as asked
    with session_scope() as s:
        ckpt = latest_checkpoint(s, job_id)
    assert ckpt is not None and ckpt.generation == 6
