"""kill -9 of prefork pool children in the first seconds after the worker starts (issue 8,
defect 3: the reaper thread held the process-wide session lock while billiard forked the
replacement child, which then blocked forever in ``session_scope`` while the parent kept its
prefetched message and looked healthy).

Three rounds, each with a fresh ``--pool prefork -c 2`` worker: a job is queued before it
starts; 1.0 s after "ready." the child running it is killed (the job must still finish), then
at 1.98 s and 2.04 s the two oldest children — so that the two surviving replacements are
forked right at the first pass of the worker's background thread (the reaper's period is half a
lease: 2 s; a 1 s dispatcher passes then too), when it builds the process's engine under that
lock. Every surviving child must then claim a job of a second batch (a deadlocked child never
does; its Python stack is dumped through faulthandler), and every job must succeed.
Before the fix this caught the deadlock in round 1 of every run on the services stack. On the
embedded stack (filesystem broker: no async transport, so billiard's pool children share one
input-queue lock, and a child killed while holding it wedges the others) every round wedged
even with the fix: there a prefork pool is now refused at start with a message saying to run
several worker processes — which is what ``legopt serve`` does — and that refusal is tested.
"""

from __future__ import annotations

import contextlib
import signal
import subprocess
import time

import psutil
import pytest

from tests.chaos.dbview import owner_pid
from tests.chaos.scenario import Scenario
from tests.chaos.workload import job_spec

pytestmark = [pytest.mark.integration, pytest.mark.chaos]

ROUNDS = 3
#: Seconds after the worker logged "ready." (its background thread starts then).
KILL_OFFSETS_S = (1.0, 1.98, 2.04)
JOB_S = 3.0


def test_kill_9_pool_child_during_first_passes(scenario: Scenario) -> None:
    sc = scenario
    if sc.stack.kind == "embedded":
        _prefork_is_refused(sc)
        return
    for rnd in range(ROUNDS):
        _round(sc, rnd)
    sc.verify()


def _prefork_is_refused(sc: Scenario) -> None:
    from services.embedded import worker_command

    out = subprocess.run(
        worker_command("prefork", 2), env=sc.stack.env, capture_output=True, text=True, timeout=120
    )
    assert out.returncode != 0, out.stdout[-2000:]
    assert "one job per worker process" in out.stderr, out.stderr[-2000:]


def _round(sc: Scenario, rnd: int) -> None:
    first = sc.submit(job_spec(seed=300 + 10 * rnd, generations=120)).resource_id
    prefork = sc.start_worker(2)
    ready = time.monotonic()
    killed: list[int] = []
    kill_times: list[float] = []

    def fresh_children() -> list[int]:
        kids = sorted(sc.stack.pool_children(prefork), key=lambda p: p.create_time())
        return [p.pid for p in kids if p.pid not in killed]

    for offset in KILL_OFFSETS_S:
        time.sleep(max(0.0, ready + offset - time.monotonic()))
        sc.wait_until("a pool child to kill", lambda: bool(fresh_children()), 15, 0.01)
        kids = fresh_children()  # oldest first: the last replacements survive to be tested
        o = sc.monitor.state(first)
        busy = owner_pid(o.owner) if o is not None and o.status == "running" else None
        target = busy if busy in kids and not killed else kids[0]
        killed.append(sc.stack.kill_pool_child(prefork, target))
        kill_times.append(round(time.monotonic() - ready, 2))
    sc.metrics[f"round{rnd}_kills_at_s_after_ready"] = kill_times

    def replaced() -> bool:
        kids = {p.pid for p in sc.stack.pool_children(prefork)}
        return len(kids) == 2 and not kids & set(killed)

    sc.metrics[f"round{rnd}_replacement_s"] = round(
        sc.wait_until("replacement children", replaced, 30), 2
    )
    assert prefork.poll() is None, f"the worker died after its children were killed\n{sc.dump()}"
    children = {p.pid for p in sc.stack.pool_children(prefork)}
    sc.stack.track_all()

    # every live child must work: a second batch, two jobs per child
    batch = [sc.submit(job_spec(seed=301 + 10 * rnd + i, generations=30)).resource_id
             for i in range(4)]  # fmt: skip

    def every_child_claimed() -> bool:
        return children <= {owner_pid(o) for o in sc.monitor.owners(batch + [first])}

    try:
        sc.metrics[f"round{rnd}_every_child_claimed_s"] = round(
            sc.wait_until("every pool child claims a job", every_child_claimed,
                          4 * sc.lease_s + 10), 2)  # fmt: skip
    except AssertionError as exc:
        idle = children - {owner_pid(o) for o in sc.monitor.owners()}
        stacks = _python_stacks(sc, prefork, idle)
        raise AssertionError(
            f"round {rnd + 1}: pool child(ren) {sorted(idle)} forked by the kills at "
            f"{kill_times} s after ready never claimed a job: deadlocked (issue 8, defect 3)? "
            f"Their Python stacks:\n{stacks}\n{exc}"
        ) from None
    sc.metrics[f"round{rnd}_drain_s"] = round(
        sc.wait_terminal(sc.bound(5, JOB_S, 2), ids=[first, *batch]), 2
    )
    sc.stack.stop_worker(prefork)


def _python_stacks(sc: Scenario, worker: subprocess.Popen[bytes], pids: set[int]) -> str:
    """SIGABRT the stuck children: faulthandler (PYTHONFAULTHANDLER=1 in the chaos env) writes
    every thread's Python stack to the worker log; returns what it wrote."""
    log = sc.stack.worker(worker).log
    mark = log.stat().st_size
    for pid in pids:
        with contextlib.suppress(psutil.Error):
            psutil.Process(pid).send_signal(signal.SIGABRT)
    time.sleep(1.5)
    with open(log, errors="replace") as f:
        f.seek(mark)
        text = f.read()
    dumps = [d.split("Extension modules")[0] for d in text.split("Fatal Python error")[1:]]
    return "\n".join(d[:4000] for d in dumps) or text[-3000:]
