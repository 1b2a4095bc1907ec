"""kill -9 of a worker while a sweep's jobs run and, on the services stack, kill -9 of Redis
mid-sweep as well (issue 8: "during submit bursts and mid-sweep").

A 12-job sweep (every third job recorded) runs on two workers: a solo worker and a victim — a
``--pool prefork -c 2`` worker on the services stack (its pool children die with their
parent), a second solo worker on the embedded one (prefork is refused there). Once the victim
runs a sweep job past generation 3 it is killed. On the services stack Redis is killed right
after it, with most of the sweep still queued in it: every queued message is lost, and the
victim's jobs reach their lease expiry (and are requeued) while the broker is down, so their
re-send fails until Redis is back (defect 2's sequence, on a sweep). A replacement worker
restores the capacity; then every invariant holds for every job of the sweep (terminal exactly
once, no job queued longer than 2 lease periods with an idle slot, artifacts match their
checksums, no orphans, the message bound) and the sweep itself reads ``finished`` with every job
succeeded.
"""

from __future__ import annotations

import time
from typing import Any

import httpx
import pytest

from tests.chaos.scenario import Scenario
from tests.chaos.workload import job_spec, submit_sweep

pytestmark = [pytest.mark.integration, pytest.mark.chaos]

SEEDS = [700 + i for i in range(4)]
#: The sweep's ``list`` axis: one recorded job in three.
RECORD = [{"record": True}, {"record": False}, {"record": False}]
N_JOBS = len(SEEDS) * len(RECORD)
GENERATIONS = 80
JOB_S = 4.0  # generous per-job time on a loaded 2-core machine (as test_worker_kill)


def _generation(sc: Scenario, job_id: str) -> int:
    o = sc.monitor.state(job_id)
    return o.generation if o is not None else 0


def _recorded(row: dict[str, Any]) -> bool:
    overrides = row.get("overrides")
    return isinstance(overrides, dict) and bool(overrides.get("record"))


def test_kill_9_worker_and_redis_mid_sweep(scenario: Scenario) -> None:
    sc = scenario
    services = sc.stack.kind == "services"
    solo, victim = sc.start_workers(1, 2 if services else 1)
    sc.mark("workers_ready")

    doc = {"base": job_spec(generations=GENERATIONS), "list": RECORD, "seeds": SEEDS}
    sub, ids = submit_sweep(sc.stack.url, sc.stack.key, doc)
    assert len(ids) == N_JOBS, ids
    sc.add(ids)
    sc.recorded.update(r["id"] for r in sc.view.job_rows(ids) if _recorded(r))
    assert len(sc.recorded) == N_JOBS // len(RECORD), "the record axis did not reach the jobs"
    sc.mark("submitted")

    # 1. kill -9 the victim worker once it runs a sweep job past generation 3
    pids = {p.pid for p in sc.stack.pool_children(victim)} if services else {victim.pid}

    def victim_busy() -> bool:
        return any(_generation(sc, j) >= 3 for j in sc.running_on(pids))

    sc.wait_until("the victim worker runs a sweep job", victim_busy, 60, 0.02)
    victims = sc.running_on(pids)
    sc.stack.kill_worker(victim)
    sc.faults[-1].victims = sorted(victims)
    sc.mark("worker_killed")

    # 2. services: kill -9 Redis with most of the sweep queued in it, for longer than the
    #    victims' leases, so that they are requeued while the broker is down
    if services:
        outage = sc.stack.kill_redis()
        outage.victims = [j for j in ids if sc.status(j) not in ("succeeded", "failed")]
        sc.metrics["queued_at_redis_kill"] = sum(1 for j in ids if sc.status(j) == "queued")

        def requeued() -> bool:
            return all(
                (o := sc.monitor.state(j)) is not None and (o.status != "running" or o.attempt > a)
                for j, a in victims.items()
            )

        try:
            sc.wait_until("the killed worker's jobs requeued", requeued, 3 * sc.lease_s + 10)
            sc.metrics["victims_requeued_during_outage"] = True
            time.sleep(1.0)  # a dispatcher pass with the broker still down
        except AssertionError:
            sc.metrics["victims_requeued_during_outage"] = False
        sc.stack.restart_redis(outage)
        assert outage.end is not None
        sc.metrics["redis_down_s"] = round((outage.end - outage.start).total_seconds(), 2)

    # 3. capacity back; the victims are claimed again, then the whole sweep drains
    sc.start_worker(1)
    sc.mark("replacement_ready")
    sc.metrics["victim_reclaim_s"] = round(
        sc.wait_reclaimed(victims, 2 * sc.lease_s + sc.bound(0, 0, 1)), 2
    )
    sc.metrics["drain_s"] = round(sc.wait_terminal(sc.bound(N_JOBS, JOB_S, 2)), 2)

    rows = sc.view.job_rows(ids)
    assert any(r["attempt_count"] > 1 for r in rows), (
        f"no sweep job was hit by the kill (timing): the scenario proved nothing\n{sc.dump()}"
    )
    sc.metrics["resumed_jobs"] = sum(1 for r in rows if r["attempt_count"] > 1)
    sc.mark("drained")
    sc.verify()

    r = httpx.get(
        f"{sc.stack.url}/api/v1/sweeps/{sub.resource_id}",
        headers={"X-API-Key": sc.stack.key},
        timeout=30,
    )
    assert r.status_code == 200, r.text[:500]
    sweep = r.json()
    assert sweep["state"] == "finished" and sweep["n_jobs"] == N_JOBS, sweep
    assert sweep["counts"]["succeeded"] == N_JOBS, sweep["counts"]
