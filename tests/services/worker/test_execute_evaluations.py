"""Every evaluated solution kept (issue 21, item 1): the worker stores each kept generation's
batch; what is stored is what the optimiser evaluated; the bound holds; resumes write nothing
twice."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from legcore.runner import prepare
from services.store import api_keys
from services.store import repository as repo
from services.store.evaluations import (
    EvaluationsIn,
    evaluation_stride,
    keeps_generation,
    load_evaluations,
    record_evaluations,
)
from services.store.keys import generate_api_key
from services.store.session import session_scope
from services.store.settings import Settings
from services.worker import execute, generation_keep

SPEC: dict[str, Any] = {
    "problem": {"kind": "hexapod_workspace"},
    "optimizer": {"kind": "moead", "params": {"n_subproblems": 20, "n_neighbors": 5}},
    "budget": {"generations": 6},
    "seed": 3,
    "record": False,
}


def _job(spec: dict[str, Any]) -> str:
    with session_scope() as s:
        key = api_keys.create_api_key(s, name="t", key_hash=generate_api_key()[1])
        total = spec["budget"]["generations"]
        return repo.create_job(s, owner_key_id=key.id, spec=spec, total_generations=total).id


def test_stride_and_kept_generations() -> None:
    assert evaluation_stride(100, 100, bound=20_000) == 1
    assert evaluation_stride(100, 1000, bound=20_000) == 5
    kept = [g for g in range(1, 13) if keeps_generation(g, 5, last=g == 12)]
    assert kept == [1, 6, 11, 12]


def test_a_job_stores_what_its_optimiser_evaluated(settings: Settings) -> None:
    job_id = _job(SPEC)
    assert execute.execute_job(job_id, settings, wid="w1").status == "succeeded"
    with session_scope() as s:
        ev = load_evaluations(s, job_id)
    assert ev is not None
    assert sorted(set(ev.generation.tolist())) == [1, 2, 3, 4, 5, 6]
    # The same run by hand, generation by generation: the stored rows are its batches.
    run = prepare(SPEC).new_run()
    batches = []
    while not run.done:
        batches.append(run.step().batch)
    X = np.concatenate([b.X for b in batches])
    F = np.concatenate([b.F for b in batches])
    np.testing.assert_array_equal(ev.X, X)
    np.testing.assert_array_equal(
        np.nan_to_num(ev.F, nan=np.inf), np.where(np.isfinite(F), F, np.inf)
    )
    np.testing.assert_array_equal(ev.cv, np.concatenate([b.cv for b in batches]))
    problem = prepare(SPEC).problem
    assert ev.X.shape[1] == problem.n_var
    F2, _ = problem.evaluate(ev.X)  # each stored objective vector is its stored solution's
    np.testing.assert_allclose(
        np.nan_to_num(ev.F, nan=1e300), np.nan_to_num(F2, nan=1e300, posinf=1e300)
    )


def test_the_bound_holds(settings: Settings, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(generation_keep, "MAX_STORED_EVALUATIONS", 50)
    monkeypatch.setattr(
        generation_keep, "evaluation_stride", lambda p, g: evaluation_stride(p, g, bound=50)
    )
    job_id = _job(SPEC)
    assert execute.execute_job(job_id, settings, wid="w1").status == "succeeded"
    with session_scope() as s:
        ev = load_evaluations(s, job_id)
    assert ev is not None
    gens = sorted(set(ev.generation.tolist()))
    assert gens[0] == 1 and gens[-1] == 6 and len(gens) < 6
    assert len(ev) <= 50 + 20  # the bound, plus the last generation


def test_duplicates_are_ignored(settings: Settings) -> None:
    job_id = _job(SPEC)
    batch = EvaluationsIn(1, np.ones((3, 2)), np.zeros((3, 2)), np.zeros(3))
    with session_scope() as s:
        record_evaluations(s, job_id, [batch])
        record_evaluations(s, job_id, [EvaluationsIn(1, 2 * np.ones((3, 2)), batch.F, batch.cv)])
    with session_scope() as s:
        ev = load_evaluations(s, job_id)
    assert ev is not None and len(ev) == 3 and float(ev.X[0, 0]) == 1.0
