"""Worker recycling cannot lose, repeat or wedge a job (issue 8: "worker recycling
(``max_tasks_per_child`` or memory limit) that cannot deadlock").

``LEGOPT_WORKER_MAX_MEMORY_MB=1`` makes every worker process "too large" after each job:

- services stack, ``--pool prefork -c 2``: Celery's ``worker_max_memory_per_child`` replaces the
  pool child after every task, so each job after the first two runs in a freshly forked child
  (the fork the reaper's lock once deadlocked: defect 3). Every job must succeed exactly once
  and more children than slots must have existed.
- embedded stack (solo workers; prefork is refused there): the worker asks Celery for a warm
  shutdown after its job — the message of that job is handled, the others stay queued — and
  exits 0; a fresh worker (what ``legopt serve``'s supervisor starts) takes the next job.
"""

from __future__ import annotations

import subprocess

import pytest

from tests.chaos.scenario import Scenario
from tests.chaos.workload import job_spec
from tests.patience import Patience

pytestmark = [pytest.mark.integration, pytest.mark.chaos]

N_JOBS = 6
JOB_S = 3.0
LIMIT_ENV = {"LEGOPT_WORKER_MAX_MEMORY_MB": "1"}


def _with_env(sc: Scenario, concurrency: int) -> subprocess.Popen[bytes]:
    saved = {k: sc.stack.env.get(k) for k in LIMIT_ENV}
    sc.stack.env.update(LIMIT_ENV)
    try:
        return sc.start_worker(concurrency)
    finally:
        for k, v in saved.items():
            if v is None:
                sc.stack.env.pop(k, None)
            else:
                sc.stack.env[k] = v


def test_recycled_workers_finish_every_job_once(scenario: Scenario) -> None:
    sc = scenario
    solo = sc.stack.kind == "embedded"
    proc = _with_env(sc, 1 if solo else 2)  # ready before the jobs: no wait counted as loss
    ids = [sc.submit(job_spec(seed=700 + i, generations=2)).resource_id for i in range(N_JOBS)]
    if solo:
        _solo_rounds(sc, ids, proc)
    else:
        _prefork(sc, ids, proc)
    sc.verify()


def _prefork(sc: Scenario, ids: list[str], proc: subprocess.Popen[bytes]) -> None:
    seen: set[int] = set()

    def done() -> bool:
        seen.update(p.pid for p in sc.stack.pool_children(proc))
        return all(sc.status(j) == "succeeded" for j in ids)

    sc.wait_until("every job done by recycled pool children", done,
                  sc.bound(N_JOBS, JOB_S, 2) + 60, 0.05)  # fmt: skip
    sc.metrics["pool_children_seen"] = len(seen)
    assert len(seen) > 2, f"no pool child was replaced ({len(seen)} seen)"
    assert proc.poll() is None, "the worker itself must stay up"


def _solo_rounds(sc: Scenario, ids: list[str], first: subprocess.Popen[bytes]) -> None:
    rounds = 0
    gap = None  # the recycled worker's exit: no worker until the next one is ready
    patience = Patience(sc.bound(N_JOBS, JOB_S, 1) + 30 * N_JOBS)
    proc: subprocess.Popen[bytes] | None = first
    while not all(sc.status(j) == "succeeded" for j in ids):
        assert not patience.expired(), f"jobs left after {rounds} recycled workers ({patience})"
        if proc is None:
            proc = _with_env(sc, 1)
            if gap is not None:
                gap.close()
        rounds += 1
        sc.wait_until("the worker to recycle itself after a job",
                      lambda p=proc: p.poll() is not None, 60 + JOB_S * N_JOBS, 0.05)  # fmt: skip
        assert proc.returncode == 0, f"a recycled worker exits 0, got {proc.returncode}"
        w = sc.stack.worker(proc)
        w.up = False
        sc.stack._capacity_changed()
        # a recycle is not a fault, but while no worker runs the dispatcher re-sends the
        # long-queued jobs' messages (it cannot tell a waiting message from a lost one): the
        # message bound counts that gap like a fault
        gap = sc.stack.fault("recycle", w.name)
        proc = None
    if gap is not None:
        gap.close()
    sc.metrics["recycled_workers"] = rounds
    assert rounds >= 2, "the memory limit should have stopped a worker after its first job"
