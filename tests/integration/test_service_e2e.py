"""End to end over HTTP with real worker processes, on the embedded stack and (when PostgreSQL and
redis-server are available) on PostgreSQL + Redis. See tests/integration/stack.py."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import pytest
import yaml
from sqlalchemy import func, select

from services.client import TERMINAL, ApiError
from services.recording.blueprint import read_entities
from services.store.session import make_engine, session_scope
from services.store.tables import GENERATIONS, JOBS, PARETO_POINTS, RESULTS
from tests.integration.stack import ROOT, Stack
from tests.patience import Patience

pytestmark = pytest.mark.integration

EXAMPLES = sorted((ROOT / "examples").glob("*.yaml"))


def _spec(path: Path, generations: int | None = None, **over: Any) -> dict[str, Any]:
    spec = yaml.safe_load(path.read_text())
    if generations is not None:
        spec["budget"] = {"generations": generations}
    spec.update(over)
    return spec


def _count(stack: Stack, table: Any, job_id: str) -> int:
    engine = make_engine(stack.env["LEGOPT_DATABASE_URL"])
    try:
        with session_scope(engine) as s:
            col = table.c.job_id if "job_id" in table.c else table.c.id
            return int(s.execute(select(func.count()).where(col == job_id)).scalar_one())
    finally:
        engine.dispose()


def _lease_owner_pid(stack: Stack, job_id: str) -> int | None:
    engine = make_engine(stack.env["LEGOPT_DATABASE_URL"])
    try:
        with session_scope(engine) as s:
            owner = s.execute(select(JOBS.c.lease_owner).where(JOBS.c.id == job_id)).scalar()
    finally:
        engine.dispose()
    return int(owner.split(":")[1]) if owner else None


def _succeeded(job: dict[str, Any]) -> bool:
    if job["status"] in TERMINAL and job["status"] != "succeeded":
        raise AssertionError(f"job ended {job['status']}: {job.get('error')}")
    return job["status"] == "succeeded"


def test_each_example_study_end_to_end(stack: Stack) -> None:
    """Every example spec: submitted, polled to success, result + front + recording read back."""
    assert EXAMPLES, "examples/*.yaml missing"
    with stack.client() as c:
        ids = {p.stem: c.submit(_spec(p, generations=3))["id"] for p in EXAMPLES}
        for name, job_id in ids.items():
            job = stack.wait_for(job_id, _succeeded, timeout_s=300)
            assert job["generation"] == job["total_generations"] == 3, name
            result = c.result(job_id)
            assert result["objective_names"], name
            assert result["metrics"], name
            # never "succeeded" without a verdict: the job row says what its result says
            assert isinstance(job["feasible"], bool), (name, job)
            assert result["feasible"] is job["feasible"], name
            assert bool(job["violations"]) is not job["feasible"], (name, job["violations"])
            assert result["violations"] == job["violations"] and result["task"], name
            front = c.pareto(job_id)
            assert front["total"] >= 1 and len(front["items"]) == front["total"], name
            assert len(front["items"][0]["objectives"]) == len(result["objective_names"]), name
            rrd = c.recording(job_id)
            assert rrd[:4] == b"RRF2", name  # a Rerun file, served from the artifact store
            gens = c.generations(job_id)
            assert [g["generation"] for g in gens["items"]] == [1, 2, 3], name


def test_sweep_of_12_jobs_over_two_workers(stack: Stack) -> None:
    """Each of 12 jobs runs exactly once; the aggregated table matches the stored results."""
    base = _spec(ROOT / "examples" / "000_swing_energy_flat.yaml", generations=4)
    with stack.client() as c:
        sw = c.sweep({"base": base, "grid": {"seed": list(range(1, 13))}})
        assert len(sw["job_ids"]) == 12
        for job_id in sw["job_ids"]:
            stack.wait_for(job_id, _succeeded, timeout_s=300)
        table = c.get_sweep(sw["id"])
        rows = table["table"]["items"]
        assert sorted(r["overrides"]["seed"] for r in rows) == list(range(1, 13))
        for r in rows:
            job = c.job(r["job_id"])
            assert r["status"] == "succeeded"
            assert job["attempts"] == 1  # done once
            assert r["objectives"] == c.result(r["job_id"])["objectives"]["values"]
            assert _count(stack, GENERATIONS, r["job_id"]) == 4
            assert _count(stack, RESULTS, r["job_id"]) == 1
        chosen = [rows[0]["job_id"], rows[1]["job_id"]]
        merged = stack.tmp / "merged.rrd"
        merged.write_bytes(c.sweep_recording(sw["id"], chosen))
    entities = read_entities(merged)
    for i, job_id in enumerate(chosen):
        assert any(e.startswith(f"jobs/{i + 1}_{job_id[:8]}/") for e in entities), entities


def _long_job(c: Any, generations: int = 400) -> str:
    spec = _spec(ROOT / "examples" / "000_swing_energy_flat.yaml", generations=generations)
    spec["record"] = False
    return str(c.submit(spec)["id"])


def test_kill_9_worker_job_resumes_from_checkpoint(stack: Stack) -> None:
    """kill -9 of the worker running a job: another worker finishes it from its checkpoint."""
    with stack.client() as c:
        job_id = _long_job(c)
        job = stack.wait_for(job_id, lambda j: j["status"] == "running" and j["generation"] >= 5)
        pid = _lease_owner_pid(stack, job_id)
        assert pid is not None
        victim = stack.worker_by_pid(pid)
        stack.kill_worker(victim)
        killed_at = job["generation"]
        stack.start_worker()  # keep two workers alive for the rest of the module
        job = stack.wait_for(job_id, _succeeded, timeout_s=300)
        assert job["attempts"] == 2
        resumed = [w for w in job["warnings"] if "resumed from the checkpoint" in w]
        assert resumed, job["warnings"]
        gen = int(resumed[0].split("generation ")[1].split(" ")[0])
        assert gen >= killed_at - 1 and gen > 0  # not restarted from generation 0
        assert _count(stack, GENERATIONS, job_id) == job["total_generations"]  # no duplicates
        assert _count(stack, RESULTS, job_id) == 1
        assert _count(stack, PARETO_POINTS, job_id) == c.pareto(job_id)["total"]


def test_api_restart_mid_job(stack: Stack) -> None:
    """Restarting the API process while a job runs loses nothing."""
    with stack.client() as c:
        job_id = _long_job(c, generations=200)
        stack.wait_for(job_id, lambda j: j["status"] == "running")
    stack.stop_api()
    time.sleep(1.0)
    stack.start_api()
    job = stack.wait_for(job_id, _succeeded, timeout_s=300)
    assert job["attempts"] == 1
    assert _count(stack, GENERATIONS, job_id) == job["total_generations"]


def test_broker_restart_mid_job(stack: Stack) -> None:
    """Restarting Redis (services stack; on the embedded stack: the broker's queue directory is
    wiped, the same loss of every message) while a job runs: the job completes, new jobs run."""
    with stack.client() as c:
        job_id = _long_job(c, generations=200)
        stack.wait_for(job_id, lambda j: j["status"] == "running")
        if stack.kind == "services":
            stack.redis.restart()  # type: ignore[attr-defined]
        else:
            queue = Path(stack.env["LEGOPT_DATA_DIR"]) / "broker" / "queue"
            for f in queue.iterdir():
                f.unlink()
        stack.wait_for(job_id, _succeeded, timeout_s=300)
        after = _long_job(c, generations=3)
        stack.wait_for(after, _succeeded, timeout_s=300)


def test_cancel_running_job_stops_within_a_generation(stack: Stack) -> None:
    with stack.client() as c:
        job_id = _long_job(c, generations=5000)
        stack.wait_for(job_id, lambda j: j["status"] == "running" and j["generation"] >= 2)
        c.cancel(job_id)
        t0 = time.monotonic()
        job = stack.wait_for(job_id, lambda j: j["status"] in TERMINAL, timeout_s=30)
        assert job["status"] == "cancelled"
        assert time.monotonic() - t0 < 10
        assert job["generation"] < job["total_generations"]
        with pytest.raises(ApiError) as info:
            c.cancel(job_id)
        assert info.value.status == 409


def test_recording_survives_restarts_byte_identical(stack: Stack) -> None:
    """The .rrd is a stored artifact with its checksum in the database: after restarting the
    API and a worker it downloads byte-identical, matching the recorded SHA-256."""
    import hashlib

    from services.store.tables import ARTIFACTS

    with stack.client() as c:
        job_id = c.submit(_spec(ROOT / "examples" / "003_quadruped_gait.yaml", generations=2))["id"]
        stack.wait_for(job_id, _succeeded, timeout_s=300)
        before = c.recording(job_id)
    stack.stop_api()
    victim = stack.workers[0]
    stack.kill_worker(victim)
    stack.workers.remove(victim)
    stack.start_worker()
    stack.start_api()
    with stack.client() as c:
        after = c.recording(job_id)
    assert after == before
    engine = make_engine(stack.env["LEGOPT_DATABASE_URL"])
    try:
        with session_scope(engine) as s:
            sha = s.execute(
                select(ARTIFACTS.c.sha256).where(
                    ARTIFACTS.c.job_id == job_id, ARTIFACTS.c.kind == "recording"
                )
            ).scalar_one()
    finally:
        engine.dispose()
    assert hashlib.sha256(after).hexdigest() == sha


def test_replay_web_serves_the_viewer(stack: Stack, tmp_path: Path) -> None:
    """`legopt replay JOB --web` downloads the recording and serves the web viewer (HTTP 200)."""
    import subprocess
    import sys

    import httpx

    from tests.integration.stack import free_port

    if stack.kind != "embedded":  # one stack is enough for the viewer; the download is shared
        return
    with stack.client() as c:
        job_id = c.submit(_spec(ROOT / "examples" / "004_path_tracking.yaml", generations=2))["id"]
    stack.wait_for(job_id, _succeeded, timeout_s=300)
    port = free_port()
    env = dict(stack.env, LEGOPT_API_URL=stack.url, LEGOPT_API_KEY=stack.key)
    proc = subprocess.Popen(
        [sys.executable, "-m", "services.cli", "replay", job_id, "--web", "--port", str(port),
         "--save", str(tmp_path / "job.rrd")],
        env=env, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
    )  # fmt: skip
    try:
        patience = Patience(60)
        status, page = None, ""
        while not patience.expired() and status != 200:
            if proc.poll() is not None:
                raise AssertionError(proc.stdout.read().decode() if proc.stdout else "exited")
            try:  # (a slow answer on a busy machine is asked again, not a failure)
                r = httpx.get(f"http://127.0.0.1:{port}/", timeout=10)
                status, page = r.status_code, r.text
            except httpx.HTTPError:
                time.sleep(0.3)
        assert status == 200
        assert "rerun" in page.lower()
        assert (tmp_path / "job.rrd").read_bytes()[:4] == b"RRF2"
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()


def test_cli_talks_to_the_service(stack: Stack, tmp_path: Path) -> None:
    """`legopt submit --wait`, `status`, `results --json`; a bad spec exits 2 naming the field."""
    import json
    import subprocess
    import sys

    env = dict(stack.env, LEGOPT_API_URL=stack.url, LEGOPT_API_KEY=stack.key)
    spec = tmp_path / "spec.yaml"
    spec.write_text(yaml.safe_dump(_spec(ROOT / "examples" / "003_quadruped_gait.yaml", 2)))

    def legopt(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [sys.executable, "-m", "services.cli", *args],
            env=env, cwd=ROOT, capture_output=True, text=True, timeout=300,
        )  # fmt: skip

    out = legopt("submit", str(spec), "--wait")
    assert out.returncode == 0, out.stdout + out.stderr
    job_id = out.stdout.split()[1]
    assert "start → optimum" in out.stdout and "succeeded" not in out.stderr
    out = legopt("status")
    assert out.returncode == 0 and job_id[:8] in out.stdout
    out = legopt("results", job_id, "--json")
    assert out.returncode == 0
    doc = json.loads(out.stdout)
    assert doc["job_id"] == job_id and len(doc["objective_names"]) == 1
    assert isinstance(doc["feasible"], bool) and doc["task"]["params"]["kind"] == "quadruped_gait"
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({"problem": {"kind": "quadruped_gait"}, "budget": {"gens": 3}}))
    out = legopt("submit", str(bad))
    assert out.returncode == 2
    assert "budget.gens" in out.stderr and "Extra inputs are not permitted" in out.stderr
