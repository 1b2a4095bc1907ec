"""The dashboard's API on a real SQLite database with jobs run in-process by the real executor:
the jobs page (filters, sorts, search, keyset paging, tenancy), a job's front with labelled
objectives, per-point metrics and its per-generation hypervolume, the best of each objective
so far (seed 002, three objectives), a front point's and a baseline's motion and on-demand
recording (cached as an artifact), the spec as YAML, the job list's id-prefix filter, sweep
cells and fronts, robot views, exports, and the pages and assets served without the
internet."""

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
import yaml
from fastapi.testclient import TestClient

from services.api.app import create_app
from services.api.deps import ApiContext
from services.api.lookups import study_defaults
from services.store import dashboard_queries as dq
from services.store import repository as repo
from services.store.keys import generate_api_key
from services.store.migrate import upgrade
from services.store.session import reset_engine
from services.store.settings import get_settings
from services.worker.execute import execute_job

pytestmark = pytest.mark.slow  # the quick lane (run.py test --quick) leaves it out

API = "/api/v1"
ROOT = Path(__file__).resolve().parents[3]
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
    for name in ("alice", "bob", "carol"):
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
        assert dq.sync_labels(s, key_id, study_defaults) == 0
        assert dq.sync_labels(s, key_id, study_defaults, full=True) == 0


def test_front_has_named_objectives_baselines_and_hypervolume(env: dict[str, Any]) -> None:
    client, alice = env["client"], env["alice"]
    front = client.get(f"{API}/jobs/{env['job']}/front", headers=alice).json()
    assert [o["unit"] for o in front["objectives"]] == ["s", "J"]
    assert [o["axis"] for o in front["objectives"]][0] == "cycle time [s]"
    assert front["points"] and front["best_index"] is not None
    # the reported optimum's place as the worker stored it: that point is the optimum itself
    with env["ctx"].read() as s:
        result = repo.get_result(s, env["job"])
    assert result is not None and front["best_index"] == result.summary["best_index"]
    best = next(p for p in front["points"] if p["index"] == front["best_index"])
    assert best["x"] == pytest.approx(result.best_x)
    assert {b["name"] for b in front["baselines"]} == {"time_optimal", "seed", "seed_max_V"}
    # the physical minimum (TOPP-RA) is a marked point, faster than every front point
    fastest = min(p["objectives"][0] for p in front["points"])
    mark = next(b for b in front["baselines"] if b["name"] == "time_optimal")
    assert mark["objectives"][0] < fastest
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
    from services.recording.blueprint import read_entities

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
    assert float(cells[0]["time_mean [s]"]) > 0  # CSV headers carry the unit
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
    from services.api.front_view import paper_numbers

    names = ["f1_beta1", "f2_beta5", "f3_perimeter"]
    kind = "hexapod_workspace"
    paper = paper_numbers({"problem": {"kind": kind}}, quantities(names, kind), kind)
    assert paper is not None and paper.source.startswith("Domínguez")
    assert [(m.label, m.objectives) for m in paper.marks] == [
        ("paper's optimum", [0.0001, 0.0009, 0.000764])
    ]
    assert paper_numbers({"problem": {"kind": "nothing"}}, quantities(names), None) is None


def test_front_points_carry_their_metrics_decoded_once(env: dict[str, Any]) -> None:
    """Every front point's metrics (labelled with readable names and units) are those its
    motion decodes to; computed once and kept as the artifact ``front-metrics``; in the front
    export as ``metric.<name>`` columns."""
    client, alice, ctx = env["client"], env["alice"], env["ctx"]
    front = client.get(f"{API}/jobs/{env['job']}/front", headers=alice).json()
    assert front["point_metrics"] == "ready" and front["point_metrics_note"] is None
    labels = {q["name"]: q for q in front["metrics"]}
    assert labels["energy"]["unit"] == "J" and labels["time"]["label"] == "cycle time"
    points = front["points"]
    assert all(p["metrics"] and set(p["metrics"]) <= set(labels) for p in points)
    point = points[len(points) // 2]
    motion = client.get(f"{API}/jobs/{env['job']}/motion?point={point['index']}", headers=alice)
    decoded = motion.json()["metrics"]
    assert decoded and {k: point["metrics"][k] for k in decoded} == pytest.approx(decoded)
    assert point["metrics"]["time"] == pytest.approx(point["objectives"][0], rel=1e-12)
    with ctx.read() as s:
        art = repo.get_artifact(s, env["job"], "front-metrics")
    assert art is not None and art.relative_path.endswith(".json")

    # served from the artifact afterwards: no decoding
    from services.recording import point as point_module

    def no_decode(*_a: Any, **_k: Any) -> Any:
        raise AssertionError("the front's metrics were decoded again")

    mp = pytest.MonkeyPatch()
    mp.setattr(point_module, "decode_point", no_decode)
    try:
        again = client.get(f"{API}/jobs/{env['job']}/front", headers=alice).json()
        r = client.get(f"{API}/jobs/{env['job']}/front/export?format=csv", headers=alice)
    finally:
        mp.undo()
    assert [p["metrics"] for p in again["points"]] == [p["metrics"] for p in points]
    assert r.status_code == 200, r.text
    rows = list(csv.DictReader(io.StringIO(r.text)))
    marks = [r for r in rows if r["baseline"]]  # the baselines follow the front's points
    assert {r["baseline"] for r in marks} == {"time_optimal", "seed", "seed_max_V"}
    assert all(r["index"] == "" and float(r["time [s]"]) > 0 for r in marks)
    rows = [r for r in rows if not r["baseline"]]
    assert len(rows) == len(points)
    # the objectives are metrics too: one column each (the objective's), with its unit
    metric_columns = [c for c in rows[0] if c.startswith("metric.")]
    assert metric_columns and not any(c.split(" ")[0] in ("metric.energy", "metric.time")
                                      for c in metric_columns)  # fmt: skip
    row = next(r for r in rows if int(r["index"]) == point["index"])
    assert float(row["energy [J]"]) == pytest.approx(point["metrics"]["energy"])
    assert list(rows[0])[:3] == ["index", "time [s]", "energy [J]"] and "x1" in rows[0]
    for fmt in ("json", "parquet"):
        r = client.get(f"{API}/jobs/{env['job']}/front/export?format={fmt}", headers=alice)
        cols = (
            json.loads(r.content)["columns"]
            if fmt == "json"
            else pq.read_table(io.BytesIO(r.content)).column_names
        )
        assert "energy" in cols and "metric.energy" not in cols, fmt  # one column per quantity


def test_a_baseline_has_its_own_recording(env: dict[str, Any]) -> None:
    """Clicking a baseline opens that baseline's recording (made on demand like a point's),
    not the whole job's."""
    client, alice, ctx = env["client"], env["alice"], env["ctx"]
    motion = client.get(f"{API}/jobs/{env['job']}/motion?baseline=seed_max_V", headers=alice)
    url = motion.json()["recording_url"]
    assert url == f"{API}/jobs/{env['job']}/baselines/seed_max_V/recording"
    r = client.get(url, headers=alice)
    assert r.status_code == 200, r.text
    assert r.content[:4] == b"RRF2" and r.headers["x-checksum-sha256"]
    job_rrd = client.get(f"{API}/jobs/{env['job']}/recording", headers=alice).content
    assert job_rrd[:4] == b"RRF2" and r.content != job_rrd
    with ctx.read() as s:
        kinds = {a.kind for a in repo.list_artifacts(s, env["job"])}
    assert "baseline-1" in kinds  # seed_max_V: the second baseline by name
    assert client.get(url, headers=alice).content == r.content
    missing = client.get(f"{API}/jobs/{env['job']}/baselines/nope/recording", headers=alice)
    assert missing.status_code == 404 and "seed_max_V" in missing.text
    # made on demand: a job that did not record itself (record: false) has them too
    quiet = env["sweep_jobs"][0]
    assert client.get(f"{API}/jobs/{quiet}/recording", headers=alice).status_code == 404
    r = client.get(f"{API}/jobs/{quiet}/baselines/seed/recording", headers=alice)
    assert r.status_code == 200 and r.content[:4] == b"RRF2"
    assert client.get(url, headers=env["bob"]).status_code == 404


def test_spec_yaml_is_the_stored_spec(env: dict[str, Any]) -> None:
    client, alice, ctx = env["client"], env["alice"], env["ctx"]
    for job_id in (env["job"], env["sweep_jobs"][-1]):  # its own spec; a sweep's base + overrides
        r = client.get(f"{API}/jobs/{job_id}/spec.yaml", headers=alice)
        assert r.status_code == 200 and r.headers["content-type"].startswith("application/yaml")
        assert f'filename="job-{job_id[:8]}.yaml"' in r.headers["content-disposition"]
        with ctx.read() as s:
            stored = repo.job_spec(s, repo.get_job(s, job_id))  # type: ignore[arg-type]
        assert yaml.safe_load(r.text) == stored
    last = yaml.safe_load(client.get(f"{API}/jobs/{env['sweep_jobs'][-1]}/spec.yaml",
                                     headers=alice).text)  # fmt: skip
    assert last["optimizer"]["params"]["pop_size"] == 32 and last["record"] is False
    assert client.get(f"{API}/jobs/{env['job']}/spec.yaml", headers=env["bob"]).status_code == 404


def test_job_and_sweep_lists_filter_by_id_prefix(
    env: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    client, alice = env["client"], env["alice"]
    job = env["job"]
    for prefix in (job[:6], job[:9], job[:13].upper(), job):
        page = client.get(f"{API}/jobs", params={"id_prefix": prefix}, headers=alice).json()
        assert [i["id"] for i in page["items"]] == [job] and page["total"] == 1, prefix
    everything = client.get(f"{API}/jobs", params={"id_prefix": ""}, headers=alice).json()
    assert everything["total"] == 5
    for impossible in ("zz", job[:8] + "x", "0" * 9, job + "0"):
        r = client.get(f"{API}/jobs", params={"id_prefix": impossible}, headers=alice)
        assert r.status_code == 422 if len(impossible) > 36 else r.json()["total"] == 0
    assert client.get(f"{API}/jobs", params={"id_prefix": job[:6]},
                      headers=env["bob"]).json()["total"] == 0  # fmt: skip
    sweeps = client.get(f"{API}/sweeps", params={"id_prefix": env["sweep"][:5]}, headers=alice)
    assert [s["id"] for s in sweeps.json()["items"]] == [env["sweep"]]

    # the CLI's client resolves a prefix with one request (no paging through the list)
    from services.client import Client

    c = Client(key=alice["X-API-Key"])
    c.http = TestClient(client.app, base_url="http://testserver/api/v1", headers=alice)
    requests: list[str] = []
    send = c.http.request

    def counted(method: str, url: Any, **kw: Any) -> Any:
        requests.append(f"{method} {url} {kw.get('params')}")
        return send(method, url, **kw)

    monkeypatch.setattr(c.http, "request", counted)
    assert c.ids_with_prefix("jobs", job[:7].upper()) == [job]
    assert len(requests) == 1 and "id_prefix" in requests[0], requests
    assert c.ids_with_prefix("sweeps", env["sweep"][:4]) == [env["sweep"]]
    assert c.ids_with_prefix("jobs", "zz") == [] and len(requests) == 3


@pytest.fixture(scope="module")
def hexapod(env: dict[str, Any]) -> str:
    """Seed 002 (three objectives, MOEA/D), run to the end for Carol."""
    spec = yaml.safe_load((ROOT / "examples" / "002_hexapod_workspace.yaml").read_text())
    spec["record"] = False
    r = env["client"].post(f"{API}/jobs", json=spec, headers=env["carol"])
    assert r.status_code == 202, r.text
    job_id = str(r.json()["id"])
    assert execute_job(job_id, env["ctx"].settings).status == "succeeded"
    return job_id


def test_best_per_objective_never_gets_worse(env: dict[str, Any], hexapod: str) -> None:
    """Seed 002: the stored per-generation `best` is the compromise point of the front and
    rises in some objective; `best_so_far` (the convergence plot's and the history export's
    `best_<name>`) is the running minimum of each generation's front minimum: never worse,
    and down to the final front's minimum."""

    client, carol = env["client"], env["carol"]
    url = f"{API}/jobs/{hexapod}/generations"
    rows = client.get(url, params={"limit": 1000}, headers=carol).json()["items"]
    assert len(rows) == 100
    reported = np.array([r["best"] for r in rows], dtype=float)
    assert (np.diff(reported, axis=0) > 0).any(), "the compromise point never rose here"
    best = np.array([r["best_so_far"] for r in rows], dtype=float)
    assert best.shape == (100, 3) and np.isfinite(best).all()
    assert (np.diff(best, axis=0) <= 0).all()
    front_min = np.array([r["front_min"] for r in rows], dtype=float)
    assert np.array_equal(best, np.minimum.accumulate(front_min, axis=0))
    assert (best <= reported).all()
    pareto = client.get(f"{API}/jobs/{hexapod}/front", headers=carol).json()["points"]
    final = np.array([p["objectives"] for p in pareto], dtype=float)
    assert (best[-1] <= final.min(axis=0) + 1e-15).all()

    # polled page by page (`after`): each page continues from the stored fronts before it
    after, paged = -1, []
    while True:
        page = client.get(url, params={"after": after, "limit": 7}, headers=carol).json()
        if not page["items"]:
            break
        paged += page["items"]
        after = page["next_after"]
    assert [p["best_so_far"] for p in paged] == [r["best_so_far"] for r in rows]

    r = client.get(f"{API}/jobs/{hexapod}/history/export?format=json", headers=carol)
    doc = json.loads(r.content)
    names = ["f1_beta1", "f2_beta5", "f3_perimeter"]
    assert doc["columns"][:5] == ["generation", "n_evals", *[f"best_{n}" for n in names]]
    exported = np.array([[row[f"best_{n}"] for n in names] for row in doc["rows"]])
    assert np.array_equal(exported, best)
    assert [row[f"compromise_{names[0]}"] for row in doc["rows"]] == list(reported[:, 0])


@pytest.mark.slow
def test_single_objective_best_so_far_is_the_incumbent(env: dict[str, Any]) -> None:
    client, alice = env["client"], env["alice"]
    spec = {"problem": {"kind": "swing_energy"}, "optimizer": {"kind": "ga"},
            "budget": {"generations": 4}, "record": False}  # fmt: skip
    r = client.post(f"{API}/jobs", json=spec, headers=env["carol"])
    job_id = r.json()["id"]
    assert execute_job(job_id, env["ctx"].settings).status == "succeeded"
    rows = client.get(f"{API}/jobs/{job_id}/generations", headers=env["carol"]).json()["items"]
    assert rows and all(g["best_so_far"] == g["best"] and g["front_min"] is None for g in rows)
    assert client.get(f"{API}/jobs/{job_id}/generations", headers=alice).status_code == 404
