"""Service benchmarks with real processes (API + Celery workers), on the embedded stack and, when
PostgreSQL and redis-server are available, on PostgreSQL + Redis.

1. submit→start latency (p50, p95) of trivial jobs (one generation, no recording), submitted
   one at a time into an idle stack: ``started_at − created_at`` of each job;
2. a 64-job sweep on 1 vs 2 worker processes: wall time from submit to the last job done, and
   the speed-up (goal ≥ 1.7× on 2 cores);
3. GET latency of a job with a 300-point Pareto front (``GET /jobs/{id}`` and
   ``GET /jobs/{id}/pareto?limit=300``) under 100 concurrent clients.

    python benchmarks/bench_service.py [--stacks embedded services] [--sweep-jobs 64]
"""

from __future__ import annotations

import argparse
import asyncio
import sys
import tempfile
import time
from datetime import datetime
from pathlib import Path
from typing import Any

import httpx

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.integration.stack import (  # noqa: E402
    RedisServer,
    Stack,
    postgres_database,
    services_available,
)

TRIVIAL = {
    "problem": {"kind": "swing_energy"},
    "optimizer": {"kind": "ga", "params": {"pop_size": 10}},
    "budget": {"generations": 1},
    "record": False,
}
SWEEP_JOB = {
    "problem": {"kind": "swing_energy"},
    "budget": {"generations": 150},
    "record": False,
}
FRONT_300 = {"problem": {"kind": "hexapod_workspace"}, "budget": {"generations": 30}, "seed": 1}


def pct(values: list[float], q: float) -> float:
    values = sorted(values)
    k = (len(values) - 1) * q
    lo, hi = int(k), min(int(k) + 1, len(values) - 1)
    return values[lo] + (values[hi] - values[lo]) * (k - lo)


def _ts(s: str) -> float:
    return datetime.fromisoformat(s).timestamp()


def bench_latency(st: Stack, n: int) -> dict[str, float]:
    lat = []
    with st.client() as c:
        for _ in range(n):
            job = c.submit(TRIVIAL)
            done = c.wait(job["id"], poll_s=0.05, timeout_s=120)
            assert done["status"] == "succeeded", done
            lat.append(_ts(done["started_at"]) - _ts(done["created_at"]))
    return {"p50_ms": 1e3 * pct(lat, 0.5), "p95_ms": 1e3 * pct(lat, 0.95), "n": n}


def bench_sweep(st: Stack, n_jobs: int) -> float:
    with st.client() as c:
        t0 = time.perf_counter()
        sw = c.sweep({"base": SWEEP_JOB, "grid": {"seed": list(range(1, n_jobs + 1))}})
        for job_id in sw["job_ids"]:
            done = c.wait(job_id, poll_s=0.2, timeout_s=1800)
            assert done["status"] == "succeeded", done
        return time.perf_counter() - t0


async def _hammer(
    url: str, key: str, paths: list[str], clients: int, per_client: int
) -> list[float]:
    lat: list[float] = []
    retries: list[int] = []
    limits = httpx.Limits(max_connections=clients)
    async with httpx.AsyncClient(headers={"X-API-Key": key}, limits=limits, timeout=60) as http:

        async def one_client() -> None:
            for i in range(per_client):
                t0 = time.perf_counter()
                for attempt in range(3):  # a pooled keep-alive connection the server just closed
                    try:
                        r = await http.get(url + paths[i % len(paths)])
                        break
                    except (httpx.ReadError, httpx.RemoteProtocolError):
                        retries.append(1)
                        if attempt == 2:
                            raise
                r.raise_for_status()
                lat.append(time.perf_counter() - t0)

        await asyncio.gather(*(one_client() for _ in range(clients)))
    if retries:
        print(f"({len(retries)} requests retried after the server closed a keep-alive connection)")
    return lat


def bench_get(st: Stack, clients: int, per_client: int) -> dict[str, Any]:
    with st.client() as c:
        job = c.submit(FRONT_300)
        c.wait(job["id"], poll_s=0.2, timeout_s=600)
        n_front = c.pareto(job["id"])["total"]
    paths = [f"/api/v1/jobs/{job['id']}", f"/api/v1/jobs/{job['id']}/pareto?limit=300"]
    t0 = time.perf_counter()
    lat = asyncio.run(_hammer(st.url, st.key, paths, clients, per_client))
    wall = time.perf_counter() - t0
    return {
        "front": n_front,
        "requests": len(lat),
        "p50_ms": 1e3 * pct(lat, 0.5),
        "p95_ms": 1e3 * pct(lat, 0.95),
        "rps": len(lat) / wall,
    }


def run_stack(kind: str, args: argparse.Namespace) -> dict[str, Any]:
    out: dict[str, Any] = {"stack": kind}
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)

        def make(workers: int, sub: str, db: str, broker: str) -> Stack:
            st = Stack(kind, tmp / sub, db, broker)
            (tmp / sub / "data").mkdir(parents=True, exist_ok=True)
            st.env["LEGOPT_CHECKPOINT_EVERY"] = "5"
            st.env["LEGOPT_LEASE_SECONDS"] = "30"
            st.env["LEGOPT_HEARTBEAT_SECONDS"] = "5"
            st.migrate_and_key()
            st.start_api(workers=args.api_workers)
            for _ in range(workers):
                st.start_worker()
            time.sleep(3.0)  # workers import legcore and connect
            return st

        def db_broker(sub: str) -> tuple[str, str, Any]:
            if kind == "embedded":
                return f"sqlite:///{tmp / sub / 'data' / 'legopt.db'}", "filesystem://", None
            redis = RedisServer(tmp)
            redis.start()
            cm = postgres_database()
            url = cm.__enter__()
            return url, redis.url, (redis, cm)

        for workers in (1, 2):
            sub = f"w{workers}"
            db, broker, res = db_broker(sub)
            st = make(workers, sub, db, broker)
            try:
                if workers == 2:
                    out["latency"] = bench_latency(st, args.latency_jobs)
                    out["get"] = bench_get(st, args.clients, args.per_client)
                out[f"sweep_{workers}w_s"] = bench_sweep(st, args.sweep_jobs)
            finally:
                st.stop()
                if res is not None:
                    res[0].stop()
                    res[1].__exit__(None, None, None)
    out["speedup"] = out["sweep_1w_s"] / out["sweep_2w_s"]
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--stacks", nargs="+", default=["embedded", "services"])
    ap.add_argument("--latency-jobs", type=int, default=30)
    ap.add_argument("--sweep-jobs", type=int, default=64)
    ap.add_argument("--clients", type=int, default=100)
    ap.add_argument("--per-client", type=int, default=10)
    ap.add_argument("--api-workers", type=int, default=2, help="uvicorn processes (compose: 2)")
    args = ap.parse_args()
    rows = []
    for kind in args.stacks:
        if kind == "services" and not services_available():
            print("services stack skipped: PostgreSQL or redis-server not available")
            continue
        rows.append(run_stack(kind, args))
    print()
    print(
        f"{'stack':<10} {'submit→start p50/p95 ms':>26} {'sweep 1w s':>11} {'sweep 2w s':>11} "
        f"{'speed-up':>9} {'GET p50/p95 ms':>16} {'req/s':>7}"
    )
    for r in rows:
        lat, get = r["latency"], r["get"]
        print(
            f"{r['stack']:<10} {lat['p50_ms']:>12.0f} / {lat['p95_ms']:<11.0f} "
            f"{r['sweep_1w_s']:>11.1f} {r['sweep_2w_s']:>11.1f} {r['speedup']:>8.2f}x "
            f"{get['p50_ms']:>7.0f} / {get['p95_ms']:<6.0f} {get['rps']:>7.0f}"
        )
    for r in rows:
        g = r["get"]
        print(
            f"{r['stack']}: GET under {args.clients} clients: {g['requests']} requests on a job "
            f"with a {g['front']}-point front"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
