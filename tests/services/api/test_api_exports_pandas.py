"""Exports a notebook can use (issue 21, item 4): every export — the job list, a job's front
and history, a sweep's cells and its jobs one row each — in every format (CSV, JSON, Parquet)
loads into a table whose every quantity column carries its unit: in the CSV header
(``key [unit]``), in JSON's ``units`` beside ``columns``, in Parquet's field metadata; the same
unit in the three, the one the quantity catalogue gives (a dimensionless one says so with "");
each quantity once, in its own sign (the seed's score F, which the optimiser minimises as
``neg_score``, is ``score``, positive). A sweep's job rows sit beside its cells: the mean over
a cell's jobs is the cell's mean. Every file is named ``legopt-<what>[-<id8>].<format>``.

pandas loads each file as the docs say (``test_every_export_loads_in_pandas``: skipped where
pandas is not installed — it is no dependency of the project); the other tests read the same
files with the standard library and pyarrow."""

from __future__ import annotations

import csv
import io
import json
import re
from collections.abc import Iterator
from typing import Any

import pyarrow.parquet as pq
import pytest
from api_helpers import DASHBOARD_SPEC, SCORE_SPEC, fresh_app

from services.api.quantities import describe

pytestmark = pytest.mark.slow

API = "/api/v1"
SCORE = SCORE_SPEC
#: Every export kind, by the file name's ``<what>``: its route, and the study of its data.
EXPORTS: list[tuple[str, str, str]] = [
    ("jobs", "/export/jobs", ""),
    ("front", "/jobs/{two}/front/export", "path_tracking"),
    ("history", "/jobs/{two}/history/export", "path_tracking"),
    ("cells", "/sweeps/{sweep}/cells/export", "path_tracking"),
    ("sweep-jobs", "/sweeps/{sweep}/jobs/export", "path_tracking"),
    ("front", "/jobs/{score}/front/export", "swing_energy"),
    ("history", "/jobs/{score}/history/export", "swing_energy"),
    ("cells", "/sweeps/{score_sweep}/cells/export", "swing_energy"),
    ("sweep-jobs", "/sweeps/{score_sweep}/jobs/export", "swing_energy"),
]
FORMATS = ("csv", "json", "parquet")
_HEADER = re.compile(r"^(?P<key>.*?)(?: \[(?P<unit>[^\]]+)\])?$")


@pytest.fixture(scope="module")
def env(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """Alice's path-tracking sweep (2 cells x 2 seeds) and seed-score sweep (1 cell x 2
    seeds), run to the end by the real executor."""
    from services.worker.execute import execute_job

    with fresh_app(tmp_path_factory.mktemp("pandas"), "alice") as app:
        client, alice = app.client, app.keys["alice"]
        ids: dict[str, Any] = {}
        for name, body in (
            ("sweep", {"base": {**DASHBOARD_SPEC, "record": False}, "seeds": [1, 2],
                       "grid": {"optimizer.params.pop_size": [24, 32]}}),
            ("score_sweep", {"base": SCORE, "seeds": [1, 2]}),
        ):  # fmt: skip
            r = client.post(f"{API}/sweeps", json=body, headers=alice)
            assert r.status_code == 202, r.text
            ids[name], ids[f"{name}_jobs"] = r.json()["id"], r.json()["job_ids"]
            for j in r.json()["job_ids"]:
                assert execute_job(j, app.settings).status == "succeeded"
        ids["two"], ids["score"] = ids["sweep_jobs"][0], ids["score_sweep_jobs"][0]
        yield {"client": client, "alice": alice, **ids}


def _get(env: dict[str, Any], path: str, fmt: str) -> tuple[bytes, str]:
    """The file's bytes and the name the server gives it."""
    r = env["client"].get(f"{API}{path.format(**env)}", params={"format": fmt},
                          headers=env["alice"])  # fmt: skip
    assert r.status_code == 200, r.text
    name = re.search(r'filename="([^"]+)"', r.headers["content-disposition"])
    assert name is not None, r.headers
    return r.content, name.group(1)


def quantity_columns(what: str, columns: list[str]) -> list[str]:
    """The columns of an export that hold a physical quantity (not an id, an index, a count,
    a swept value, a status, a time stamp or a decision variable)."""
    if what == "jobs":
        return ["best"]  # its quantity and unit: best_quantity, best_unit of each row
    if what == "front":
        return [
            c for c in columns if c not in ("index", "baseline") and not re.fullmatch(r"x\d+", c)
        ]
    if what == "history":
        return [c for c in columns if c not in ("generation", "n_evals")]
    if what == "cells":
        return [c for c in columns if c.endswith(("_mean", "_sd"))]
    assert what == "sweep-jobs", what
    return columns[columns.index("violations") + 1 : columns.index("generation")]


def quantity_of(column: str) -> str:
    """The catalogue's key of a quantity column (``best_time`` -> ``time``,
    ``metric.path_length`` -> ``path_length``, ``energy_mean`` -> ``energy``)."""
    for prefix in ("metric.", "best_", "front_min_", "compromise_"):
        column = column.removeprefix(prefix)
    return re.sub(r"_(mean|sd)$", "", column)


def read(raw: bytes, fmt: str) -> tuple[list[str], dict[str, str], list[dict[str, Any]]]:
    """Without pandas: the columns, the unit of each (as the file states it) and the rows."""
    if fmt == "csv":
        lines = list(csv.reader(io.StringIO(raw.decode(), newline="")))
        heads = [_HEADER.fullmatch(h) for h in lines[0]]
        columns = [m.group("key") for m in heads if m]
        units = {m.group("key"): m.group("unit") or "" for m in heads if m}
        return columns, units, [dict(zip(columns, r, strict=True)) for r in lines[1:]]
    if fmt == "json":
        doc = json.loads(raw)
        assert set(doc["labels"]) == set(doc["columns"])
        return doc["columns"], doc["units"], doc["rows"]
    table = pq.read_table(io.BytesIO(raw))
    units = {f.name: (f.metadata or {}).get(b"unit", b"?").decode() for f in table.schema}
    assert json.loads(table.schema.metadata[b"legopt.units"]) == units
    return table.column_names, units, table.to_pylist()


@pytest.mark.parametrize(("what", "path", "kind"), EXPORTS)
def test_every_export_names_the_unit_of_every_quantity_in_every_format(
    env: dict[str, Any], what: str, path: str, kind: str
) -> None:
    got = {fmt: read(_get(env, path, fmt)[0], fmt) for fmt in FORMATS}
    columns, units, rows = got["json"]
    assert len(set(columns)) == len(columns), columns  # each quantity once
    assert rows, (what, path)
    for fmt in ("csv", "parquet"):
        assert got[fmt][0] == columns and got[fmt][1] == units, fmt
    quantities = quantity_columns(what, columns)
    assert quantities, columns
    labels = json.loads(_get(env, path, "json")[0])["labels"]
    for c in quantities:
        assert labels[c], c
        if what != "jobs":
            assert units[c] == describe(quantity_of(c), kind)["unit"], (what, c)
    if what == "jobs":
        named = [r for r in rows if r["best"] is not None]
        assert named and all(r["best_quantity"] and r["best_unit"] is not None for r in named)
        for r in named:
            assert r["best_unit"] == describe(r["best_quantity"], r["kind"])["unit"], r
        assert {(r["best_quantity"], r["best_unit"]) for r in named if r["kind"] == "path_tracking"
                } <= {("time", "s"), ("energy", "J")}  # fmt: skip
    elif kind == "path_tracking":  # the objectives wherever they appear: time in s, energy in J
        shown = {quantity_of(c): units[c] for c in quantities}
        assert (shown["time"], shown["energy"]) == ("s", "J"), shown
        assert sum(bool(units[c]) for c in quantities) >= 2
    else:  # the score, in its own sign; never as neg_score
        assert not any("neg_score" in c for c in columns), columns
        assert any(quantity_of(c) == "score" for c in quantities), columns


@pytest.mark.parametrize("fmt", FORMATS)
def test_every_file_is_named_legopt_what_id8(env: dict[str, Any], fmt: str) -> None:
    for what, path, _kind in EXPORTS:
        ident = re.search(r"\{(\w+)\}", path)
        id8 = "" if ident is None else "-" + env[ident.group(1)][:8]
        assert _get(env, path, fmt)[1] == f"legopt-{what}{id8}.{fmt}"


@pytest.mark.parametrize("sweep", ["sweep", "score_sweep"])
def test_a_sweeps_job_rows_agree_with_its_cells(env: dict[str, Any], sweep: str) -> None:
    cells = json.loads(_get(env, f"/sweeps/{{{sweep}}}/cells/export", "json")[0])
    jobs = json.loads(_get(env, f"/sweeps/{{{sweep}}}/jobs/export", "json")[0])
    assert [r["id"] for r in jobs["rows"]] == env[f"{sweep}_jobs"]  # sweep order
    assert all(r["status"] == "succeeded" for r in jobs["rows"])
    swept = cells["columns"][1 : cells["columns"].index("jobs")]
    assert jobs["columns"][: 2 + len(swept) + 4] == ["id", "cell", *swept, "seed", "status",
                                                      "feasible", "violations"]  # fmt: skip
    assert sorted({r["seed"] for r in jobs["rows"]}) == [1, 2]
    quantities = quantity_columns("sweep-jobs", jobs["columns"])
    assert "hypervolume" in quantities if sweep == "sweep" else "score" in quantities
    for cell in cells["rows"]:
        mine = [r for r in jobs["rows"] if r["cell"] == cell["cell"]]
        assert len(mine) == cell["jobs"] and all(r[p] == cell[p] for r in mine for p in swept)
        for c in quantities:
            name = quantity_of(c)
            values = [r[c] for r in mine if r[c] is not None]
            assert cell[f"{name}_n"] == len(values), c
            assert cell[f"{name}_mean"] == pytest.approx(sum(values) / len(values)), c
            assert jobs["units"][c] == cells["units"][f"{name}_mean"], c
    if sweep == "score_sweep":  # F = 5 f_d + 5 f_a: positive, and each job's best
        for r in jobs["rows"]:
            best = env["client"].get(f"{API}/jobs/{r['id']}/result", headers=env["alice"]).json()
            assert r["score"] > 0 and r["score"] == pytest.approx(best["metrics"]["score"])


@pytest.mark.parametrize(("what", "path", "kind"), EXPORTS)
def test_every_export_loads_in_pandas(env: dict[str, Any], what: str, path: str, kind: str) -> None:
    """What docs/dashboard.md tells a notebook to do, format by format: the same columns,
    units and values, every quantity column numeric."""
    pd = pytest.importorskip("pandas")
    columns, units, rows = read(_get(env, path, "json")[0], "json")
    raw = {fmt: _get(env, path, fmt)[0] for fmt in FORMATS}

    df = pd.read_csv(io.BytesIO(raw["csv"]))  # units in the header: "energy [J]"
    heads = [_HEADER.fullmatch(h) for h in df.columns]
    assert {m.group("key"): m.group("unit") or "" for m in heads if m} == units
    frames = {"csv": df.rename(columns=dict(zip(df.columns, columns, strict=True)))}
    doc = json.loads(raw["json"])  # units beside the columns
    frames["json"] = pd.DataFrame(doc["rows"], columns=doc["columns"])
    assert doc["units"] == units
    frames["parquet"] = pd.read_parquet(io.BytesIO(raw["parquet"]))  # units in its schema
    schema = pq.read_schema(io.BytesIO(raw["parquet"]))
    assert {f.name: f.metadata[b"unit"].decode() for f in schema} == units

    for fmt, frame in frames.items():
        assert list(frame.columns) == columns and len(frame) == len(rows), fmt
        for c in quantity_columns(what, columns):
            if frame[c].notna().any():
                assert pd.api.types.is_numeric_dtype(frame[c]), (fmt, c, frame[c].dtype)
                assert frame[c].tolist() == pytest.approx(
                    frames["json"][c].tolist(), nan_ok=True
                ), (fmt, c)
