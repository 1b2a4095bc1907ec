"""kill -9 of Redis (services stack) with jobs queued and running, then a restart: every
message in it is gone. During the outage a worker running a job is killed too, so its lease
expires and the job is requeued while the broker is down — the re-send then fails, and a
service that sends only after committing the requeue leaves the job ``queued`` forever
(issue 8, defect 2). A client submits during the outage: the job must then either be refused
(503, nothing left queued) or accepted and run.
"""

from __future__ import annotations

import time

import httpx
import pytest

from tests.chaos.scenario import Scenario
from tests.chaos.workload import job_spec

pytestmark = [pytest.mark.integration, pytest.mark.chaos]

N_JOBS = 6
GENERATIONS = 200
JOB_S = 6.0


def _generation(sc: Scenario, job_id: str) -> int:
    o = sc.monitor.state(job_id)
    return o.generation if o is not None else 0


@pytest.mark.stacks("services")  # the embedded broker is files: no broker process to kill
def test_kill_9_redis_with_jobs_queued_and_running(scenario: Scenario) -> None:
    sc = scenario
    w1, w2 = sc.start_workers(1, 1)
    for i in range(N_JOBS):
        sc.submit(job_spec(seed=400 + i, generations=GENERATIONS))

    def two_running() -> bool:
        held = sc.running_on({w1.pid, w2.pid})
        return len(held) == 2 and all(_generation(sc, j) <= GENERATIONS // 3 for j in held)

    sc.wait_until("two jobs running, early in their run", two_running, 60, 0.02)
    outage = sc.stack.kill_redis()
    outage.victims = [j for j in sc.ids if sc.status(j) not in ("succeeded", "failed")]

    # a worker dies during the outage: its job is requeued while the broker is down
    victim_worker, victims = next(
        ((w, v) for w in (w1, w2) if (v := sc.running_on({w.pid}))), (w1, {})
    )
    assert victims, f"no job running when Redis died (timing): nothing to prove\n{sc.dump()}"
    sc.stack.kill_worker(victim_worker)
    sc.faults[-1].victims = sorted(victims)

    # a submission during the outage: refused (and nothing queued) or accepted (and run)
    other: dict[str, str | None] = {}
    try:
        r = httpx.post(f"{sc.stack.url}/api/v1/jobs", json=job_spec(seed=450, generations=5),
                       headers={"X-API-Key": sc.stack.key}, timeout=30)  # fmt: skip
        sc.metrics["submit_during_outage"] = r.status_code
        if r.status_code == 202:
            sc.add([r.json()["id"]])
        else:
            assert r.status_code == 503, f"{r.status_code}: {r.text}"
    except httpx.TransportError as exc:
        sc.metrics["submit_during_outage"] = type(exc).__name__
    for jid in sc.all_ids() - set(sc.ids):  # refused: whatever was stored must not stay queued
        other[jid] = None

    def requeued() -> bool:
        states = [(sc.monitor.state(j), a) for j, a in victims.items()]
        return all(o is not None and (o.status == "queued" or o.attempt > a) for o, a in states)

    try:
        sc.wait_until("the dead worker's job requeued", requeued, 3 * sc.lease_s + 10)
        sc.metrics["victim_requeued_during_outage"] = True
        time.sleep(sc.lease_s)  # the broker stays down while the service tries to re-send
    except AssertionError:
        sc.metrics["victim_requeued_during_outage"] = False
    sc.stack.restart_redis(outage)
    assert outage.end is not None
    sc.metrics["redis_down_s"] = round((outage.end - outage.start).total_seconds(), 2)
    sc.start_worker(1)  # capacity back to two slots
    sc.metrics["victim_reclaim_after_restart_s"] = round(
        sc.wait_reclaimed(victims, 2 * sc.lease_s + 20), 2
    )
    sc.metrics["drain_after_restart_s"] = round(sc.wait_terminal(sc.bound(N_JOBS + 1, JOB_S, 2)), 2)
    sc.verify(expect_other=other)
