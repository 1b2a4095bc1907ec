"""Exports a notebook can use (issue 21, item 4): every front, history and sweep-cell export
carries a unit (or says it has none) and a label for each column — CSV headers ``key [unit]``,
JSON ``units``/``labels``, Parquet field metadata — and a maximised quantity appears once, in
its own sign (the seed's score F, which the optimiser minimises as ``neg_score``)."""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Iterator
from typing import Any

import pyarrow.parquet as pq
import pytest
from api_helpers import SCORE_SPEC, fresh_app

from services.worker.execute import execute_job

pytestmark = pytest.mark.slow

API = "/api/v1"
SCORE = SCORE_SPEC
TWO: dict[str, Any] = {
    "problem": {"kind": "path_tracking", "objective": "energy_time"},
    "optimizer": {"kind": "nsga2", "params": {"pop_size": 12}},
    "budget": {"generations": 3},
    "seed": 1,
    "record": False,
}


@pytest.fixture(scope="module")
def env(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    with fresh_app(tmp_path_factory.mktemp("units"), "alice") as fa:
        client, alice = fa.client, fa.keys["alice"]
        score = client.post(f"{API}/jobs", json=SCORE, headers=alice).json()["id"]
        sweep_spec = {"base": TWO, "seeds": [1, 2], "grid": {"optimizer.params.pop_size": [12, 16]}}
        r = client.post(f"{API}/sweeps", json=sweep_spec, headers=alice)
        assert r.status_code == 202, r.text
        sweep, jobs = r.json()["id"], r.json()["job_ids"]
        for j in [score, *jobs]:
            assert execute_job(j, fa.settings).status == "succeeded"
        yield {"client": client, "alice": alice, "score": score, "sweep": sweep, "two": jobs[0]}


def _get(env: dict[str, Any], path: str, fmt: str) -> bytes:
    r = env["client"].get(f"{API}{path}?format={fmt}", headers=env["alice"])
    assert r.status_code == 200, r.text
    return r.content


def _metric_like(column: str) -> bool:
    """Columns that hold a physical quantity (not an index, a count or a name)."""
    plain = {"index", "baseline", "generation", "n_evals", "cell", "jobs", "succeeded", "seeds",
             "hypervolume"}  # fmt: skip
    return not (column in plain or column.endswith("_n") or column[:1] == "x"
                or column.startswith("optimizer.") or column.startswith("hypervolume"))  # fmt: skip


@pytest.mark.parametrize(
    "path", ["/jobs/{two}/front/export", "/jobs/{two}/history/export",
             "/sweeps/{sweep}/cells/export", "/jobs/{score}/front/export"],
)  # fmt: skip
def test_every_quantity_column_has_a_unit_in_every_format(env: dict[str, Any], path: str) -> None:
    url = path.format(**env)
    doc = json.loads(_get(env, url, "json"))
    columns, units, labels = doc["columns"], doc["units"], doc["labels"]
    assert set(units) == set(columns) == set(labels)
    quantities = [c for c in columns if _metric_like(c)]
    assert quantities, columns
    assert all(labels[c] for c in quantities)  # a dimensionless one says so: unit ""
    # the objectives' own units wherever they appear (energy in J, time in s)
    for c in quantities:
        if c.split(".")[-1].removeprefix("best_").removeprefix("front_min_") in ("energy",):
            assert units[c] == "J", (url, c)
        if c.removeprefix("best_").removesuffix("_mean").removesuffix("_sd") == "time":
            assert units[c] == "s", (url, c)
    if "{two}" in path or "{sweep}" in path:
        assert sum(units[c] in ("J", "s") for c in quantities) >= 2, (url, units)
    header = next(csv.reader(io.StringIO(_get(env, url, "csv").decode())))
    assert header == [f"{c} [{units[c]}]" if units[c] else c for c in columns]
    table = pq.read_table(io.BytesIO(_get(env, url, "parquet")))
    assert table.column_names == columns
    for field in table.schema:
        meta = {k.decode(): v.decode() for k, v in (field.metadata or {}).items()}
        assert meta["unit"] == units[field.name] and meta["label"] == labels[field.name]
    assert json.loads(table.schema.metadata[b"legopt.units"]) == units


def test_a_maximised_quantity_appears_once_in_its_own_sign(env: dict[str, Any]) -> None:
    front = json.loads(_get(env, f"/jobs/{env['score']}/front/export", "json"))
    assert "score" in front["columns"] and "neg_score" not in front["columns"]
    assert "metric.score" not in front["columns"]
    best = env["client"].get(f"{API}/jobs/{env['score']}/result", headers=env["alice"]).json()
    scores = [r["score"] for r in front["rows"] if r["baseline"] is None]
    assert scores and all(s > 0 for s in scores)  # F = 5 f_d + 5 f_a, positive
    assert max(scores) == pytest.approx(best["metrics"]["score"])
    history = json.loads(_get(env, f"/jobs/{env['score']}/history/export", "json"))
    assert "best_score" in history["columns"]
    assert history["rows"][-1]["best_score"] == pytest.approx(best["metrics"]["score"])


def test_the_jobs_page_names_the_best_in_its_own_sign_and_unit(env: dict[str, Any]) -> None:
    page = env["client"].get(f"{API}/dashboard/jobs", headers=env["alice"]).json()
    rows = {r["id"]: r for r in page["items"]}
    score = rows[env["score"]]["best_named"]
    assert [q["name"] for q in score] == ["score"] and score[0]["value"] > 0  # F, not -F
    assert score[0]["value"] == pytest.approx(-rows[env["score"]]["best_objective"][0])
    two = {q["name"]: q for q in rows[env["two"]]["best_named"]}
    assert set(two) == {"time", "energy"}
    assert (two["time"]["unit"], two["energy"]["unit"]) == ("s", "J")
