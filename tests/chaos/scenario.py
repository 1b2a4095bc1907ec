"""One chaos scenario on a shared ``ChaosStack``: its jobs, workers, faults, waits and checks.

A test starts its own workers through the scenario, submits, injects faults through the stack,
then calls ``wait_terminal`` (bounded: remaining work + 2 lease periods + slack, failing with
the job rows, events and logs) and ``verify`` (stops the workers, then every invariant of
``tests.chaos.invariants``; fails with the same dump). ``close`` (the fixture's teardown)
leaves the shared stack clean for the next scenario even after a failure: leftover jobs are
cancelled in the database, leftover worker processes killed.

Measured numbers (recovery times, messages per job, waits) go to ``metrics``; ``verify``
prints them as one JSON line and appends it to ``$LEGOPT_CHAOS_METRICS`` when that is set
(``benchmarks/bench_chaos.py`` reads it).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import time
from datetime import datetime, timedelta
from pathlib import Path
from typing import Any

from sqlalchemy import update

from tests.chaos import invariants as inv
from tests.chaos.dbview import TERMINAL, DbView, Monitor
from tests.chaos.harness import ChaosStack, Fault, utcnow
from tests.chaos.workload import Submitted, submit
from tests.patience import Patience

#: Extra seconds allowed on top of every bound: 2 cores shared with other test runs.
SLACK_S = 20.0


class Scenario:
    """See the module docstring."""

    def __init__(self, stack: ChaosStack, name: str) -> None:
        self.stack, self.name = stack, name
        self.t0 = utcnow()
        self.view = DbView(stack.env["LEGOPT_DATABASE_URL"])
        #: how busy the machine is over the scenario (wall / quiet-machine seconds, >= 1)
        self.load = Patience(math.inf)
        self.monitor = Monitor(self.view, self.t0 - timedelta(seconds=1), on_tick=self._tick)
        self.monitor.start()
        self.ids: list[str] = []
        self.recorded: set[str] = set()
        self.workers: list[subprocess.Popen[bytes]] = []
        self.metrics: dict[str, Any] = {"scenario": name, "stack": stack.kind}
        self.lease_s = float(stack.env["LEGOPT_LEASE_SECONDS"])
        self._fault0 = len(stack.faults)
        self._cap0 = len(stack.capacity_log)
        self._cap_start = stack.capacity_log[-1][1] if stack.capacity_log else 0

    def _tick(self) -> None:
        self.stack.track_all()
        self.load.expired()  # integrates the quiet-machine clock

    @property
    def oversubscription(self) -> float:
        """The machine's mean CPU oversubscription over the scenario so far (>= 1)."""
        return max(1.0, self.load.wall_s / max(self.load.quiet_s, 1e-9))

    # ------------------------------------------------------------------ setup
    def mark(self, name: str) -> None:
        """Record when a phase ended (``t_<name>``: seconds since the scenario started)."""
        self.metrics[f"t_{name}"] = round((utcnow() - self.t0).total_seconds(), 2)

    def start_worker(self, concurrency: int = 1, *, wait: bool = True) -> subprocess.Popen[bytes]:
        proc = self.stack.start_worker(concurrency, wait=wait)
        self.workers.append(proc)
        return proc

    def start_workers(self, *concurrency: int) -> list[subprocess.Popen[bytes]]:
        """Start several workers at once (their imports overlap), then wait until all are
        ready."""
        procs = [self.start_worker(c, wait=False) for c in concurrency]
        for p in procs:
            self.stack.wait_ready(self.stack.worker(p))
        return procs

    def submit(self, spec: dict[str, Any], **kw: Any) -> Submitted:
        s = submit(self.stack.url, self.stack.key, spec, **kw)
        self.add([s.resource_id], recorded=bool(spec.get("record")))
        return s

    def add(self, ids: list[str], recorded: bool = False) -> None:
        for j in ids:
            if j not in self.ids:
                self.ids.append(j)
        if recorded:
            self.recorded.update(ids)

    @property
    def faults(self) -> list[Fault]:
        return self.stack.faults[self._fault0 :]

    @property
    def capacity_log(self) -> list[tuple[datetime, int]]:
        return [(self.t0, self._cap_start), *self.stack.capacity_log[self._cap0 :]]

    def all_ids(self) -> set[str]:
        """The scenario's jobs and every job created since it started (retries, probes)."""
        return set(self.ids) | {r["id"] for r in self.view.jobs_created_since(self.t0)}

    # ------------------------------------------------------------------ waiting
    def bound(self, n_jobs: int, job_s: float, slots: int) -> float:
        """Remaining work + 2 lease periods + slack (seconds)."""
        return math.ceil(n_jobs / max(slots, 1)) * job_s + 2 * self.lease_s + SLACK_S

    def wait_until(self, what: str, pred: Any, timeout_s: float, poll_s: float = 0.05) -> float:
        """Poll ``pred()`` until true; seconds waited (wall); fails with the dump after
        ``timeout_s`` quiet-machine seconds (``tests.patience``: a bound a busy CI machine
        stretches instead of breaking)."""
        patience = Patience(timeout_s)
        while not pred():
            if patience.expired():
                raise AssertionError(f"[{self.name}] timeout ({patience}): {what}\n"
                                     f"{self.dump()}")  # fmt: skip
            time.sleep(poll_s)
        return patience.wall_s

    def status(self, job_id: str) -> str | None:
        o = self.monitor.state(job_id)
        return None if o is None else o.status

    def wait_terminal(self, timeout_s: float, ids: list[str] | None = None) -> float:
        """Invariant 1: every job (default: all of the scenario's) terminal within
        ``timeout_s``; returns the seconds it took."""
        want = list(ids) if ids is not None else None

        def done() -> bool:
            targets = want if want is not None else sorted(self.all_ids())
            return all(self.status(j) in TERMINAL for j in targets)

        return self.wait_until("every job terminal", done, timeout_s)

    def running_on(self, pids: set[int]) -> dict[str, int]:
        """Jobs running under one of ``pids`` (as lease owner) now: job id -> attempt."""
        from tests.chaos.dbview import owner_pid

        out = {}
        for jid in self.ids:
            o = self.monitor.state(jid)
            if o is not None and o.status == "running" and owner_pid(o.owner) in pids:
                out[jid] = o.attempt
        return out

    def wait_reclaimed(self, victims: dict[str, int], timeout_s: float) -> float:
        """Seconds until every victim (job -> attempt when hit) is claimed again or terminal."""

        def done() -> bool:
            for jid, attempt in victims.items():
                o = self.monitor.state(jid)
                if o is None or not (o.status in TERMINAL or o.attempt > attempt):
                    return False
            return True

        return self.wait_until(f"victims {sorted(victims)} claimed again", done, timeout_s)

    # ------------------------------------------------------------------ checks
    def stop_workers(self) -> None:
        for proc in self.workers:
            self.stack.stop_worker(proc)

    def verify(
        self,
        *,
        expect: str | None = "succeeded",
        expect_other: dict[str, str | None] | None = None,
        strict_queue: tuple[set[str], float] | None = None,
    ) -> inv.Report:
        """Stop the workers, check invariants 1–6, print the metrics; raise on any failure.
        ``expect``: every job's final status (None: any terminal one), except the jobs of
        ``expect_other``. The queue rule allows 2 lease periods, and ``strict_queue``
        ``(ids, seconds)`` less to some jobs."""
        self.stop_workers()
        self.monitor.stop()
        now = utcnow()
        r = inv.Report(metrics=self.metrics)
        ids = self.all_ids()
        rows = self.view.job_rows(ids)
        events = self.view.event_rows(ids)
        other = expect_other or {}
        inv.check_terminal([x for x in rows if x["id"] not in other], ids - set(other), expect, r)
        for jid, status in other.items():
            inv.check_terminal([x for x in rows if x["id"] == jid], {jid}, status, r)
        inv.check_terminal_once(self.view, rows, events, r)
        if self.view.events is not None:
            timeline = inv.timeline_from_events(events)
            r.metrics["timeline"] = "job_events"
        else:
            timeline = inv.timeline_from_monitor(self.monitor.snapshot(), rows)
            r.metrics["timeline"] = "jobs rows + monitor (0.1 s polls)"
        # 2 lease periods of a quiet machine: on a machine k times oversubscribed every worker
        # start and poll takes about k times longer (tests.patience)
        load = self.oversubscription
        r.metrics["cpu_oversubscription"] = round(load, 2)
        waits = inv.queue_wait_check(
            timeline, ids, self.capacity_log, self.faults, now, 2 * self.lease_s * load, r
        )
        r.metrics["max_idle_queue_wait_s"] = round(max(waits.values(), default=0.0), 2)
        if strict_queue is not None:
            strict = inv.Report()
            inv.queue_wait_check(
                timeline, strict_queue[0], self.capacity_log, self.faults, now,
                strict_queue[1] * load, strict,
            )  # fmt: skip
            r.failures += [f"{f} [strict limit of this scenario]" for f in strict.failures]
        artifact_dir = Path(self.stack.env["LEGOPT_ARTIFACT_DIR"])
        r.metrics["artifacts_checked"] = inv.check_artifacts(
            self.view, rows, artifact_dir, self.recorded, r
        )
        inv.check_messages(
            self.view, rows, events, self.faults, self.stack.logs, now, r, self.lease_s
        )
        keep = {p.pid for p in (self.stack.api, getattr(self.stack.redis, "proc", None)) if p}
        for left in self.stack.leftover_processes(exclude=keep):
            r.fail(f"orphan process after the workers stopped: {left}")
        r.metrics["jobs"] = len(rows)
        self.emit(r)
        if r.failures:
            raise AssertionError(
                f"[{self.name} on {self.stack.kind}] {len(r.failures)} invariant(s) broken:\n  "
                + "\n  ".join(r.failures[:40])
                + f"\nskipped: {r.skipped}\nmetrics: {json.dumps(r.metrics)}\n"
                + self.dump(rows, events)
            )
        return r

    def emit(self, r: inv.Report) -> None:
        line = json.dumps({**r.metrics, "failures": len(r.failures), "skipped": r.skipped},
                          default=str)  # fmt: skip
        print(f"CHAOS-METRICS {line}")
        path = os.environ.get("LEGOPT_CHAOS_METRICS")
        if path:
            with open(path, "a") as f:
                f.write(line + "\n")

    def dump(
        self, rows: list[dict[str, Any]] | None = None, events: list[dict[str, Any]] | None = None
    ) -> str:
        """Job rows, events, monitor observations, faults, capacity and log tails."""
        try:
            ids = self.all_ids()
            rows = rows if rows is not None else self.view.job_rows(ids)
            events = events if events is not None else self.view.event_rows(ids)
            text = inv.render(rows, events, self.monitor.snapshot(), self.faults,
                              self.capacity_log, self.t0)  # fmt: skip
        except Exception as exc:  # the dump must never hide the original failure
            text = f"(could not read the database: {exc})"
        return f"{text}\nLOGS\n{self.log_tail()}"

    def log_tail(self, n: int = 4000) -> str:
        """The last ``n`` characters of the API log and of this scenario's worker logs."""
        paths = [self.stack.logs / "api.log", *(self.stack.worker(p).log for p in self.workers)]
        return "\n".join(
            f"--- {p.name}\n{p.read_text(errors='replace')[-n:]}" for p in paths if p.exists()
        )

    # ------------------------------------------------------------------ teardown
    def close(self) -> None:
        """Leave the shared stack clean (see the module docstring)."""
        if self.monitor.is_alive():
            self.monitor.stop()
        for proc in self.workers:
            try:
                self.stack.stop_worker(proc, timeout_s=10)
            except Exception:
                proc.kill()
        keep = {p.pid for p in (self.stack.api, getattr(self.stack.redis, "proc", None)) if p}
        if self.stack.leftover_processes(exclude=keep):
            self.stack.kill_leftovers(exclude=keep)
        self.stack.ensure_api()
        jobs = self.view.jobs
        left = [j for j in self.all_ids() if self.status(j) not in TERMINAL]
        if left:
            with self.view.engine.begin() as conn:
                conn.execute(
                    update(jobs)
                    .where(jobs.c.id.in_(left), jobs.c.status.in_(["queued", "running"]))
                    .values(status="cancelled", cancel_requested=True, lease_owner=None)
                )
        self.view.close()
