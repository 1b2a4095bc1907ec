"""Batched progress (issue 12): ``record_generations`` writes many rows in one UPDATE + one
INSERT and answers ``cancel_requested``; ``renew_lease`` answers it too; fronts are stored as
float64 bytes and read back as before (lists of rows, ``None`` where not finite)."""

from __future__ import annotations

from datetime import UTC, datetime

import numpy as np
import pytest
from sqlalchemy import Engine

from services.store import (
    JobRecord,
    LeaseLostError,
    claim_job,
    create_api_key,
    create_job,
    get_job,
    list_generations,
    record_generation,
    request_cancel,
    session_scope,
)
from services.store.front_codec import decode_front, decode_front_array, encode_front
from services.store.lifecycle import heartbeat, renew_lease
from services.store.progress import record_generations
from services.store.records import GenerationIn

T0 = datetime(2026, 3, 1, 8, 0, tzinfo=UTC)


def _running(engine: Engine, worker: str = "w1") -> JobRecord:
    with session_scope(engine) as s:
        key = create_api_key(s, name="k", key_hash=f"h-{datetime.now().timestamp()}")
        job = create_job(s, owner_key_id=key.id, spec={"seed": 1}, total_generations=10)
        assert claim_job(s, job.id, worker, 30.0, now=T0) is not None
    return job


def _rows(gens: range, front: bool = True) -> list[GenerationIn]:
    F = np.array([[1.0, 2.0], [1.5, np.inf], [2.0, 0.5]])
    return [
        GenerationIn(g, 10 * g, [float(g), -1.0], 0.01, 0.5 * g, F + g if front else None)
        for g in gens
    ]


def test_front_codec_round_trip_is_exact_with_none_for_non_finite() -> None:
    F = np.array([[0.1, 2.0, -3.25], [np.nan, 1e-3, np.inf]])
    blob = encode_front(F)
    assert blob is not None and len(blob) == 8 + 8 * F.size
    back = decode_front(blob)
    assert back[1][0] is None and back[1][2] is None and back[0] == [0.1, 2.0, -3.25]
    np.testing.assert_array_equal(decode_front_array(blob)[1], [np.nan, 1e-3, np.nan])
    assert encode_front(None) is None and encode_front(np.zeros((0, 2))) is None
    assert decode_front(encode_front([[1.0, None]]) or b"") == [[1.0, None]]


def test_a_batch_is_written_at_once_and_advances_progress(engine: Engine) -> None:
    job = _running(engine)
    with session_scope(engine) as s:
        assert record_generations(s, job.id, "w1", _rows(range(1, 4))) is False
    with session_scope(engine) as s:
        rows = list_generations(s, job.id)
        rec = get_job(s, job.id)
    assert [r.generation for r in rows] == [1, 2, 3]
    assert rec is not None and rec.progress_generation == 3 and rec.best_objective == [3.0, -1.0]
    assert rows[1].front == [[3.0, 4.0], [3.5, None], [4.0, 2.5]]  # the same answer as JSON
    assert rows[2].n_evals == 30 and rows[2].hypervolume == 1.5 and rows[2].best == [3.0, -1.0]


def test_a_batch_is_idempotent_and_never_moves_progress_back(engine: Engine) -> None:
    job = _running(engine)
    with session_scope(engine) as s:
        record_generations(s, job.id, "w1", _rows(range(1, 6)))
    with session_scope(engine) as s:  # a resumed job re-runs 4..5, then goes on to 6
        record_generations(s, job.id, "w1", _rows(range(4, 7), front=False))
        assert record_generation(
            s, job.id, "w1", generation=2, n_evals=1, best=0.0, wall_time_s=0.0
        ) is False  # fmt: skip
    with session_scope(engine) as s:
        rows = list_generations(s, job.id)
        rec = get_job(s, job.id)
    assert [r.generation for r in rows] == [1, 2, 3, 4, 5, 6]
    assert rows[3].front is not None and rows[5].front is None  # the first write kept
    assert rec is not None and rec.progress_generation == 6
    with session_scope(engine) as s:  # an old batch alone: no progress change, still ours
        assert record_generations(s, job.id, "w1", _rows(range(1, 3))) is False
        assert record_generations(s, job.id, "w1", []) is False
    assert _progress(engine, job.id) == 6


def _progress(engine: Engine, job_id: str) -> int:
    with session_scope(engine) as s:
        rec = get_job(s, job_id)
    assert rec is not None
    return rec.progress_generation


def test_a_batch_answers_cancellation_and_a_stale_worker_writes_nothing(engine: Engine) -> None:
    job = _running(engine)
    with session_scope(engine) as s:
        request_cancel(s, job.id)
    with session_scope(engine) as s:
        assert record_generations(s, job.id, "w1", _rows(range(1, 3))) is True
        assert record_generations(s, job.id, "w1", []) is True
    with pytest.raises(LeaseLostError), session_scope(engine) as s:
        record_generations(s, job.id, "stale", _rows(range(3, 5)))
    with session_scope(engine) as s:
        assert [r.generation for r in list_generations(s, job.id)] == [1, 2]
    assert _progress(engine, job.id) == 2


def test_renew_lease_answers_lost_or_the_cancel_flag(engine: Engine) -> None:
    job = _running(engine)
    with session_scope(engine) as s:
        assert renew_lease(s, job.id, "w1", 30.0) is False
        assert renew_lease(s, job.id, "w2", 30.0) is None
        assert heartbeat(s, job.id, "w1", 30.0) and not heartbeat(s, job.id, "w2", 30.0)
        request_cancel(s, job.id)
        assert renew_lease(s, job.id, "w1", 30.0) is True
