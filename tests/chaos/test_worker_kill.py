"""kill -9 of a worker's main process mid-job: a prefork parent (its pool children die with it;
on the embedded stack, where prefork is refused, a second solo worker) and then a solo worker.
The jobs they held are requeued once their lease expires and finish elsewhere from their
checkpoints; nothing is left behind (issue 8, defects 2 and 7)."""

from __future__ import annotations

import pytest

from tests.chaos.scenario import Scenario
from tests.chaos.workload import job_spec

pytestmark = [pytest.mark.integration, pytest.mark.chaos]

N_JOBS = 6
N_SECOND = 4
GENERATIONS = 80
JOB_S = 4.0  # generous per-job time on a loaded 2-core machine


def test_kill_9_worker_parents_mid_job(scenario: Scenario) -> None:
    sc = scenario
    concurrency = 1 if sc.stack.kind == "embedded" else 2
    solo, prefork = sc.start_workers(1, concurrency)
    sc.mark("workers_ready")
    for i in range(N_JOBS):
        sc.submit(job_spec(seed=100 + i, generations=GENERATIONS, record=i % 4 == 0))

    # 1. the prefork parent, once one of its children runs a job past generation 3
    children = (
        {p.pid for p in sc.stack.pool_children(prefork)} if concurrency > 1 else {prefork.pid}
    )

    def child_busy() -> bool:
        held = sc.running_on(children)
        return any((o := sc.monitor.state(j)) is not None and o.generation >= 3 for j in held)

    sc.wait_until("a prefork child runs a job", child_busy, 60)
    sc.mark("first_kill")
    victims = sc.running_on(children)
    sc.stack.kill_worker(prefork)
    fault = sc.faults[-1]
    fault.victims = sorted(victims)
    sc.start_worker(1)  # capacity back
    sc.metrics["prefork_parent_reclaim_s"] = round(
        sc.wait_reclaimed(victims, 2 * sc.lease_s + sc.bound(0, 0, 1)), 2
    )

    # 2. the solo worker, running a job of a second wave
    for i in range(N_SECOND):
        sc.submit(job_spec(seed=150 + i, generations=GENERATIONS, record=i == 0))

    def solo_busy() -> bool:
        held = sc.running_on({solo.pid})
        return any((o := sc.monitor.state(j)) is not None and o.generation >= 3 for j in held)

    sc.wait_until("the solo worker runs a job", solo_busy, 60)
    victims = sc.running_on({solo.pid})
    sc.stack.kill_worker(solo)
    sc.faults[-1].victims = sorted(victims)
    sc.metrics["solo_reclaim_s"] = round(
        sc.wait_reclaimed(victims, 2 * sc.lease_s + sc.bound(0, 0, 1)), 2
    )

    sc.metrics["drain_after_last_fault_s"] = round(
        sc.wait_terminal(sc.bound(N_JOBS + N_SECOND, JOB_S, 2)), 2
    )
    rows = sc.view.job_rows(sc.ids)
    resumed = [r for r in rows if r["attempt_count"] > 1]
    assert resumed, "no job was hit by the kills (timing): the scenario proved nothing"
    sc.verify()
