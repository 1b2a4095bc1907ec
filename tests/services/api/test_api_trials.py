"""Every evaluated solution explorable (issue 21, item 1): a job run in-process by the real
executor stores its trials; the API filters, sorts and pages them, gives their columns for a
parallel-coordinates plot, and decodes any trial — not only a front point — into its motion
and a Rerun recording."""

from __future__ import annotations

import hashlib
from collections.abc import Iterator
from typing import Any

import pytest
from fastapi.testclient import TestClient

from services.api.app import create_app
from services.api.deps import ApiContext
from services.store import repository as repo
from services.store.keys import generate_api_key
from services.store.migrate import upgrade
from services.store.session import reset_engine
from services.store.settings import get_settings
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
    tmp = tmp_path_factory.mktemp("trials")
    mp = pytest.MonkeyPatch()
    url = f"sqlite:///{tmp / 'legopt.db'}"
    mp.setenv("LEGOPT_DATA_DIR", str(tmp))
    mp.setenv("LEGOPT_DATABASE_URL", url)
    get_settings.cache_clear()
    reset_engine()
    upgrade(url)
    settings = get_settings()
    app = create_app(settings, enqueue=lambda _j: None)
    ctx: ApiContext = app.state.context
    keys = {}
    for name in ("alice", "bob"):
        raw, key_hash = generate_api_key()
        with ctx.write() as s:
            repo.create_api_key(s, name=name, key_hash=key_hash)
        keys[name] = {"X-API-Key": raw}
    with TestClient(app) as client:
        r = client.post(f"{API}/jobs", json=SPEC, headers=keys["alice"])
        assert r.status_code == 202, r.text
        job_id = r.json()["id"]
        before = client.get(f"{API}/jobs/{job_id}/trials", headers=keys["alice"]).json()
        assert execute_job(job_id, settings).status == "succeeded"
        yield {"client": client, "job": job_id, "before": before, **keys}
    mp.undo()
    get_settings.cache_clear()
    reset_engine()


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
