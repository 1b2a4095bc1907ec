"""The dashboard's API on a real SQLite database with jobs run in-process by the real executor:
the jobs page (filters, sorts, search, keyset paging, tenancy), a job's front with labelled
objectives and its per-generation hypervolume, a front point's motion and on-demand recording
(cached as an artifact), sweep cells and fronts, robot views, exports, and the pages and
assets served without the internet."""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest
from fastapi.testclient import TestClient

from services.api.app import create_app
from services.api.deps import ApiContext
from services.store import dashboard_queries as dq
from services.store import repository as repo
from services.store.keys import generate_api_key
from services.store.migrate import upgrade
from services.store.session import reset_engine
from services.store.settings import get_settings
from services.worker.execute import execute_job

API = "/api/v1"
SPEC: dict[str, Any] = {
    "name": "front demo",
    "tags": ["demo", "energy-time"],
    "problem": {"kind": "path_tracking", "objective": "energy_time"},
    "optimizer": {"kind": "nsga2", "params": {"pop_size": 24}},
    "budget": {"generations": 8},
    "seed": 2,
}


@pytest.fixture(scope="module")
def env(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """An app on a fresh database; Alice's sweep of 2 cells x 2 seeds and one single job, all
    run to the end by the real executor; Bob's key."""
    tmp = tmp_path_factory.mktemp("dash")
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
        sweep = {
            "base": {**SPEC, "name": "sweep demo", "record": False},
            "grid": {"optimizer.params.pop_size": [24, 32]},
            "seeds": [1, 2],
        }
        r = client.post(f"{API}/sweeps", json=sweep, headers=keys["alice"])
        assert r.status_code == 202, r.text
        sweep_id, sweep_jobs = r.json()["id"], r.json()["job_ids"]
        for j in [job_id, *sweep_jobs]:
            assert execute_job(j, settings).status == "succeeded"
        yield {"client": client, "ctx": ctx, "job": job_id, "sweep": sweep_id,
               "sweep_jobs": sweep_jobs, **keys}  # fmt: skip
    mp.undo()
    get_settings.cache_clear()
    reset_engine()


def test_jobs_page_filters_sorts_searches_and_pages(env: dict[str, Any]) -> None:
    client, alice, bob = env["client"], env["alice"], env["bob"]
    page = client.get(f"{API}/dashboard/jobs", headers=alice).json()
    assert page["total"] == 5 and len(page["items"]) == 5
    row = next(i for i in page["items"] if i["id"] == env["job"])
    assert (row["kind"], row["robot"], row["optimizer"], row["seed"]) == (
        "path_tracking", "articulated_5dof", "nsga2", 2,
    )  # fmt: skip
    assert row["status"] == "succeeded" and row["progress"] == 1.0 and row["finished_at"]
    assert client.get(f"{API}/dashboard/jobs?q=seed=1", headers=alice).json()["total"] == 2
    assert client.get(f"{API}/dashboard/jobs?q=FRONT%20demo", headers=alice).json()["total"] == 1
    q = f"{API}/dashboard/jobs?sweep_id={env['sweep']}&status=succeeded&kind=path_tracking"
    assert client.get(q, headers=alice).json()["total"] == 4
    assert client.get(f"{API}/dashboard/jobs?kind=swing_energy", headers=alice).json()["total"] == 0
    assert client.get(f"{API}/dashboard/jobs", headers=bob).json()["total"] == 0

    # keyset paging (default order) walks the same rows as one page, newest first
    ids, cursor = [], None
    while True:
        url = f"{API}/dashboard/jobs?limit=2" + (f"&cursor={cursor}" if cursor else "")
        p = client.get(url, headers=alice).json()
        ids += [i["id"] for i in p["items"]]
        cursor = p["next_cursor"]
        if cursor is None:
            break
    assert ids == [i["id"] for i in page["items"]]
    assert ids[-1] == env["job"]  # submitted first
    # other orders page by offset, in SQL
    by_best = client.get(f"{API}/dashboard/jobs?sort=best&order=asc", headers=alice).json()
    values = [i["best_objective"][0] for i in by_best["items"]]
    assert values == sorted(values)
    r = client.get(f"{API}/dashboard/jobs?cursor=nonsense", headers=alice)
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["query", "cursor"]
    r = client.get(f"{API}/dashboard/jobs?sort=colour", headers=alice)
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["query", "sort"]


def test_labels_are_written_once_for_new_jobs(env: dict[str, Any]) -> None:
    ctx = env["ctx"]
    env["client"].get(f"{API}/dashboard/jobs", headers=env["alice"])  # reading writes them
    with ctx.read() as s:
        key_id = repo.get_job(s, env["job"]).owner_key_id  # type: ignore[union-attr]
        assert not dq.missing_labels(s, key_id)
    with ctx.write() as s:
        assert dq.sync_labels(s, key_id) == 0
        assert dq.sync_labels(s, key_id, full=True) == 0


def test_front_has_named_objectives_baselines_and_hypervolume(env: dict[str, Any]) -> None:
    client, alice = env["client"], env["alice"]
    front = client.get(f"{API}/jobs/{env['job']}/front", headers=alice).json()
    assert [o["unit"] for o in front["objectives"]] == ["s", "J"]
    assert [o["axis"] for o in front["objectives"]][0] == "cycle time [s]"
    assert front["points"] and front["best_index"] is not None
    assert {b["name"] for b in front["baselines"]} == {"seed", "seed_max_V"}
    assert all(len(b["objectives"]) == 2 for b in front["baselines"])
    # the paper's own numbers: seed 004 printed only the time of its law (not plottable alone)
    paper = front["paper"]
    assert paper["source"].startswith("Sandoval") and paper["marks"] == []
    assert paper["metrics"]["time"]["start"] == pytest.approx(17.2832)
    ref = front["hypervolume_ref"]
    assert ref is not None and len(ref) == 2
    gens = client.get(f"{API}/jobs/{env['job']}/generations", headers=alice).json()["items"]
    hv = [g["hypervolume"] for g in gens]
    first = next(i for i, v in enumerate(hv) if v is not None)  # the first feasible front
    assert all(v is not None and v > 0 for v in hv[first:]), hv
    # the stored value is the exact hypervolume of that generation's front against ref
    from legcore.metrics import hypervolume

    with env["ctx"].read() as s:
        last = repo.list_generations(s, env["job"])[-1]
    assert last.front is not None
    assert hv[-1] >= hypervolume(np.asarray(last.front), ref).value - 1e-12


def test_point_motion_and_recording_are_made_once(env: dict[str, Any]) -> None:
    client, alice, ctx = env["client"], env["alice"], env["ctx"]
    front = client.get(f"{API}/jobs/{env['job']}/front", headers=alice).json()
    point = front["points"][-1]
    m = client.get(f"{API}/jobs/{env['job']}/motion?point={point['index']}", headers=alice)
    assert m.status_code == 200, m.text
    motion = m.json()
    # the deterministic decode gives back the stored objectives
    assert [motion["objectives"]["time"], motion["objectives"]["energy"]] == pytest.approx(
        point["objectives"], rel=1e-12
    )
    assert len(motion["joint_names"]) == 5
    q = next(s for s in motion["signals"] if s["name"] == "q")
    assert len(q["values"]) == 5 and len(q["values"][0]) == len(motion["t"]) <= 400
    assert motion["recording_url"].endswith(f"/pareto/{point['index']}/recording")
    base = client.get(f"{API}/jobs/{env['job']}/motion?baseline=seed", headers=alice).json()
    assert base["source"] == "baseline" and base["t"]
    assert (
        client.get(f"{API}/jobs/{env['job']}/motion?baseline=nope", headers=alice).status_code
        == 409
    )

    url = f"{API}/jobs/{env['job']}/pareto/{point['index']}/recording"
    first = client.get(url, headers=alice)
    assert first.status_code == 200, first.text
    assert first.content[:4] == b"RRF2" and first.headers["x-checksum-sha256"]
    with ctx.read() as s:
        art = repo.get_artifact(s, env["job"], f"point-{point['index']}")
        result = repo.get_artifact(s, env["job"], "result")
    assert art is not None and result is not None
    assert art.relative_path.rsplit("/", 1)[0] == result.relative_path.rsplit("/", 1)[0]
    again = client.get(url, headers=alice)
    assert again.content == first.content  # served from the artifact store
    from services.worker.rerun_blueprint import read_entities

    rrd = Path(ctx.settings.data_dir) / "point.rrd"
    rrd.write_bytes(first.content)
    ents = read_entities(rrd)
    assert any(e.split("/")[:2] == ["signals", "q"] for e in ents) and "optimization/front" in ents
    for bad in ("99999", "x", "-1"):
        assert (
            client.get(f"{API}/jobs/{env['job']}/pareto/{bad}/recording", headers=alice).status_code
            == 404
        )
    assert client.get(url, headers=env["bob"]).status_code == 404


def test_sweep_cells_group_seeds_and_overlay_fronts(env: dict[str, Any]) -> None:
    client, alice = env["client"], env["alice"]
    cells = client.get(f"{API}/sweeps/{env['sweep']}/cells", headers=alice).json()
    assert cells["columns"] == ["optimizer.params.pop_size"]
    assert [c["values"] for c in cells["cells"]] == [
        {"optimizer.params.pop_size": 24}, {"optimizer.params.pop_size": 32},
    ]  # fmt: skip
    assert all(c["seeds"] == [1, 2] and c["counts"] == {"succeeded": 2} for c in cells["cells"])
    names = [q["name"] for q in cells["stat_columns"]]
    assert names[:3] == ["time", "energy", "hypervolume"]
    stat = cells["cells"][0]["stats"]["time"]
    assert stat["n"] == 2 and stat["mean"] > 0 and stat["sd"] >= 0
    assert set(cells["best"]) == {"time", "energy", "hypervolume"}
    fronts = client.get(f"{API}/sweeps/{env['sweep']}/fronts?cell=0&cell=1", headers=alice)
    assert fronts.status_code == 200
    assert [len(c["jobs"]) for c in fronts.json()["cells"]] == [2, 2]
    r = client.get(f"{API}/sweeps/{env['sweep']}/fronts?cell=7", headers=alice)
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["query", "cell"]


def test_exports_read_back(env: dict[str, Any]) -> None:
    client, alice = env["client"], env["alice"]
    r = client.get(f"{API}/export/jobs?format=csv&kind=path_tracking", headers=alice)
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/csv")
    rows = list(csv.DictReader(io.StringIO(r.text)))
    assert len(rows) == 5 and rows[-1]["id"] == env["job"] and rows[-1]["name"] == "front demo"
    r = client.get(f"{API}/jobs/{env['job']}/front/export?format=parquet", headers=alice)
    table = pq.read_table(io.BytesIO(r.content))
    assert table.column_names[:3] == ["index", "time", "energy"] and table.num_rows > 0
    r = client.get(f"{API}/jobs/{env['job']}/history/export?format=json", headers=alice)
    doc = json.loads(r.content)
    assert doc["columns"][:4] == ["generation", "n_evals", "best_time", "best_energy"]
    assert len(doc["rows"]) == 8 and doc["rows"][-1]["hypervolume"] > 0
    r = client.get(f"{API}/sweeps/{env['sweep']}/cells/export?format=csv", headers=alice)
    cells = list(csv.DictReader(io.StringIO(r.text)))
    assert [c["optimizer.params.pop_size"] for c in cells] == ["24", "32"]
    assert float(cells[0]["time_mean"]) > 0
    assert client.get(f"{API}/export/jobs?format=xls", headers=alice).status_code == 422
    assert client.get(f"{API}/export/jobs", headers=env["bob"]).text.count("\n") == 1


def test_robot_view_lists_limits_and_fitting_studies(env: dict[str, Any]) -> None:
    client, alice = env["client"], env["alice"]
    r = client.get(f"{API}/dashboard/robots/articulated_5dof", headers=alice).json()
    assert r["nq"] == 5 and len(r["joints"]) == 5
    assert all(j["lower"] < j["upper"] for j in r["joints"])
    fits = {s["kind"]: s["accepts"] for s in r["studies"]}
    assert fits["path_tracking"] is True and fits["hexapod_workspace"] is False
    legged = client.get(f"{API}/dashboard/robots/animatronic_quadruped", headers=alice).json()
    assert legged["kind"] == "legged" and len(legged["legs"]) == 4
    assert client.get(f"{API}/dashboard/robots/nope", headers=alice).status_code == 404


def test_pages_and_assets_are_served_locally(env: dict[str, Any]) -> None:
    client = env["client"]
    index = client.get("/")
    assert index.status_code == 200 and "/static/js/app.js" in index.text
    assert client.get("/docs", follow_redirects=False).headers["location"] == f"{API}/docs"
    assert client.get(API, follow_redirects=False).headers["location"] == f"{API}/docs"
    docs = client.get(f"{API}/docs").text
    assert "/static/vendor/swagger-ui/swagger-ui-bundle.js" in docs and "cdn" not in docs.lower()
    for path in ("/static/vendor/swagger-ui/swagger-ui-bundle.js",
                 "/static/vendor/plotly-gl3d.min.js", "/static/js/pages/job.js"):  # fmt: skip
        assert client.get(path).status_code == 200, path
    for html in (index.text, client.get("/viewer/").text):
        assert "http://" not in html and "https://" not in html


def test_total_is_counted_up_to_the_cap(
    env: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(dq, "COUNT_CAP", 2)
    page = env["client"].get(f"{API}/dashboard/jobs?limit=1", headers=env["alice"]).json()
    assert page["total"] == 3 and len(page["items"]) == 1  # 3 = "more than 2"


def test_job_tags_are_listed_and_filter_the_jobs(env: dict[str, Any]) -> None:
    """A spec's ``tags`` show in the jobs list and ``?tag=`` selects by one of them; a bad tag
    is a 422 naming ``tags.0``."""
    c, alice = env["client"], env["alice"]
    r = c.get(f"{API}/dashboard/jobs", params={"tag": "energy-time", "limit": 100}, headers=alice)
    assert r.status_code == 200, r.text
    items = r.json()["items"]
    assert {j["id"] for j in items} >= {env["job"]}
    assert all("energy-time" in j["tags"] for j in items)
    r = c.get(f"{API}/dashboard/jobs", params={"tag": "nope", "limit": 100}, headers=alice)
    assert r.json()["items"] == []
    bad = {**SPEC, "tags": ["has space"]}
    r = c.post(f"{API}/jobs", json=bad, headers=alice)
    assert r.status_code == 422 and "tags" in r.text


def test_paper_solution_is_marked_where_every_objective_was_printed() -> None:
    """Seed 002's paper solution a has all three objectives: one mark on the 3-D front."""
    from services.api.dashboard_schemas import quantities
    from services.api.routes.job_views import paper_numbers

    names = ["f1_beta1", "f2_beta5", "f3_perimeter"]
    kind = "hexapod_workspace"
    paper = paper_numbers({"problem": {"kind": kind}}, quantities(names, kind), kind)
    assert paper is not None and paper.source.startswith("Domínguez")
    assert [(m.label, m.objectives) for m in paper.marks] == [
        ("paper's optimum", [0.0001, 0.0009, 0.000764])
    ]
    assert paper_numbers({"problem": {"kind": "nothing"}}, quantities(names), None) is None
