"""`legopt export` against the test app (issue 21, item 4): a sweep's jobs one row each beside
its cells (`export sweep-jobs`, ``GET /sweeps/{id}/jobs/export``); prefixes accepted everywhere,
an unknown one an error and not an empty file (`export jobs --sweep PREFIX`: exit 2 naming
it; the API: 422 naming ``query.sweep_id`` / ``query.robot``); one file name pattern,
``legopt-<what>[-<id8>].<format>``, for the server's ``Content-Disposition`` and the CLI's
default ``--out``. The jobs are finished through the store as a worker finishes them."""

from __future__ import annotations

import csv
import io
import json
import uuid
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq
import pytest
from api_helpers import finish_like_a_worker, locs
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from services.api.deps import ApiContext
from services.cli import app
from services.cli import export as cli_export
from services.client import Client

API = "/api/v1"
runner = CliRunner()
#: A path-tracking sweep of 2 cells x 2 seeds (objectives time and energy; its default robot:
#: articulated_5dof).
SWEEP = {
    "base": {
        "problem": {"kind": "path_tracking", "objective": "energy_time"},
        "optimizer": {"kind": "nsga2"},
        "record": False,
    },
    "grid": {"optimizer.params.pop_size": [12, 16]},
    "seeds": [1, 2],
}


@pytest.fixture
def here(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty current directory (beside the app's data directory)."""
    path = tmp_path / "here"
    path.mkdir()
    monkeypatch.chdir(path)
    return path


@pytest.fixture
def cli(
    client: TestClient, alice: dict[str, str], monkeypatch: pytest.MonkeyPatch, here: Path
) -> Any:
    """``legopt export …`` run in ``here`` with its API client talking to the test app:
    ``(exit code, output)``."""

    def make(_url: str | None, _key: str | None) -> Client:
        c = Client("http://testserver", alice["X-API-Key"])
        c.http.close()
        c.http = TestClient(client.app, base_url=f"http://testserver{API}", headers=alice)
        return c

    monkeypatch.setattr(cli_export, "client", make)

    def run(*args: str) -> tuple[int, str]:
        res = runner.invoke(app, ["export", *args])
        return res.exit_code, res.output

    return run


@pytest.fixture
def sweep(client: TestClient, ctx: ApiContext, alice: dict[str, str]) -> dict[str, Any]:
    """Alice's finished sweep and one job of hers outside it (queued)."""
    r = client.post(f"{API}/sweeps", json=SWEEP, headers=alice)
    assert r.status_code == 202, r.text
    sweep_id, job_ids = r.json()["id"], r.json()["job_ids"]
    for job_id in job_ids:
        finish_like_a_worker(ctx, job_id, n_pareto=4, recording=None)
    r = client.post(f"{API}/jobs", json=SWEEP["base"], headers=alice)
    assert r.status_code == 202, r.text
    return {"id": sweep_id, "jobs": job_ids, "other": r.json()["id"]}


def test_sweep_jobs_export_one_row_per_job_beside_the_cells(
    cli: Any, sweep: dict[str, Any], here: Path
) -> None:
    code, out = cli("sweep-jobs", sweep["id"][:6])
    assert code == 0, out
    name = f"legopt-sweep-jobs-{sweep['id'][:8]}.csv"
    with open(here / name, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["id"] for r in rows] == sweep["jobs"]  # sweep order
    assert [(r["cell"], r["optimizer.params.pop_size"], r["seed"]) for r in rows] == [
        ("0", "12", "1"), ("0", "12", "2"), ("1", "16", "1"), ("1", "16", "2"),
    ]  # fmt: skip
    assert {r["status"] for r in rows} == {"succeeded"}
    # the result's objectives by name, its metrics as metric.<name>, each with its SI unit
    assert {(r["energy [J]"], r["time [s]"], r["metric.path_length_m [m]"]) for r in rows} == {
        ("1.5", "2.0", "0.3")
    }
    assert all(float(r["hypervolume"]) >= 0 for r in rows)

    code, out = cli("sweep-jobs", sweep["id"][:6], "--format", "parquet")
    assert code == 0, out
    table = pq.read_table(here / f"legopt-sweep-jobs-{sweep['id'][:8]}.parquet")
    assert table.num_rows == 4 and table.schema.field("energy").metadata[b"unit"] == b"J"
    code, out = cli("sweep-jobs", "ffffffff")
    assert code == 2 and "SWEEP: no sweep id starts with 'ffffffff'" in out


def test_every_default_file_name_follows_one_pattern(
    client: TestClient, alice: dict[str, str], cli: Any, sweep: dict[str, Any], here: Path
) -> None:
    job, sid = sweep["jobs"][0], sweep["id"]
    cases = [
        (["jobs"], "/export/jobs", "legopt-jobs.csv"),
        (["front", job[:7], "-f", "json"], f"/jobs/{job}/front/export?format=json",
         f"legopt-front-{job[:8]}.json"),
        (["history", job[:7], "-f", "parquet"], f"/jobs/{job}/history/export?format=parquet",
         f"legopt-history-{job[:8]}.parquet"),
        (["cells", sid[:7]], f"/sweeps/{sid}/cells/export", f"legopt-cells-{sid[:8]}.csv"),
        (["sweep-jobs", sid[:7], "-f", "json"], f"/sweeps/{sid}/jobs/export?format=json",
         f"legopt-sweep-jobs-{sid[:8]}.json"),
    ]  # fmt: skip
    for args, path, name in cases:
        r = client.get(f"{API}{path}", headers=alice)
        assert r.headers["content-disposition"] == f'attachment; filename="{name}"', path
        code, out = cli(*args)
        assert code == 0 and f"saved {name}" in out.replace("\n", ""), out
        assert (here / name).read_bytes() == r.content, name
    assert {p.name for p in here.iterdir()} == {name for _, _, name in cases}


def test_export_jobs_takes_a_sweep_prefix_and_refuses_an_unknown_one(
    client: TestClient, alice: dict[str, str], cli: Any, sweep: dict[str, Any], here: Path
) -> None:
    code, out = cli("jobs", "--sweep", sweep["id"][:5], "--out", "mine.json", "-f", "json")
    assert code == 0, out
    doc = json.loads((here / "mine.json").read_text())
    assert sorted(r["id"] for r in doc["rows"]) == sorted(sweep["jobs"])
    # each row names the quantity and unit of its best value
    assert {(r["best_quantity"], r["best_unit"]) for r in doc["rows"]} == {("time", "s")}
    assert doc["units"]["best"] == "" and "best_unit" in doc["labels"]["best"]

    code, out = cli("jobs", "--sweep", "ffff")
    assert code == 2 and "--sweep: no sweep id starts with 'ffff'" in out, out
    r = client.post(f"{API}/sweeps", json={**SWEEP, "seeds": [3]}, headers=alice)
    assert r.status_code == 202, r.text
    code, out = cli("jobs", "--sweep", "")
    assert code == 2 and "--sweep: '' is ambiguous" in out, out
    unknown = str(uuid.uuid4())
    code, out = cli("jobs", "--sweep", unknown)  # a whole id: the API says no
    assert code == 2 and "query.sweep_id" in out and unknown in out, out
    assert not list(here.glob("legopt-*"))  # no empty file left behind


def test_export_jobs_refuses_a_robot_nobody_has(
    cli: Any, sweep: dict[str, Any], here: Path
) -> None:
    code, out = cli("jobs", "--robot", "ur5")
    assert code == 2 and "query.robot" in out and "'ur5'" in out, out
    assert not (here / "legopt-jobs.csv").exists()
    code, out = cli("jobs", "--robot", "articulated_5dof", "--out", "ran.csv")
    assert code == 0, out
    with open(here / "ran.csv", newline="") as fh:
        assert len(list(csv.DictReader(fh))) == 5
    code, out = cli("jobs", "--robot", "puma560", "--out", "none.csv")  # known, never run
    assert code == 0, out
    assert (here / "none.csv").read_text().count("\n") == 1  # the header only


def test_the_api_names_an_unknown_filter_of_the_job_list(
    client: TestClient, alice: dict[str, str], bob: dict[str, str], sweep: dict[str, Any]
) -> None:
    prefix, whole = sweep["id"][:8], sweep["id"]
    r = client.get(f"{API}/export/jobs", params={"sweep_id": prefix}, headers=alice)
    assert locs(r) == [["query", "sweep_id"]] and prefix in r.text
    r = client.get(f"{API}/export/jobs", params={"sweep_id": whole}, headers=bob)  # not his
    assert locs(r) == [["query", "sweep_id"]]
    r = client.get(f"{API}/export/jobs", params={"robot": "ur5"}, headers=alice)
    assert locs(r) == [["query", "robot"]] and "ur5" in r.text
    r = client.get(f"{API}/export/jobs", params={"sweep_id": whole, "format": "csv"},
                   headers=alice)  # fmt: skip
    assert r.status_code == 200
    assert sorted(row["id"] for row in csv.DictReader(io.StringIO(r.text))) == sorted(sweep["jobs"])
    # a stored robot of hers counts, by name and by id, though no job ran it yet
    from api_helpers import dh_spec

    r = client.post(f"{API}/robots", json={"name": "arm2", "spec": dh_spec()}, headers=alice)
    assert r.status_code == 201, r.text
    for ref in ("arm2", r.json()["id"]):
        got = client.get(f"{API}/export/jobs", params={"robot": ref}, headers=alice)
        assert got.status_code == 200 and got.text.count("\n") == 1, ref
    assert (
        client.get(f"{API}/export/jobs", params={"robot": "arm2"}, headers=bob).status_code == 422
    )
