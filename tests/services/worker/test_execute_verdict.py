"""Infeasible is never "succeeded" without saying so (issue 25, item 2): the real executor runs
a gait the robot cannot hold (a 20 mm static margin on seed 003's quadruped, whose best step
keeps ~2.4 mm) and a feasible one, and each job row carries the verdict its result.json has —
``feasible`` and the optimum's violations with their amounts — beside ``status: succeeded``;
the result keeps the task the job ran. Every parameter is given, so the runs do not depend on
the study's robot-relative defaults."""

from __future__ import annotations

import json
from typing import Any

from services.store import api_keys
from services.store import output_queries as oq
from services.store import repository as repo
from services.store.artifacts import ArtifactStore
from services.store.keys import generate_api_key
from services.store.session import session_scope
from services.store.settings import Settings
from services.worker import execute
from tests.gait_specs import GAIT, UNSTABLE


def _run(spec: dict[str, Any], settings: Settings) -> tuple[Any, dict[str, Any], Any]:
    """Run ``spec`` to its end: the job row, its result.json and its stored result."""
    with session_scope() as s:
        key = api_keys.create_api_key(s, name="t", key_hash=generate_api_key()[1])
        job_id = repo.create_job(s, owner_key_id=key.id, spec=spec, total_generations=2).id
    assert execute.execute_job(job_id, settings, wid="w1").status == "succeeded"
    with session_scope() as s:
        job = repo.get_job(s, job_id)
        art = oq.get_artifact(s, job_id, "result")
        result = oq.get_result(s, job_id)
    assert job is not None and art is not None and result is not None
    doc = json.loads(ArtifactStore.from_settings(settings).read(art.relative_path, art.sha256))
    return job, doc, result


def test_an_infeasible_optimum_is_flagged_on_the_job(settings: Settings) -> None:
    job, doc, result = _run(UNSTABLE, settings)
    assert job.status == "succeeded"  # the run completed...
    assert job.feasible is False and doc["feasible"] is False  # ...and its answer is infeasible
    assert job.violations == doc["violations"] and job.violations
    margin = next(v for v in job.violations if v["constraint"] == "stability_margin_mm")
    assert 15.0 < margin["amount"] <= 20.0  # mm short of the 20 mm asked (the best keeps < 5)
    assert result.summary["task"] == doc["task"]
    assert result.summary["task"]["params"]["stability_margin"] == 0.02


def test_a_feasible_optimum_is_flagged_too(settings: Settings) -> None:
    job, doc, _ = _run(GAIT, settings)
    assert job.status == "succeeded" and job.feasible is True and job.violations == []
    assert doc["feasible"] is True and doc["best"]["feasible"] is True
