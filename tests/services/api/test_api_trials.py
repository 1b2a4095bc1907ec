"""Every evaluated solution explorable (issue 21, item 1): a job run in-process by the real
executor stores its trials; the API filters, sorts and pages them, gives their columns for a
parallel-coordinates plot, and decodes any trial — not only a front point — into its motion
and a Rerun recording."""

from __future__ import annotations

import hashlib
from collections.abc import Iterator
from typing import Any

import pytest
from api_helpers import fresh_app

from services.worker.execute import execute_job

pytestmark = pytest.mark.slow  # the quick lane (run.py test --quick) leaves it out

API = "/api/v1"
POP, GENS = 16, 5
NAMES = ["time", "energy"]  # the study's objectives, in the front's order
E = NAMES.index("energy")
SPEC: dict[str, Any] = {
    "name": "trials",
    "problem": {"kind": "path_tracking", "objective": "energy_time"},
    "optimizer": {"kind": "nsga2", "params": {"pop_size": POP}},
    "budget": {"generations": GENS},
    "seed": 4,
}


@pytest.fixture(scope="module")
def env(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """An app on a fresh database with one job of Alice's run to the end; Bob's key."""
    with fresh_app(tmp_path_factory.mktemp("trials"), "alice", "bob") as app:
        client, alice = app.client, app.keys["alice"]
        r = client.post(f"{API}/jobs", json=SPEC, headers=alice)
        assert r.status_code == 202, r.text
        job_id = r.json()["id"]
        before = client.get(f"{API}/jobs/{job_id}/trials", headers=alice).json()
        assert execute_job(job_id, app.settings).status == "succeeded"
        yield {"client": client, "job": job_id, "before": before, **app.keys}


def _all(env: dict[str, Any], query: str = "") -> dict[str, Any]:
    r = env["client"].get(f"{API}/jobs/{env['job']}/trials?limit=1000{query}", headers=env["alice"])
    assert r.status_code == 200, r.text
    return r.json()


def test_every_evaluation_is_stored_and_labelled(env: dict[str, Any]) -> None:
    before = env["before"]  # a queued job: nothing yet, but its columns are known
    assert before["stored"] == 0 and before["items"] == []
    assert sorted(q["name"] for q in before["objectives"]) == ["energy", "time"]
    page = _all(env)
    gens = env["client"].get(f"{API}/jobs/{env['job']}/generations", headers=env["alice"])
    n_evals = gens.json()["items"][-1]["n_evals"]
    assert page["stored"] == page["matched"] == n_evals == len(page["items"])
    assert page["generations"] == list(range(1, GENS + 1))
    assert [q["name"] for q in page["objectives"]] == NAMES
    assert all(q["unit"] for q in page["objectives"])  # J, s
    row = page["items"][0]
    assert row["trial"] == 0 and row["generation"] == 1
    assert len(row["x"]) == len(page["variables"]) and len(row["objectives"]) == 2


def test_sort_filter_and_page(env: dict[str, Any]) -> None:
    everything = _all(env)["items"]
    asc = _all(env, "&sort=energy")["items"]
    energies = [r["objectives"][E] for r in asc]
    assert energies == sorted(energies)
    desc = _all(env, f"&sort=f{1 - E + 1}&descending=true")["items"]
    times = [r["objectives"][1 - E] for r in desc]
    assert times == sorted(times, reverse=True)
    feasible = sorted(r["objectives"][E] for r in everything if r["feasible"])
    assert feasible, "the job found no feasible solution"
    lo, hi = feasible[len(feasible) // 4], feasible[3 * len(feasible) // 4]
    ranged = _all(env, f"&range=energy:{lo}:{hi}&feasible=true")
    expected = [r for r in everything if lo <= r["objectives"][E] <= hi and r["feasible"]]
    assert ranged["matched"] == len(expected) > 0
    assert [r["trial"] for r in ranged["items"]] == [r["trial"] for r in expected]
    gen3 = _all(env, "&generation=3")["items"]
    assert gen3 and {r["generation"] for r in gen3} == {3}
    page2 = (
        env["client"]
        .get(f"{API}/jobs/{env['job']}/trials?limit=5&offset=5&sort=energy", headers=env["alice"])
        .json()
    )
    assert [r["trial"] for r in page2["items"]] == [r["trial"] for r in asc[5:10]]


def test_bad_queries_name_their_field(env: dict[str, Any]) -> None:
    client, alice, job = env["client"], env["alice"], env["job"]
    for query, field in (("sort=colour", "sort"), ("range=f1:a:b", "range"),
                         ("range=x999:0:1", "range"), ("range=f1", "range")):  # fmt: skip
        r = client.get(f"{API}/jobs/{job}/trials?{query}", headers=alice)
        assert r.status_code == 422, (query, r.text)
        assert r.json()["detail"][0]["loc"] == ["query", field]
        assert "f1" in r.json()["detail"][0]["msg"] or "COLUMN" in r.json()["detail"][0]["msg"]
    assert client.get(f"{API}/jobs/{job}/trials", headers=env["bob"]).status_code == 404


def test_columns_for_parallel_coordinates(env: dict[str, Any]) -> None:
    client, alice, job = env["client"], env["alice"], env["job"]
    cols = client.get(f"{API}/jobs/{job}/trials/columns", headers=alice).json()
    n = cols["matched"]
    assert len(cols["trial"]) == n and len(cols["feasible"]) == n
    assert len(cols["x_values"]) == len(cols["variables"])
    assert all(len(v) == n for v in cols["x_values"] + cols["objective_values"])
    assert len(cols["objective_values"]) == 2
    small = client.get(f"{API}/jobs/{job}/trials/columns?max_rows=10", headers=alice).json()
    assert len(small["trial"]) == 10 and small["trial"][-1] == n - 1


def test_a_non_front_trial_has_its_motion_and_recording(env: dict[str, Any]) -> None:
    client, alice, job = env["client"], env["alice"], env["job"]
    front = client.get(f"{API}/jobs/{job}/front", headers=alice).json()
    front_x = [p["x"] for p in front["points"]]
    rows = _all(env)["items"]
    trial = next(r for r in rows if r["x"] not in front_x)  # not on the front
    r = client.get(f"{API}/jobs/{job}/motion?trial={trial['trial']}", headers=alice)
    assert r.status_code == 200, r.text
    motion = r.json()
    assert motion["source"] == "trial" and motion["index"] == trial["trial"]
    assert motion["x"] == pytest.approx(trial["x"])
    assert [motion["objectives"][n] for n in NAMES] == pytest.approx(trial["objectives"])
    url = motion["recording_url"]
    assert url.endswith(f"/trials/{trial['trial']}/recording")
    rec = client.get(url, headers=alice)
    assert rec.status_code == 200, rec.text
    assert hashlib.sha256(rec.content).hexdigest() == rec.headers["x-checksum-sha256"]
    again = client.get(url, headers=alice)  # cached as an artifact: the same bytes
    assert again.content == rec.content
    missing = client.get(f"{API}/jobs/{job}/motion?trial=999999", headers=alice)
    assert missing.status_code == 404 and "no trial 999999" in missing.json()["detail"]
    for bad in ("²", "x", "1234567890"):  # a path index: ASCII digits only, else a 404
        r = client.get(f"{API}/jobs/{job}/trials/{bad}/recording", headers=alice)
        assert r.status_code == 404 and f"no trial {bad!r}" in r.json()["detail"], bad


def test_parameter_importance(env: dict[str, Any]) -> None:
    client, alice, job = env["client"], env["alice"], env["job"]
    r = client.get(f"{API}/jobs/{job}/trials/importance", headers=alice)
    assert r.status_code == 200, r.text
    imp = r.json()
    assert "RandomForestRegressor" in imp["method"] and imp["trials"] > 10
    assert len(imp["importance"]) == 2
    for row in imp["importance"]:
        assert len(row) == len(imp["variables"])
        assert sum(row) == pytest.approx(1.0) and min(row) >= 0.0
    again = client.get(f"{API}/jobs/{job}/trials/importance", headers=alice).json()
    assert again == imp  # the same forest (seed 0), cached for a finished job


def test_importance_finds_the_variable_that_matters() -> None:
    """On synthetic trials where f1 depends only on x2 and f2 only on x1 and x3."""
    import numpy as np

    from services.api.importance import importance
    from services.api.trial_view import TrialSet
    from services.store.evaluations import Evaluations

    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, (400, 4))
    F = np.stack([X[:, 1] ** 2, X[:, 0] + 0.5 * X[:, 2]], axis=1)
    ev = Evaluations(np.repeat(np.arange(1, 5), 100), X, F, np.zeros(400))
    out = importance(TrialSet("j", ev, ("a", "b")))
    assert int(np.argmax(out.importance[0])) == 1 and out.importance[0][1] > 0.8
    assert {int(i) for i in np.argsort(out.importance[1])[-2:]} == {0, 2}


def test_rows_and_columns_serve_non_finite_values_as_null() -> None:
    """NaN and ±inf (a failed evaluation's objectives) are null in the rows and the columns;
    every other value is a plain float, in the trials' order; an empty selection is empty."""
    import numpy as np

    from services.api.trial_view import TrialSet, trial_columns, trial_rows
    from services.store.evaluations import Evaluations

    nan, inf = float("nan"), float("inf")
    X = np.array([[0.5, -1.0], [nan, 2.0], [3.0, inf]])
    F = np.array([[1.0, nan], [-inf, 2.5], [0.0, 7.0]])
    ev = Evaluations(np.array([1, 1, 2]), X, F, np.array([0.0, 0.25, 0.0]))
    trials = TrialSet("j", ev, ("a", "b"))
    rows = trial_rows(trials, np.array([2, 0, 1]))
    assert [r.model_dump() for r in rows] == [
        {"trial": 2, "generation": 2, "x": [3.0, None], "objectives": [0.0, 7.0], "cv": 0.0,
         "feasible": True},
        {"trial": 0, "generation": 1, "x": [0.5, -1.0], "objectives": [1.0, None], "cv": 0.0,
         "feasible": True},
        {"trial": 1, "generation": 1, "x": [None, 2.0], "objectives": [None, 2.5], "cv": 0.25,
         "feasible": False},
    ]  # fmt: skip
    assert all(type(v) is float for r in rows for v in r.x + r.objectives if v is not None)
    cols = trial_columns(trials, np.arange(3), 10)
    assert cols.trial == [0, 1, 2] and cols.feasible == [True, False, True]
    assert cols.x_values == [[0.5, None, 3.0], [-1.0, 2.0, None]]
    assert cols.objective_values == [[1.0, None, 0.0], [None, 2.5, 7.0]]
    assert all(type(v) is float for c in cols.x_values + cols.objective_values for v in c
               if v is not None)  # fmt: skip
    none = np.array([], dtype=int)
    assert trial_rows(trials, none) == []
    empty = trial_columns(trials, none, 10)
    assert empty.trial == [] and empty.x_values == [[], []] and empty.objective_values == [[], []]
    blank = TrialSet("j", Evaluations.empty(2, 2), ("a", "b"))
    assert trial_columns(blank, none, 10).x_values == [[], []] and len(blank.ev) == 0


def test_a_path_index_is_ascii_digits_only() -> None:
    """A trial's or a front point's index of the path: up to 9 ASCII digits, else the 404 the
    routes answer (a Unicode digit such as '²' passes ``str.isdigit()`` and breaks ``int()``)."""
    from fastapi import HTTPException

    from services.api.lookups import path_index

    job: Any = type("Job", (), {"id": "j1"})()
    assert path_index(job, "0", "trial") == 0 and path_index(job, "007", "trial") == 7
    assert path_index(job, "999999999", "front point") == 999_999_999
    for bad in ("²", "1²", "٣", "x", "-1", "+1", " 1", "", "1234567890"):
        with pytest.raises(HTTPException) as err:
            path_index(job, bad, "front point")
        assert err.value.status_code == 404
        assert err.value.detail == f"job j1 has no front point {bad!r}"
