"""Leaks (issue 8, defect 4): 200 tiny recorded jobs through one solo worker, and repeated
downloads of a sweep's merged recording from the API — threads and resident memory of the
process must stay flat. Embedded stack only (the leak is in the worker and API processes, not
in the backends), one job at a time so that the samples are comparable.

Bounds: thread growth <= 2 and RSS growth <= 0.5 MB per job between job 20 and job 200
(the defect: ~4 threads and ~2.4 MB per recorded job); the same per call for the API.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import httpx
import psutil
import pytest

from tests.chaos.dbview import TERMINAL
from tests.chaos.scenario import Scenario
from tests.chaos.workload import job_spec, submit_sweep

pytestmark = [pytest.mark.integration, pytest.mark.chaos]

N_JOBS = 200
FIRST_SAMPLE = 20
IN_FLIGHT = 6
MAX_THREAD_GROWTH = 2
MAX_RSS_MB_PER_JOB = 0.5
N_CALLS = 25
FIRST_CALL_SAMPLE = 5


def _sample(pid: int) -> dict[str, float]:
    p = psutil.Process(pid)
    return {"threads": p.num_threads(), "rss_mb": p.memory_info().rss / 2**20}


@pytest.mark.stacks("embedded")  # the leak is in the worker process, the same on both stacks
def test_soak_200_recorded_jobs_one_worker(scenario: Scenario) -> None:
    sc = scenario
    worker = sc.start_worker(1)
    samples: dict[int, dict[str, float]] = {}
    errors: list[BaseException] = []

    def finished() -> int:
        return sum(1 for j in sc.ids if sc.status(j) in TERMINAL)

    def feed() -> None:
        try:
            for i in range(N_JOBS):
                while len(sc.ids) - finished() >= IN_FLIGHT:
                    time.sleep(0.02)
                sc.submit(job_spec(seed=1000 + i, generations=1, record=True), deadline_s=120)
        except BaseException as exc:
            errors.append(exc)

    feeder = threading.Thread(target=feed, daemon=True)
    feeder.start()
    t0 = time.monotonic()
    for mark in range(FIRST_SAMPLE, N_JOBS + 1, FIRST_SAMPLE):
        sc.wait_until(f"{mark} jobs finished", lambda m=mark: finished() >= m or bool(errors),
                      sc.bound(FIRST_SAMPLE, 3.0, 1) + 60, 0.02)  # fmt: skip
        assert not errors, f"submissions failed: {errors}"
        samples[mark] = _sample(worker.pid)
    sc.metrics["soak_s"] = round(time.monotonic() - t0, 1)
    feeder.join(10)
    a, b = samples[FIRST_SAMPLE], samples[N_JOBS]
    per_job = (b["rss_mb"] - a["rss_mb"]) / (N_JOBS - FIRST_SAMPLE)
    sc.metrics["worker_samples"] = {k: {m: round(v, 1) for m, v in s.items()}
                                    for k, s in samples.items()}  # fmt: skip
    sc.metrics["worker_thread_growth"] = b["threads"] - a["threads"]
    sc.metrics["worker_rss_mb_per_job"] = round(per_job, 3)
    sc.verify()
    assert b["threads"] - a["threads"] <= MAX_THREAD_GROWTH, (
        f"worker threads {a['threads']:.0f} after job {FIRST_SAMPLE} -> {b['threads']:.0f} "
        f"after job {N_JOBS} (bound +{MAX_THREAD_GROWTH}); samples {sc.metrics['worker_samples']}"
    )
    assert per_job <= MAX_RSS_MB_PER_JOB, (
        f"worker RSS grew {per_job:.2f} MB per job between job {FIRST_SAMPLE} and {N_JOBS} "
        f"(bound {MAX_RSS_MB_PER_JOB}); samples {sc.metrics['worker_samples']}"
    )


@pytest.mark.stacks("embedded")  # the leak is in the API process, the same on both stacks
def test_sweep_recording_downloads_do_not_leak_in_the_api(scenario: Scenario) -> None:
    sc = scenario
    sc.start_worker(1)
    doc: dict[str, Any] = {"base": job_spec(generations=1, record=True), "seeds": [1100, 1101]}
    sweep, ids = submit_sweep(sc.stack.url, sc.stack.key, doc)
    sc.add(ids, recorded=True)
    sc.wait_terminal(sc.bound(2, 3.0, 1))
    assert sc.stack.api is not None
    api = sc.stack.api.pid
    samples: dict[int, dict[str, float]] = {}
    with httpx.Client(headers={"X-API-Key": sc.stack.key}, timeout=60) as http:
        for call in range(1, N_CALLS + 1):
            r = http.get(f"{sc.stack.url}/api/v1/sweeps/{sweep.resource_id}/recording")
            assert r.status_code == 200, f"{r.status_code}: {r.text[:300]}"
            if call in (FIRST_CALL_SAMPLE, N_CALLS):
                time.sleep(0.5)  # let a streamed response's background clean-up run
                samples[call] = _sample(api)
    a, b = samples[FIRST_CALL_SAMPLE], samples[N_CALLS]
    per_call = (b["rss_mb"] - a["rss_mb"]) / (N_CALLS - FIRST_CALL_SAMPLE)
    sc.metrics["api_thread_growth"] = b["threads"] - a["threads"]
    sc.metrics["api_rss_mb_per_call"] = round(per_call, 3)
    sc.verify()
    assert b["threads"] - a["threads"] <= MAX_THREAD_GROWTH, (
        f"API threads {a['threads']:.0f} after call {FIRST_CALL_SAMPLE} -> {b['threads']:.0f} "
        f"after call {N_CALLS} of GET /sweeps/{{id}}/recording (bound +{MAX_THREAD_GROWTH})"
    )
    assert per_call <= MAX_RSS_MB_PER_JOB, (
        f"API RSS grew {per_call:.2f} MB per GET /sweeps/{{id}}/recording (bound "
        f"{MAX_RSS_MB_PER_JOB})"
    )
