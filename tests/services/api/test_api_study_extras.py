"""A job's study extras are made by the API when first asked for (issue 23: the worker no
longer makes and serialises them at the end of every job): a real job run by the real
executor leaves a ``result.json`` without them; ``GET /jobs/{id}/result`` makes them from the
stored spec and front — equal to ``legcore.run``'s of the same spec — keeps them as the
artifact ``extras`` and serves them from it afterwards; a job of an older worker, whose
``result.json`` holds them, is served from that file."""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any

import pytest
from api_helpers import FreshApp, fresh_app

import legcore
from legcore.runner import RunResult
from services.api import study_extras
from services.store import output_queries as oq
from services.store.types import json_safe
from services.worker.execute import execute_job

pytestmark = pytest.mark.slow  # real jobs: the quick lane leaves it out

API = "/api/v1"
SPEC: dict[str, Any] = {
    "name": "extras on demand",
    "problem": {"kind": "hexapod_workspace", "pose_xy_step": 0.01, "pose_yaw_step": 0.3},
    "optimizer": {"kind": "moead", "params": {"n_subproblems": 20}},
    "budget": {"generations": 3},
    "seed": 5,
    "record": False,
}


@pytest.fixture(scope="module")
def app(tmp_path_factory: pytest.TempPathFactory) -> Iterator[FreshApp]:
    with fresh_app(tmp_path_factory.mktemp("extras"), "alice") as a:
        yield a


def _job(app: FreshApp, spec: dict[str, Any]) -> str:
    r = app.client.post(f"{API}/jobs", json=spec, headers=app.keys["alice"])
    assert r.status_code == 202, r.text
    job = str(r.json()["id"])
    assert execute_job(job, app.settings).status == "succeeded"
    return job


def _result_json(app: FreshApp, job: str) -> dict[str, Any]:
    with app.ctx.read() as s:
        art = oq.get_artifact(s, job, "result")
    assert art is not None
    return dict(json.loads(app.ctx.artifacts.read(art.relative_path, art.sha256)))


def _extras(app: FreshApp, job: str) -> Any:
    r = app.client.get(f"{API}/jobs/{job}/result", headers=app.keys["alice"])
    assert r.status_code == 200, r.text
    assert "extras_warning" not in r.json()["summary"]
    return r.json()["summary"]["extras"]


def test_extras_are_made_on_demand_equal_to_the_run_and_kept(
    app: FreshApp, monkeypatch: pytest.MonkeyPatch
) -> None:
    job = _job(app, SPEC)
    assert "extras" not in _result_json(app, job)  # the worker did not make them
    expected = json.loads(json.dumps(json_safe(legcore.run(SPEC).extras)))
    assert expected["pose_workspace"]["n_reachable"] and expected["front"]
    assert _extras(app, job) == expected
    with app.ctx.read() as s:
        assert oq.get_artifact(s, job, study_extras.EXTRAS) is not None

    def never(*_a: Any) -> Any:
        raise AssertionError("made again although kept")

    monkeypatch.setattr(study_extras, "_make", never)
    assert _extras(app, job) == expected  # from the artifact


def test_extras_of_an_older_worker_are_read_from_result_json(
    app: FreshApp, monkeypatch: pytest.MonkeyPatch
) -> None:
    plain = RunResult.to_dict
    monkeypatch.setattr(RunResult, "to_dict", lambda self, extras=True: plain(self))
    job = _job(app, {**SPEC, "seed": 6})
    monkeypatch.undo()
    held = _result_json(app, job)["extras"]
    assert held["front"]
    monkeypatch.setattr(study_extras, "_make", lambda *_a: pytest.fail("made, not read"))
    assert _extras(app, job) == held
    with app.ctx.read() as s:
        assert oq.get_artifact(s, job, study_extras.EXTRAS) is None
