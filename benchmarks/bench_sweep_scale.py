"""Sweeps of 10⁴ jobs at flat cost (issue 20 item 5) on a real stack: a fresh PostgreSQL
database (dropped after), a private redis-server, the API (uvicorn, ``--api-workers``) and W =
``--workers`` solo Celery workers (``worker_command``, warmed up: ``LEGOPT_WORKER_WARMUP=true``).

1. Scale: ONE ``POST /sweeps`` of N = ``--jobs`` tiny jobs (seed 003's gait, 16 samples a cycle,
   GA of 10, 2 generations, no recording), drained (polling ``GET /sweeps/{id}``).
2. Ray Tune's measure: ``--tune-jobs`` jobs of ``budget.wall_time_s = --job-seconds``.
3. Cancel: ``--cancel-jobs`` jobs (``wall_time_s`` 30) cancelled by ONE ``POST .../cancel``;
   then one job's submit→start wait behind their queue messages.

Figures (seconds unless stated; database times, one machine's clock):

- run time r_k: the job's optimiser steps (sum of its ``generations.wall_time_s``).
- overhead o_k = f_k − f_prev − r_k: a worker slot's time per job beyond r_k (f_k its
  ``finished_at``, f_prev that of the job the same worker — ``claimed`` event's actor — ran
  before): message delivery, stale messages, claim, problem build, progress writes, finalisation,
  result store; a worker's first job left out. Claim order; goal: mean of the last K ≤ 1.2 ×
  that of the first K, K = min(1000, N // 3). "in-job": f − started − r (build and finalisation).
- messages per job: ``dispatched`` events (one per queue message sent) / N; goal ≤ 1.1.
- idle-worker queue wait: rule 3 of ``tests/chaos/invariants.py`` — time queued (created →
  started) at instants when fewer than W jobs run, in stretches ≥ 0.5 s, 0.1 s grid; the
  largest, in leases (``--lease-seconds``, compose's 60); goal ≤ 2.
- jobs/s: N / T, T from the POST sent to the last ``finished_at``.
- Ray Tune: T / (N · d / W), d the mean r_k (or of started → finished); goal ≤ 1.05, d = 1 s.
- /health: ``GET /health`` every ``--health-interval`` s on a thread: p50 / p95 / max ms.

Settings as shipped (``LEGOPT_MAX_SWEEP_JOBS`` 10 000, validation timeout 120 s), except
``LEGOPT_QUOTA_ACTIVE_JOBS``, raised above the three sweeps' jobs together.

    python benchmarks/bench_sweep_scale.py [--jobs 10000] [--tune-jobs 200] [--job-seconds 1]
"""

from __future__ import annotations

import argparse
import itertools
import math
import os
import platform
import sys
import tempfile
import threading
import time
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack
from datetime import datetime
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import redis
import yaml
from sqlalchemy import create_engine, text

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
GRID_S, IDLE_MIN_S = 0.1, 0.5


def job_spec(budget: dict[str, Any]) -> dict[str, Any]:
    """Seed 003's gait made small (the chaos suite's unit) with a GA of 10 (no early stop)."""
    spec = yaml.safe_load((ROOT / "examples" / "003_quadruped_gait.yaml").read_text())
    spec["problem"].update(samples_per_cycle=16, table_positions=12)
    spec.update(optimizer={"kind": "ga", "params": {"pop_size": 10}}, budget=budget, record=False)
    spec.pop("seed", None)
    return dict(spec)


def sweep(budget: dict[str, Any], n: int) -> dict[str, Any]:
    return {"base": job_spec(budget), "seeds": list(range(1, n + 1))}


class HealthSampler(threading.Thread):
    """``GET /health`` every ``interval`` s; samples (phase, ms), ``inf`` for a failure."""

    def __init__(self, url: str, interval: float) -> None:
        super().__init__(daemon=True)
        self.url, self.interval, self.phase = f"{url}/api/v1/health", interval, "idle"
        self.samples: list[tuple[str, float]] = []
        self.halt = threading.Event()

    def run(self) -> None:
        with httpx.Client(timeout=30) as c:
            while not self.halt.wait(self.interval):
                t, phase = time.perf_counter(), self.phase
                ms = 1e3 * (time.perf_counter() - t) if answers(self.url, c) else math.inf
                self.samples.append((phase, ms))

    def stats(self, *phases: str) -> str:
        ms = np.array([v for p, v in self.samples if p in phases])
        ok = ms[np.isfinite(ms)]
        p50, p95 = np.percentile(ok, [50, 95]) if ok.size else (math.nan, math.nan)
        top = ok.max() if ok.size else math.nan
        return f"{p50:.1f} / {p95:.1f} / {top:.0f} ({ms.size} polls, {ms.size - ok.size} failed)"


def submit(http: httpx.Client, path: str, body: Any = None) -> tuple[dict[str, Any], float, float]:
    """One POST (never retried): (answer, epoch sent, seconds to the answer)."""
    sent, t = time.time(), time.perf_counter()
    r = http.post(path, json=body)
    took = time.perf_counter() - t
    if r.status_code not in (200, 201, 202):
        raise SystemExit(f"POST {path} answered {r.status_code} after {took:.1f} s: {r.text[:800]}")
    return dict(r.json()), sent, took


def wait_drained(http: httpx.Client, sweep_id: str, timeout_s: float) -> None:
    """Poll the sweep's counts until no job is queued or running."""
    deadline = time.monotonic() + timeout_s
    for polls in itertools.count(1):
        counts = dict(http.get(f"/sweeps/{sweep_id}", params={"limit": 1}).json()["counts"])
        if counts["queued"] + counts["running"] == 0:
            return
        if time.monotonic() > deadline:
            raise SystemExit(f"sweep {sweep_id} not drained in {timeout_s:.0f} s: {counts}")
        if polls % 60 == 0:
            print(f"  {sweep_id[:8]}: {counts}", file=sys.stderr, flush=True)
        time.sleep(0.5)  # the polling period


def read_sweep(engine: Any, sweep_id: str) -> dict[str, dict[str, Any]]:
    """Per job: created, started, finished (epoch s), run (s), claims [(at, actor)], msgs."""
    q = {"s": sweep_id}
    jobs: dict[str, dict[str, Any]] = {}
    with engine.connect() as conn:
        for jid, status, c, s, f in conn.execute(text(
            "SELECT id, status, created_at, started_at, finished_at FROM jobs WHERE sweep_id = :s"
        ), q):  # fmt: skip
            jobs[jid] = {"status": str(status), "c": c.timestamp(), "s": s and s.timestamp(),
                         "f": f and f.timestamp(), "run": 0.0, "claims": [], "msgs": 0}  # fmt: skip
        for jid, run in conn.execute(text(
            "SELECT g.job_id, SUM(g.wall_time_s) FROM generations g JOIN jobs j "
            "ON j.id = g.job_id WHERE j.sweep_id = :s GROUP BY g.job_id"), q):  # fmt: skip
            jobs[jid]["run"] = float(run)
        for jid, kind, at, actor in conn.execute(text(
            "SELECT e.job_id, e.kind, e.at, e.actor FROM job_events e JOIN jobs j "
            "ON j.id = e.job_id WHERE j.sweep_id = :s ORDER BY e.at, e.id"), q):  # fmt: skip
            if kind == "claimed":
                jobs[jid]["claims"].append((at.timestamp(), actor))
            elif kind == "dispatched":
                jobs[jid]["msgs"] += 1
    return jobs


def idle_queue_wait(jobs: list[dict[str, Any]], workers: int) -> float:
    """The longest a job was queued while fewer than ``workers`` jobs ran (module docstring)."""
    t0, t1 = min(j["c"] for j in jobs), max(j["f"] for j in jobs)
    n = int((t1 - t0) / GRID_S) + 2

    def cell(t: float) -> int:
        return min(n - 1, int((t - t0) / GRID_S))

    delta = np.zeros(n + 1)
    for j in jobs:
        delta[cell(j["s"])] += 1
        delta[cell(j["f"])] -= 1
    idle = np.cumsum(delta)[:n] < workers
    edges = np.flatnonzero(np.diff(np.concatenate([[0], idle.astype(np.int8), [0]])))
    for a, b in zip(edges[::2], edges[1::2], strict=True):  # drop idle stretches < 0.5 s
        if (b - a) * GRID_S < IDLE_MIN_S:
            idle[a:b] = False
    cum = np.concatenate([[0], np.cumsum(idle)])
    return max(float(cum[cell(j["s"])] - cum[cell(j["c"])]) * GRID_S for j in jobs)


def analyse(jobs: dict[str, dict[str, Any]], sent: float, workers: int) -> dict[str, Any]:
    """The scale figures of one drained sweep (module docstring)."""
    done = sorted((j for j in jobs.values() if j["s"] and j["f"]), key=lambda j: j["claims"][0])
    prev: dict[str, float] = {}
    overhead: list[float] = []
    for j in done:
        actor = j["claims"][0][1]
        if actor in prev:
            overhead.append(j["f"] - prev[actor] - j["run"])
        prev[actor] = j["f"]
    k = max(1, min(1000, len(overhead) // 3))
    first, last = float(np.mean(overhead[:k])), float(np.mean(overhead[-k:]))
    msgs = np.array([j["msgs"] for j in jobs.values()])
    wall = max(j["f"] for j in done) - sent
    return {
        "n": len(jobs), "statuses": dict(Counter(j["status"] for j in jobs.values())),
        "wall": wall, "rate": len(done) / wall, "k": k, "first": first, "last": last,
        "ratio": last / first, "in_job": float(np.mean([j["f"] - j["s"] - j["run"] for j in done])),
        "run": float(np.mean([j["run"] for j in done])), "msgs": float(msgs.mean()),
        "busy": float(np.mean([j["f"] - j["s"] for j in done])),
        "msgs_max": int(msgs.max()), "dup": int((msgs > 1).sum()),
        "wait_p50": float(np.median([j["s"] - j["c"] for j in done])),
        "idle_wait": idle_queue_wait(done, workers), "claims": sum(len(j["claims"]) for j in done),
    }  # fmt: skip


def broker_depth(redis_url: str) -> int:
    """Messages waiting in the job queue (its priority lists included)."""
    r = redis.Redis.from_url(redis_url)
    return sum(int(r.llen(k)) for k in r.scan_iter("legopt*") if r.type(k) == b"list")


def machine(engine: Any, redis_url: str) -> str:
    cpu = next((ln.split(":", 1)[1].strip() for ln in Path("/proc/cpuinfo").read_text()
                .splitlines() if ln.startswith("model name")), platform.processor())  # fmt: skip
    with engine.connect() as conn:
        pg = conn.execute(text("SHOW server_version")).scalar_one()
    rv = redis.Redis.from_url(redis_url).info("server")["redis_version"]
    return (f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, "
            f"PostgreSQL {pg}, Redis {rv}")  # fmt: skip


def start(stack: ExitStack, tmp: Path, args: argparse.Namespace) -> tuple[Any, str]:
    """The stack (module docstring), torn down by ``stack``; (Stack, database URL)."""
    from tests.integration.stack import RedisServer, Stack, postgres_database

    db = stack.enter_context(postgres_database())
    server = RedisServer(tmp)
    server.start()
    stack.callback(server.stop)
    (tmp / "data").mkdir(parents=True, exist_ok=True)
    st = Stack("services", tmp, db, server.url)
    st.env.update({
        "LEGOPT_LEASE_SECONDS": f"{args.lease_seconds:g}",
        "LEGOPT_HEARTBEAT_SECONDS": f"{args.lease_seconds / 4:g}",
        "LEGOPT_CHECKPOINT_EVERY": "5", "LEGOPT_WORKER_WARMUP": "true",
        "LEGOPT_QUOTA_ACTIVE_JOBS": str(2000 + args.jobs + args.tune_jobs + args.cancel_jobs),
        "LEGOPT_MAX_SWEEP_JOBS": str(args.max_sweep),
    })  # fmt: skip
    st.migrate_and_key()
    stack.callback(st.stop)
    st.start_api(workers=args.api_workers)
    for _ in range(args.workers):
        st.start_worker()
    deadline = time.monotonic() + 900  # a cold numba cache compiles for minutes
    logs = [st.logs / f"worker{i + 1}.log" for i in range(args.workers)]
    while True:
        texts = [p.read_text(errors="replace") if p.exists() else "" for p in logs]
        if all(" ready." in t for t in texts) and answers(f"{st.url}/api/v1/health"):
            return st, db
        procs = [p for p in (st.api, *st.workers) if p is not None]
        if any(p.poll() is not None for p in procs) or time.monotonic() > deadline:
            raise SystemExit(f"stack not ready:\n{st.log_tail()}")
        time.sleep(0.2)  # polling period


def answers(url: str, http: Any = httpx) -> bool:
    try:
        return bool(http.get(url, timeout=30).status_code == 200)
    except httpx.HTTPError:
        return False


def warm_validation(st: Any, n: int, timeout_s: float) -> float:
    """``n`` concurrent ``POST /jobs`` (own connections; a 429 counts too) so that each API process
    starts its validation process; waits for the jobs. The slowest 202, s."""

    def one(_: int) -> tuple[float, str | None]:
        with httpx.Client(headers={"X-API-Key": st.key}, timeout=timeout_s) as c:
            t = time.perf_counter()
            r = c.post(f"{st.url}/api/v1/jobs", json=job_spec({"generations": 2}))
            return time.perf_counter() - t, r.json()["id"] if r.status_code == 202 else None

    with ThreadPoolExecutor(n) as pool:
        answered = [(t, i) for t, i in pool.map(one, range(n)) if i is not None]
    with st.client() as c:
        for _, job_id in answered:
            c.wait(job_id, poll_s=0.2, timeout_s=timeout_s)
    return max((t for t, _ in answered), default=math.nan)


def phases(st: Any, engine: Any, args: argparse.Namespace) -> dict[str, Any]:
    """Warm-up, then the three phases of the module docstring; every measured figure."""
    out: dict[str, Any] = {"machine": machine(engine, st.env["LEGOPT_BROKER_URL"])}
    guard = 600 + 3 * max(args.jobs, args.cancel_jobs) / args.workers
    health = out["health"] = HealthSampler(st.url, args.health_interval)
    health.start()
    headers = {"X-API-Key": st.key}
    with httpx.Client(base_url=f"{st.url}/api/v1", headers=headers, timeout=3600) as http:
        health.phase = "warm-up"
        out["cold_post"] = warm_validation(st, 2 * args.api_workers, guard)
        health.phase = "submit"  # 1. scale
        sw, sent, out["post"] = submit(http, "/sweeps", sweep({"generations": 2}, args.jobs))
        health.phase = "drain"
        wait_drained(http, sw["id"], guard)
        health.phase = "idle"
        out["scale"] = analyse(read_sweep(engine, sw["id"]), sent, args.workers)

        health.phase = "tune"  # 2. Ray Tune's measure
        body = sweep({"wall_time_s": args.job_seconds}, args.tune_jobs)
        tw, tsent, out["tune_post"] = submit(http, "/sweeps", body)
        wait_drained(http, tw["id"], 600 + 3 * args.tune_jobs * (args.job_seconds + 1))
        tune = out["tune"] = analyse(read_sweep(engine, tw["id"]), tsent, args.workers)
        out["tune_ratio"] = [tune["wall"] / (tune["n"] * d / args.workers) for d in (tune["run"],
                             tune["busy"])]  # fmt: skip

        health.phase = "cancel"  # 3. cancel
        cw, _, out["cancel_post"] = submit(
            http, "/sweeps", sweep({"wall_time_s": 30.0}, args.cancel_jobs)
        )
        out["cancel"], _, out["cancel_s"] = submit(http, f"/sweeps/{cw['id']}/cancel")
        t_cancel, broker = time.monotonic(), st.env["LEGOPT_BROKER_URL"]
        out["depth"] = broker_depth(broker)
        probe, _, _ = submit(http, "/jobs", job_spec({"generations": 2}))
        terminal = flushed = None
        while terminal is None or flushed is None or probe.get("started_at") is None:
            if terminal is None:
                c = http.get(f"/sweeps/{cw['id']}", params={"limit": 1}).json()["counts"]
                terminal = None if c["queued"] + c["running"] else time.monotonic() - t_cancel
            if flushed is None and broker_depth(broker) == 0:
                flushed = time.monotonic() - t_cancel
            probe = http.get(f"/jobs/{probe['id']}").json()
            if time.monotonic() - t_cancel > guard:
                raise SystemExit(f"cancelled sweep not settled in {guard:.0f} s")
            time.sleep(0.1)  # polling period
        out["terminal"], out["flushed"] = terminal, flushed
        at = {k: datetime.fromisoformat(probe[k]).timestamp() for k in ("created_at", "started_at")}
        out["probe"] = at["started_at"] - at["created_at"]
        out["final"] = dict(Counter(j["status"] for j in read_sweep(engine, cw["id"]).values()))
    health.halt.set()
    health.join()
    return out


def report(o: dict[str, Any], args: argparse.Namespace, loads: tuple[float, float]) -> None:
    sc, tu, h, lease = o["scale"], o["tune"], o["health"], args.lease_seconds
    print(f"\nMachine: {o['machine']}; load average {loads[0]:.1f} at start, {loads[1]:.1f} at "
          f"end. W = {args.workers} solo workers, {args.api_workers} API processes, lease "
          f"{lease:g} s.\n\n| figure | value | goal |\n|---|---|---|")  # fmt: skip
    rows = [
        ("scale sweep: jobs (mean run time r, ms); statuses",
         f"{sc['n']} ({1e3 * sc['run']:.0f}); {sc['statuses']}", "10 000"),
        ("ONE POST /sweeps, s (cold: a first POST /jobs)",
         f"{o['post']:.1f} ({o['cold_post']:.1f})", "seconds"),
        ("drain (POST sent → last finished), s; jobs/s", f"{sc['wall']:.1f}; {sc['rate']:.2f}", ""),
        (f"overhead per job, first / last {sc['k']}, ms (in-job)",
         f"{1e3 * sc['first']:.0f} / {1e3 * sc['last']:.0f} ({1e3 * sc['in_job']:.0f})", ""),
        ("overhead ratio last / first", f"{sc['ratio']:.2f}", "≤ 1.2"),
        ("messages per job (max; jobs with > 1); claims per job",
         f"{sc['msgs']:.3f} ({sc['msgs_max']}; {sc['dup']}); {sc['claims'] / sc['n']:.3f}",
         "≤ 1.1"),
        ("queue wait p50, s; longest queued while a worker idle, s (leases)",
         f"{sc['wait_p50']:.1f}; {sc['idle_wait']:.1f} ({sc['idle_wait'] / lease:.2f})", "≤ 2"),
        ("/health p50 / p95 / max ms: submission, drain", h.stats("submit", "drain"), "p95 < 100"),
        (f"Ray Tune: {tu['n']} jobs of {args.job_seconds:g} s: d, s; T, s (POST, s)",
         f"{tu['run']:.3f}; {tu['wall']:.1f} ({o['tune_post']:.1f})", ""),
        ("Ray Tune measure T / (N·d/W) (with d = started → finished)",
         "{:.3f} ({:.3f})".format(*o["tune_ratio"]), "≤ 1.05"),
        ("Ray Tune: overhead per job first / last, ms; messages per job",
         f"{1e3 * tu['first']:.0f} / {1e3 * tu['last']:.0f}; {tu['msgs']:.3f}", ""),
        (f"cancel: POST /sweeps of {args.cancel_jobs}, s; ONE POST /cancel, s",
         f"{o['cancel_post']:.1f}; {o['cancel_s']:.2f} ({o['cancel']['cancelled']} cancelled, "
         f"{o['cancel']['stopping']} stopping)", "one request"),
        ("final statuses; all terminal after, s", f"{o['final']}; {o['terminal']:.1f}",
         "all cancelled"),
        ("its queue messages; all delivered after, s", f"{o['depth']}; {o['flushed']:.1f}", ""),
        ("a job submitted after the cancel: submit → start, s", f"{o['probe']:.1f}", ""),
        ("/health p50 / p95 / max ms: Ray Tune, cancel", h.stats("tune", "cancel"), "p95 < 100"),
    ]  # fmt: skip
    for name, value, goal in rows:
        print(f"| {name} | {value} | {goal} |")
    print(
        f"\nSettings as shipped but LEGOPT_MAX_SWEEP_JOBS={args.max_sweep} (default 10 000) "
        "and LEGOPT_QUOTA_ACTIVE_JOBS raised above the three sweeps' jobs."
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--jobs", type=int, default=10_000, help="tiny jobs of the scale sweep")
    ap.add_argument("--workers", type=int, default=2, help="solo worker processes (W)")
    ap.add_argument("--tune-jobs", type=int, default=200, help="jobs of the Ray Tune sweep")
    ap.add_argument("--job-seconds", type=float, default=1.0, help="d of the Ray Tune sweep, s")
    ap.add_argument("--cancel-jobs", type=int, default=None, help="default: --jobs")
    ap.add_argument("--lease-seconds", type=float, default=60.0, help="compose's 60 s")
    ap.add_argument("--health-interval", type=float, default=0.1, help="s between two polls")
    ap.add_argument("--api-workers", type=int, default=2, help="uvicorn processes (compose: 2)")
    args = ap.parse_args()
    args.cancel_jobs = args.jobs if args.cancel_jobs is None else args.cancel_jobs
    args.max_sweep = max(10_000, args.jobs, args.tune_jobs, args.cancel_jobs)
    load0 = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as d, ExitStack() as stack:
        st, db = start(stack, Path(d), args)
        engine = create_engine(db)
        stack.callback(engine.dispose)
        out = phases(st, engine, args)
    report(out, args, (load0, os.getloadavg()[0]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
