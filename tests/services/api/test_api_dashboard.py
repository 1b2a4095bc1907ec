"""The dashboard's API across jobs, on a real SQLite database with jobs run in-process by the
real executor: the jobs page (filters, sorts, search, tags, keyset paging, the capped total,
tenancy), the labels written once, the job list's id-prefix filter, sweep cells and fronts,
robot views, exports, and the pages and assets served without the internet. One job's views
(front, motion, recordings, spec, convergence): ``test_api_dashboard_job``."""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Iterator
from typing import Any

import pyarrow.parquet as pq
import pytest
from api_helpers import API, dashboard_env
from api_helpers import DASHBOARD_SPEC as SPEC
from fastapi.testclient import TestClient

from services.api.lookups import study_defaults
from services.store import dashboard_queries as dq
from services.store import repository as repo

pytestmark = pytest.mark.slow  # the quick lane (run.py test --quick) leaves it out


@pytest.fixture(scope="module")
def env(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """``dashboard_env``: Alice's job and her sweep of four run to the end; Bob's and Carol's
    keys."""
    with dashboard_env(tmp_path_factory.mktemp("dash")) as built:
        yield built


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
    page = env["client"].get(f"{API}/dashboard/jobs?limit=1", headers=env["alice"]).json()
    assert page["total"] == 5 and page["total_exact"] is True
    monkeypatch.setattr(dq, "COUNT_CAP", 2)
    page = env["client"].get(f"{API}/dashboard/jobs?limit=1", headers=env["alice"]).json()
    assert page["total"] == 3 and len(page["items"]) == 1  # 3 = "more than 2"
    assert page["total_exact"] is False


def test_a_search_of_short_words_only_is_refused(env: dict[str, Any]) -> None:
    """No trigram answers a word of one or two characters: alone it is a 422 naming ``q`` (it
    would read every label of the key); beside a longer word it is checked on its matches; an
    id finds its job (by the primary key)."""
    client, alice = env["client"], env["alice"]
    for q in ("ab", "a", "zq 7", "  s   e "):
        for path in ("/dashboard/jobs", "/export/jobs"):
            r = client.get(f"{API}{path}", params={"q": q}, headers=alice)
            assert r.status_code == 422, (path, q, r.text)
            (err,) = r.json()["detail"]
            assert err["loc"] == ["query", "q"] and "3 characters" in err["msg"], err
    for q, total in (("seed=1 zq", 0), ("seed=1 s", 2), ("", 5), ("   ", 5)):
        r = client.get(f"{API}/dashboard/jobs", params={"q": q}, headers=alice)
        assert r.status_code == 200 and r.json()["total"] == total, (q, r.text)
    job = env["job"]
    for q in (job, job[:13].upper(), f"{job} nsga2 s"):
        page = client.get(f"{API}/dashboard/jobs", params={"q": q}, headers=alice).json()
        assert [i["id"] for i in page["items"]] == [job] and page["total_exact"], q
    bob = client.get(f"{API}/dashboard/jobs", params={"q": job}, headers=env["bob"]).json()
    assert bob["total"] == 0


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
