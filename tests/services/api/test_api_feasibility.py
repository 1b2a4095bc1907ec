"""A succeeded job's verdict everywhere the API shows it (issue 25, item 2): ``feasible`` and the
optimum's ``violations`` (typed: constraint, amount, unit, text) on ``GET /jobs/{id}``, the rows
of ``GET /jobs`` and of the dashboard's jobs page (both filter by it), ``GET /jobs/{id}/result``
(with the task the job ran and each baseline's verdict), the sweep table, and the job-list
exports (CSV, JSON, Parquet). A job on another robot than a paper's gets none of its numbers on
its page. The jobs are written through the store as a worker writes them (no optimisation)."""

from __future__ import annotations

import csv
import io
import json
from typing import Any

import pyarrow.parquet as pq
from fastapi.testclient import TestClient

from services.api.deps import ApiContext
from services.store import repository as repo
from services.store.lifecycle import claim_job, finish_job
from services.store.records import BaselineIn, ParetoPointIn, ResultIn

API = "/api/v1"
SPEC: dict[str, Any] = {"name": "walk", "robot": "animatronic_quadruped",
                        "problem": {"kind": "quadruped_gait"}}  # fmt: skip
#: The optimum misses a 20 mm static margin by 17.6 mm; the joint speed is 5.5 % over its limit.
VIOLATIONS = [
    {"constraint": "stability_margin_mm", "amount": 17.635, "unit": "mm",
     "text": "static stability margin 2.36 mm, 17.6 mm short of the required 20 mm"},
    {"constraint": "joint_speed", "amount": 0.0546, "unit": "", "text": ""},
]  # fmt: skip
TASK = {
    "params": {"kind": "quadruped_gait", "stability_margin": 0.02, "depth": 0.18},
    "rules": {"depth": "0.75 × leg length (0.24 m) = 0.18 m below the hip"},
    "preset": None,
}


def _job(ctx: ApiContext, alice: dict[str, str], client: TestClient, **spec: Any) -> str:
    """A stored job of Alice's (her key resolved from the header), claimed by worker w1."""
    key = client.get(f"{API}/keys/me", headers=alice).json()
    with ctx.write() as s:
        job = repo.create_job(s, owner_key_id=key["key"]["id"], spec={**SPEC, **spec},
                              total_generations=2)  # fmt: skip
        assert claim_job(s, job.id, "w1", 60.0) is not None
    return job.id


def _finish(
    ctx: ApiContext, job_id: str, feasible: bool | None, front: bool = True, task: Any = TASK
) -> None:
    """Finish the job as a worker would, its verdict ``feasible`` (``front``: with a one-point
    front; without, its page decodes nothing), having run ``task``."""
    violations = VIOLATIONS if feasible is False else []
    baseline = {"x": [0.08, 0.03, 0.8], "metrics": {"energy_per_metre": 3.1},
                "feasible": False, "violations": VIOLATIONS[:1]}  # fmt: skip
    with ctx.write() as s:
        finish_job(
            s, job_id, "w1",
            result=ResultIn(
                best_x=[0.1, 0.03, 0.8],
                objectives={"names": ["energy_per_metre"], "values": {"energy_per_metre": 2.5}},
                metrics={"energy_per_metre": 2.5},
                summary={"table": [], "optimizer": {"n_gen": 2}, "task": task},
                feasible=feasible,
                violations=violations,
            ),
            pareto=[ParetoPointIn(0, [0.1, 0.03, 0.8], [2.5])] if front else [],
            baselines=[BaselineIn("default_step", baseline)],
        )  # fmt: skip


def test_the_verdict_is_a_field_of_the_job_its_row_and_its_result(
    client: TestClient, ctx: ApiContext, alice: dict[str, str], bob: dict[str, str]
) -> None:
    bad = _job(ctx, alice, client, name="infeasible walk")
    good = _job(ctx, alice, client, name="feasible walk")
    running = _job(ctx, alice, client, name="still running")
    _finish(ctx, bad, feasible=False)
    _finish(ctx, good, feasible=True)

    job = client.get(f"{API}/jobs/{bad}", headers=alice).json()
    assert job["status"] == "succeeded" and job["feasible"] is False  # completed, infeasible
    assert job["violations"] == VIOLATIONS
    assert client.get(f"{API}/jobs/{good}", headers=alice).json()["feasible"] is True
    still = client.get(f"{API}/jobs/{running}", headers=alice).json()
    assert still["feasible"] is None and still["violations"] == []

    rows = {j["id"]: j for j in client.get(f"{API}/jobs", headers=alice).json()["items"]}
    assert [rows[i]["feasible"] for i in (bad, good, running)] == [False, True, None]
    assert rows[bad]["violations"][0]["amount"] == 17.635
    only = client.get(f"{API}/jobs?feasible=false", headers=alice).json()
    assert [j["id"] for j in only["items"]] == [bad] and only["total"] == 1
    assert [j["id"] for j in client.get(f"{API}/jobs?feasible=true", headers=alice).json()
            ["items"]] == [good]  # fmt: skip
    assert client.get(f"{API}/jobs?feasible=false", headers=bob).json()["total"] == 0

    page = client.get(f"{API}/dashboard/jobs", headers=alice).json()
    by_id = {r["id"]: r for r in page["items"]}
    assert by_id[bad]["feasible"] is False and by_id[bad]["violations"] == VIOLATIONS
    assert by_id[good]["feasible"] is True and by_id[running]["feasible"] is None
    red = client.get(f"{API}/dashboard/jobs?feasible=false&kind=quadruped_gait", headers=alice)
    assert [r["id"] for r in red.json()["items"]] == [bad] and red.json()["total"] == 1

    result = client.get(f"{API}/jobs/{bad}/result", headers=alice).json()
    assert result["feasible"] is False and result["violations"] == VIOLATIONS
    assert result["task"] == TASK
    (baseline,) = result["baselines"]
    assert baseline["feasible"] is False
    assert baseline["violations"][0]["constraint"] == "stability_margin_mm"
    assert client.get(f"{API}/jobs/{good}/result", headers=alice).json()["violations"] == []


def test_the_schemas_are_typed_and_documented(client: TestClient) -> None:
    schemas = client.get(f"{API}/openapi.json").json()["components"]["schemas"]
    violation = schemas["ViolationOut"]["properties"]
    assert violation["amount"]["type"] == "number" and violation["unit"]["type"] == "string"
    for model in ("JobOut", "JobDetail", "JobRowOut", "ResultOut"):
        props = schemas[model]["properties"]
        assert {"type": "boolean"} in props["feasible"]["anyOf"], model
        assert "infeasible" in props["feasible"]["description"] or "violates" in props[
            "feasible"]["description"]  # fmt: skip
        assert props["violations"]["items"] == {"$ref": "#/components/schemas/ViolationOut"}
    assert schemas["TaskOut"]["properties"]["rules"]["additionalProperties"] == {"type": "string"}


def test_the_job_list_exports_carry_the_verdict(
    client: TestClient, ctx: ApiContext, alice: dict[str, str]
) -> None:
    bad, good, queued = (_job(ctx, alice, client, name=n) for n in ("bad", "good", "queued"))
    _finish(ctx, bad, feasible=False)
    _finish(ctx, good, feasible=True)

    text = client.get(f"{API}/export/jobs?format=csv", headers=alice).text
    rows = {r["id"]: r for r in csv.DictReader(io.StringIO(text))}
    assert rows[bad]["status"] == "succeeded" and rows[bad]["feasible"] == "False"
    assert rows[bad]["violations"] == (
        "stability_margin_mm over its limit by 17.64 mm — static stability margin 2.36 mm, "
        "17.6 mm short of the required 20 mm; joint_speed over its limit by 0.0546"
    )
    assert (rows[good]["feasible"], rows[good]["violations"]) == ("True", "")
    assert (rows[queued]["feasible"], rows[queued]["violations"]) == ("", "")  # not checked

    doc = json.loads(client.get(f"{API}/export/jobs?format=json", headers=alice).content)
    assert doc["columns"][7:10] == ["status", "feasible", "violations"]
    by_id = {r["id"]: r for r in doc["rows"]}
    assert by_id[bad]["feasible"] is False and "17.64 mm" in by_id[bad]["violations"]
    assert by_id[queued]["feasible"] is None

    raw = client.get(f"{API}/export/jobs?format=parquet&feasible=false", headers=alice).content
    table = pq.read_table(io.BytesIO(raw))
    assert table.column("id").to_pylist() == [bad]
    assert table.column("feasible").to_pylist() == [False]
    assert str(table.schema.field("feasible").type) == "bool"


def test_no_paper_numbers_beside_a_job_on_another_robot(
    client: TestClient, ctx: ApiContext, alice: dict[str, str]
) -> None:
    """Seed 003's numbers (Pailos et al.) belong to its quadruped with its settings: a job of
    the same study on another robot shows none of them, nor one on its robot that ran other
    settings (the task stored with the result: a 20 mm margin instead of the paper's 1 mm)."""
    paper_task = {"params": {"kind": "quadruped_gait", "stability_margin": 0.001,
                             "depth": 0.1648}, "rules": {}, "preset": "seed 003"}  # fmt: skip
    paper_robot = _job(ctx, alice, client)
    default_robot = _job(ctx, alice, client, robot=None)  # the study's default: the paper's
    other_settings = _job(ctx, alice, client)
    other = _job(ctx, alice, client, robot="citedi_hexapod")
    inline = _job(ctx, alice, client, robot={"kind": "urdf", "name": "animatronic_quadruped"})
    jobs = (paper_robot, default_robot, other_settings, other, inline)
    for jid in jobs:
        _finish(ctx, jid, feasible=True, front=False,
                task=TASK if jid == other_settings else paper_task)  # fmt: skip
    papers = {jid: client.get(f"{API}/jobs/{jid}/front", headers=alice).json()["paper"]
              for jid in jobs}  # fmt: skip
    assert papers[paper_robot]["source"].startswith("Pailos")
    assert papers[default_robot] == papers[paper_robot]
    assert papers[other_settings] is None
    assert papers[other] is None and papers[inline] is None
