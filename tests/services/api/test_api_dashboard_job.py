"""The dashboard's view of one job, on a real SQLite database with jobs run in-process by the
real executor: its front with labelled objectives, per-point metrics and its per-generation
hypervolume, the best of each objective so far (seed 002, three objectives), a front point's
and a baseline's motion and on-demand recording (cached as an artifact), and the spec as
YAML. The jobs page, sweeps and exports: ``test_api_dashboard``."""

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
from api_helpers import API, dashboard_env

from services.store import output_queries as oq
from services.store import repository as repo
from services.worker.execute import execute_job

pytestmark = pytest.mark.slow  # the quick lane (run.py test --quick) leaves it out

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def env(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """``dashboard_env``: Alice's job and her sweep of four run to the end; Bob's and Carol's
    keys."""
    with dashboard_env(tmp_path_factory.mktemp("dash-job")) as built:
        yield built


def test_front_has_named_objectives_baselines_and_hypervolume(env: dict[str, Any]) -> None:
    client, alice = env["client"], env["alice"]
    front = client.get(f"{API}/jobs/{env['job']}/front", headers=alice).json()
    assert [o["unit"] for o in front["objectives"]] == ["s", "J"]
    assert [o["axis"] for o in front["objectives"]][0] == "cycle time [s]"
    assert front["points"] and front["best_index"] is not None
    # the reported optimum's place as the worker stored it: that point is the optimum itself
    with env["ctx"].read() as s:
        result = oq.get_result(s, env["job"])
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
        last = oq.list_generations(s, env["job"])[-1]
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
        art = oq.get_artifact(s, env["job"], f"point-{point['index']}")
        result = oq.get_artifact(s, env["job"], "result")
    assert art is not None and result is not None
    assert art.relative_path.rsplit("/", 1)[0] == result.relative_path.rsplit("/", 1)[0]
    again = client.get(url, headers=alice)
    assert again.content == first.content  # served from the artifact store
    from services.recording.blueprint import read_entities

    rrd = Path(ctx.settings.data_dir) / "point.rrd"
    rrd.write_bytes(first.content)
    ents = read_entities(rrd)
    assert any(e.split("/")[:2] == ["signals", "q"] for e in ents) and "optimization/front" in ents
    for bad in ("99999", "x", "-1", "²", "1234567890"):
        assert (
            client.get(f"{API}/jobs/{env['job']}/pareto/{bad}/recording", headers=alice).status_code
            == 404
        )
    assert client.get(url, headers=env["bob"]).status_code == 404


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
        art = oq.get_artifact(s, env["job"], "front-metrics")
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
        kinds = {a.kind for a in oq.list_artifacts(s, env["job"])}
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
