"""The invariants every chaos scenario must end with (issue 8), read from the database.

1. **Terminal**: every job ends succeeded / failed / cancelled once the faults stop, within
   (remaining work + 2 lease periods + slack) — ``Scenario.wait_terminal`` enforces the bound;
   ``check_terminal`` then also checks the expected outcome (normally ``succeeded``).
2. **Terminal exactly once**: exactly one terminal row in ``job_events`` per job, matching
   the job's status, and no claim or requeue after it. Skipped (with the reason) while the
   schema has no ``job_events`` table.
3. **No wedged queue**: no job waits in ``queued`` for longer than ``limit_s`` (2 lease
   periods) of *idle-capacity time*. The rule, kept simple: time in ``queued`` is counted only
   at instants when (a) at least one worker job slot is up (the harness's capacity log: ready
   and neither killed nor paused), (b) fewer jobs are ``running`` than slots are up (a job
   still leased by a dead worker counts as running, which errs on the side of excusing), and
   (c) no fault that blocks every worker (Redis down) is open — and only in stretches of at
   least 0.5 s (a worker between two jobs is not idle). The state timeline comes from
   ``job_events`` (submitted / requeued -> queued, claimed -> running, terminal) or, while it
   does not exist, from the ``jobs`` rows' own times (created, first claim, end) plus the
   monitor's 0.1 s polls for what happened in between (requeues, later claims).
4. **Artifacts**: every ``artifacts`` row's file exists under ``LEGOPT_ARTIFACT_DIR`` with its
   size and SHA-256, and every succeeded job submitted with ``record: true`` has a recording.
5. **No orphans**: see ``ChaosStack.leftover_processes`` (checked by the scenario).
6. **Messages per job**: ``dispatched`` events per job; mean (beyond paced re-sends) <= 3; per job,
   <= 1 + the number of faults that happened while the job was not terminal, + 1 after a
   fault: the dispatcher's one early re-send when the broker holds fewer messages than there
   are queued jobs (a message a live worker has taken but not yet claimed is not counted by
   the broker, so one rescue of it may be a duplicate; a storm is still caught), + each
   re-send the protocol allows under delay: one that came at least a lease after the job's
   previous send while the job stayed queued (the early re-send waits a lease, the backoff
   two or more), so a slow machine that keeps a job waiting earns it a message per lease,
   while re-sends closer together than a lease (a storm) still break the bound. Without
   ``job_events`` the count is *estimated from the worker logs* (1 API send + each job id in a
   reaper's ``re-sent [...]`` line), reported, and held to the same bound.
"""

from __future__ import annotations

import hashlib
import re
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from datetime import datetime, timedelta
from pathlib import Path
from typing import Any

import numpy as np

from tests.chaos.dbview import TERMINAL, DbView, Observation
from tests.chaos.harness import Fault

GRID_S = 0.1
#: A slot idle for less than this (a worker between two jobs) does not count as idle.
IDLE_MIN_S = 0.5
QUEUED_KINDS = {"submitted", "requeued"}
UUID = re.compile(r"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}")


@dataclass
class Report:
    """Failures (each one sentence with the evidence), skipped checks, measured numbers."""

    failures: list[str] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    metrics: dict[str, Any] = field(default_factory=dict)

    def fail(self, msg: str) -> None:
        self.failures.append(msg)


@dataclass(frozen=True)
class Transition:
    at: datetime
    job_id: str
    state: str  # queued | running | succeeded | failed | cancelled


def timeline_from_events(events: list[dict[str, Any]]) -> list[Transition]:
    out = []
    for e in events:
        kind = e["kind"]
        if kind in QUEUED_KINDS:
            out.append(Transition(e["at"], e["job_id"], "queued"))
        elif kind == "claimed":
            out.append(Transition(e["at"], e["job_id"], "running"))
        elif kind in TERMINAL:
            out.append(Transition(e["at"], e["job_id"], kind))
    return out


def timeline_from_monitor(
    observations: list[Observation], rows: list[dict[str, Any]]
) -> list[Transition]:
    """The precise times the ``jobs`` row keeps (created, first claim, end) plus, from the
    monitor's polls, what happened in between (requeues and later claims)."""
    out = []
    for row in rows:
        jid = row["id"]
        out.append(Transition(row["created_at"], jid, "queued"))
        if row.get("started_at") is not None:
            out.append(Transition(row["started_at"], jid, "running"))
        if row["status"] in TERMINAL and row.get("finished_at") is not None:
            out.append(Transition(row["finished_at"], jid, row["status"]))
        end = row.get("finished_at")
        for o in observations:
            if o.job_id != jid or (end is not None and o.at >= end):
                continue
            if (o.status == "queued" and o.attempt >= 1) or (
                o.status == "running" and o.attempt >= 2
            ):
                out.append(Transition(o.at, jid, o.status))
    return sorted(out, key=lambda t: t.at)


def _drop_short_runs(mask: np.ndarray, min_len: int) -> np.ndarray:
    """``mask`` without its runs of True shorter than ``min_len`` samples."""
    out = mask.copy()
    i, n = 0, len(mask)
    while i < n:
        if mask[i]:
            j = i
            while j < n and mask[j]:
                j += 1
            if j - i < min_len:
                out[i:j] = False
            i = j
        else:
            i += 1
    return out


def check_terminal(
    rows: list[dict[str, Any]], ids: set[str], expect: str | None, r: Report
) -> None:
    seen = {row["id"] for row in rows}
    for jid in sorted(ids - seen):
        r.fail(f"job {jid} is missing from the database")
    for row in rows:
        if row["status"] not in TERMINAL:
            r.fail(f"job {row['id']} is {row['status']} (attempt {row['attempt_count']}), "
                   f"not terminal")  # fmt: skip
        elif expect is not None and row["status"] != expect:
            r.fail(f"job {row['id']} ended {row['status']}, expected {expect}: "
                   f"{row.get('error_message')}")  # fmt: skip


def check_terminal_once(
    view: DbView, rows: list[dict[str, Any]], events: list[dict[str, Any]], r: Report
) -> None:
    if view.events is None:
        r.skipped.append(f"terminal exactly once: {view.missing_events_reason}")
        return
    by_job: dict[str, list[dict[str, Any]]] = {}
    for e in events:
        by_job.setdefault(e["job_id"], []).append(e)
    for row in rows:
        evs = by_job.get(row["id"], [])
        terminal = [e for e in evs if e["kind"] in TERMINAL]
        if len(terminal) != 1:
            r.fail(f"job {row['id']}: {len(terminal)} terminal events "
                   f"({[e['kind'] for e in terminal]}), expected exactly 1")  # fmt: skip
            continue
        if terminal[0]["kind"] != row["status"]:
            r.fail(f"job {row['id']}: terminal event {terminal[0]['kind']} but status "
                   f"{row['status']}")  # fmt: skip
        after = [e["kind"] for e in evs if e["kind"] in {"claimed", "requeued"}
                 and (e["at"], e["id"]) > (terminal[0]["at"], terminal[0]["id"])]  # fmt: skip
        if after:
            r.fail(f"job {row['id']}: {after} after its terminal event")
        if not any(e["kind"] == "submitted" for e in evs):
            r.fail(f"job {row['id']}: no 'submitted' event")


def capacity_series(
    grid: np.ndarray, t0: datetime, capacity_log: list[tuple[datetime, int]]
) -> np.ndarray:
    cap = np.zeros_like(grid)
    for at, slots in sorted(capacity_log):
        cap[grid >= (at - t0).total_seconds()] = slots
    return cap


def queue_wait_check(
    transitions: list[Transition],
    ids: set[str],
    capacity_log: list[tuple[datetime, int]],
    faults: list[Fault],
    now: datetime,
    limit_s: float,
    r: Report,
) -> dict[str, float]:
    """Rule 3 (module docstring); returns each job's counted queue wait (s)."""
    if not transitions:
        return {}
    t0 = min(t.at for t in transitions)
    grid = np.arange(0.0, (now - t0).total_seconds() + GRID_S, GRID_S)
    cap = capacity_series(grid, t0, capacity_log)
    running = np.zeros_like(grid)
    blocked = np.zeros(grid.shape, dtype=bool)
    for f in faults:
        if f.blocks_workers:
            a = (f.start - t0).total_seconds()
            b = ((f.end or now) - t0).total_seconds()
            blocked |= (grid >= a) & (grid <= b)
    intervals: dict[str, list[tuple[float, float, str]]] = {}
    per_job: dict[str, list[Transition]] = {}
    for t in sorted(transitions, key=lambda t: t.at):
        per_job.setdefault(t.job_id, []).append(t)
    for jid, ts in per_job.items():
        for cur, nxt in zip(ts, [*ts[1:], None], strict=True):
            start = (cur.at - t0).total_seconds()
            end = (nxt.at - t0).total_seconds() if nxt is not None else float(grid[-1])
            intervals.setdefault(jid, []).append((start, end, cur.state))
            if cur.state == "running":
                running[(grid >= start) & (grid < end)] += 1
    idle = _drop_short_runs((cap > 0) & (running < cap) & ~blocked, round(IDLE_MIN_S / GRID_S))
    waits: dict[str, float] = {}
    for jid in ids:
        worst = 0.0
        for start, end, state in intervals.get(jid, []):
            if state == "queued":
                worst = max(worst, float(np.count_nonzero(idle & (grid >= start) & (grid < end)))
                            * GRID_S)  # fmt: skip
        waits[jid] = worst
        if worst > limit_s:
            r.fail(f"job {jid} waited {worst:.1f} s in 'queued' while a worker slot was up and "
                   f"idle (limit {limit_s:.1f} s)")  # fmt: skip
    return waits


def check_artifacts(
    view: DbView, rows: list[dict[str, Any]], artifact_dir: Path, recorded: set[str], r: Report
) -> int:
    """Rule 4; returns the number of files verified."""
    arts = view.artifact_rows([row["id"] for row in rows])
    for a in arts:
        path = artifact_dir / a["relative_path"]
        if not path.is_file():
            r.fail(f"job {a['job_id']}: artifact {a['kind']} file {a['relative_path']} missing")
            continue
        data = path.read_bytes()
        if len(data) != a["size_bytes"] or hashlib.sha256(data).hexdigest() != a["sha256"]:
            r.fail(f"job {a['job_id']}: artifact {a['kind']} ({a['relative_path']}) does not "
                   f"match its row: {len(data)} B sha256 {hashlib.sha256(data).hexdigest()[:12]}"
                   f" vs {a['size_bytes']} B {a['sha256'][:12]}")  # fmt: skip
    have = {(a["job_id"], a["kind"]) for a in arts}
    for row in rows:
        if row["status"] == "succeeded" and row["id"] in recorded:
            if (row["id"], "recording") not in have:
                r.fail(f"job {row['id']} succeeded with record: true but has no recording "
                       f"(warnings: {row.get('warnings')})")  # fmt: skip
    return len(arts)


def resends_from_logs(log_dir: Path) -> Counter[str]:
    """Job ids in reaper ``re-sent [...]`` lines of the worker logs (pre-``job_events``)."""
    c: Counter[str] = Counter()
    for p in log_dir.glob("worker*.log"):
        for line in p.read_text(errors="replace").splitlines():
            if "re-sent" in line:
                seg = line.split("re-sent", 1)[1].split("]", 1)[0]
                c.update(UUID.findall(seg))
    return c


def faults_during(row: dict[str, Any], faults: list[Fault], now: datetime) -> int:
    start = row["created_at"]
    end = row.get("finished_at") or now
    return sum(1 for f in faults if f.start <= end and (f.end or now) >= start)


#: A re-send at least this fraction of a lease after the previous one is one the protocol
#: allows (the database clock of two processes on one machine; the rest is rounding).
SPACING_TOLERANCE = 0.95


def paced_resends(events: list[dict[str, Any]], lease_s: float) -> Counter[str]:
    """Per job, the re-sends the dispatch protocol allows under delay: ``dispatched`` events
    that came at least a lease (× ``SPACING_TOLERANCE``) after the job's previous one with no
    claim between them (the job stayed queued, its earlier message unclaimed)."""
    allowed: Counter[str] = Counter()
    last_send: dict[str, datetime] = {}
    for e in sorted(events, key=lambda x: x["at"]):
        jid, kind = e["job_id"], e["kind"]
        if kind == "dispatched":
            before = last_send.get(jid)
            if before is not None and (e["at"] - before).total_seconds() >= (
                SPACING_TOLERANCE * lease_s
            ):
                allowed[jid] += 1
            last_send[jid] = e["at"]
        elif kind != "submitted":
            last_send.pop(jid, None)  # claimed, requeued or ended: a new queued stretch
    return allowed


def check_messages(
    view: DbView,
    rows: list[dict[str, Any]],
    events: list[dict[str, Any]],
    faults: list[Fault],
    log_dir: Path,
    now: datetime,
    r: Report,
    lease_s: float,
    mean_limit: float = 3.0,
) -> None:
    """Rule 6; puts ``messages_per_job_mean/max`` and their source in ``r.metrics``."""
    if not rows:
        return
    paced: Counter[str] = Counter()
    if view.events is not None:
        counts = Counter(e["job_id"] for e in events if e["kind"] == "dispatched")
        paced = paced_resends(events, lease_s)
        source = "job_events"
    else:
        counts = resends_from_logs(log_dir)
        counts.update({row["id"]: 1 for row in rows})
        source = "estimated from worker logs (1 + reaper re-sends)"
    per_job = {row["id"]: counts.get(row["id"], 0) for row in rows}
    mean = sum(per_job.values()) / len(per_job)
    # the mean bound counts what the protocol does not pace: a re-send a lease or more after
    # the one before is the backoff working on a slow machine, not a flood
    unpaced = sum(max(0, n - paced[j]) for j, n in per_job.items()) / len(per_job)
    r.metrics["messages_per_job_mean"] = round(mean, 2)
    r.metrics["messages_per_job_unpaced_mean"] = round(unpaced, 2)
    r.metrics["messages_per_job_max"] = max(per_job.values())
    r.metrics["messages_source"] = source
    if unpaced > mean_limit:
        r.fail(f"{unpaced:.2f} messages per job on average beyond the paced re-sends "
               f"({source}; {mean:.2f} in all), limit {mean_limit}")  # fmt: skip
    for row in rows:
        during = faults_during(row, faults, now)
        bound = 1 + during + (1 if during else 0) + paced[row["id"]]
        if per_job[row["id"]] > bound:
            r.fail(f"job {row['id']}: {per_job[row['id']]} messages ({source}), bound {bound} "
                   f"(1 + faults while it was live, + 1 rescue after a fault, + "
                   f"{paced[row['id']]} sent a lease or more after the one before)")  # fmt: skip
        if view.events is not None and per_job[row["id"]] == 0 and row["attempt_count"] > 0:
            r.fail(f"job {row['id']} was claimed without any 'dispatched' event")


def render(
    rows: list[dict[str, Any]],
    events: list[dict[str, Any]],
    observations: list[Observation],
    faults: list[Fault],
    capacity_log: list[tuple[datetime, int]],
    t0: datetime,
) -> str:
    """Job rows, events (or monitor observations), faults and capacity, times relative to t0."""

    def rel(t: datetime | None) -> str:
        return "-" if t is None else f"{(t - t0).total_seconds():7.2f}"

    out = ["JOBS (times in s from the scenario start)"]
    for row in rows:
        out.append(f"  {row['id']} {row['status']:9} att={row['attempt_count']} "
                   f"gen={row['progress_generation']}/{row['total_generations']} "
                   f"created={rel(row['created_at'])} started={rel(row.get('started_at'))} "
                   f"finished={rel(row.get('finished_at'))} owner={row.get('lease_owner')} "
                   f"err={(row.get('error_message') or '')[:120]}")  # fmt: skip
    if events:
        out.append("JOB_EVENTS")
        for e in events:
            out.append(f"  {rel(e['at'])} {e['job_id'][:8]} {e['kind']:10} att={e['attempt']} "
                       f"{e.get('actor') or ''} {(e.get('detail') or '')[:100]}")  # fmt: skip
    out.append("MONITOR (status changes seen by polling)")
    out += [f"  {rel(o.at)} {o.job_id[:8]} {o.status:9} att={o.attempt} gen={o.generation} "
            f"{o.owner or ''}" for o in observations]  # fmt: skip
    out.append("FAULTS")
    out += [f"  {rel(f.start)}..{rel(f.end)} {f.kind} {f.target}" for f in faults]
    out.append("CAPACITY (job slots up)")
    out += [f"  {rel(at)} {slots}" for at, slots in capacity_log]
    return "\n".join(out)


def only_since(faults: Iterable[Fault], since: datetime) -> list[Fault]:
    return [f for f in faults if (f.end or f.start) >= since - timedelta(seconds=1)]
