"""Latency of the jobs page and the API's job listings at 10^3, 10^4 and 10^5 stored jobs.

One API key owns N jobs (a mix of study kinds, optimizers, statuses and best values, created
over the past days); the app runs in-process (``fastapi.testclient``, no network) on a SQLite
file and, when ``LEGOPT_TEST_POSTGRES_URL`` / 127.0.0.1:5432 answers, on PostgreSQL. For each
N it reports p50 / p95 (ms) over ``--repeat`` requests of:

- ``page 1``: the jobs page's request (``/dashboard/jobs?limit=50``, newest first, with total);
- ``page 1 + options``: what opening the page costs (the filters' choices and page 1);
- ``keyset page 200``: a page deep in the list by ``cursor`` (10^4 jobs in), newest first and
  (``sort best``) by best value;
- ``status filter``, ``kind filter``, ``search``, ``sort by best``: filtered / sorted pages;
  the searches: ``seed=42`` (1 % of the jobs), one job's id (by the primary key), ``nsga2``
  (25 %: more matches than the count's cap) and a word of two letters (no trigram answers it:
  the API refuses it, 422 — the request measured is that answer);
- ``GET /jobs``: the API's plain listing (offset paging);
- ``Python filter``: the obvious alternative — read every job of the key, label, filter, sort
  and page in Python (``repository.list_jobs`` + ``job_labels``) — measured up to 10^4 jobs.

Then, in the store (``dashboard_queries.list_job_rows``, no HTTP), each search by its index
(FTS5 trigram table / pg_trgm GIN, revision 0009; an id by the primary key; two letters: LIKE
either way) against the same search by LIKE scan — the
read before revision 0009; on PostgreSQL the same statements planned with bitmap scans off,
the only way a GIN index is read — interleaved sample by sample, as a ratio; and the two
counts: the jobs page's, capped at ``COUNT_CAP + 1``, and ``GET /jobs``'s exact
``count(*)``.

    python benchmarks/bench_dashboard.py [--sizes 1000,10000,100000] [--repeat 30]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from datetime import timedelta
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sqlalchemy import bindparam, func, literal, select, text, update  # noqa: E402

from services.api.lookups import study_defaults  # noqa: E402
from services.store import api_keys  # noqa: E402
from services.store import dashboard_queries as dq  # noqa: E402
from services.store import repository as repo  # noqa: E402
from services.store.keys import generate_api_key  # noqa: E402
from services.store.states import JobStatus  # noqa: E402
from services.store.tables import JOBS  # noqa: E402

KINDS = ["path_tracking", "swing_energy", "hexapod_workspace", "quadruped_gait", "path_placement"]
OPTIMIZERS = ["nsga2", "ga", "moead", "hka"]
STATUSES = [JobStatus.SUCCEEDED] * 6 + [JobStatus.FAILED, JobStatus.CANCELLED, JobStatus.QUEUED]


def fill(ctx: Any, key_id: str, n: int, start: int) -> None:
    """Add jobs ``start .. n`` to the key: one insert per 5000, created one minute apart."""
    base = repo.now_utc() - timedelta(minutes=n + 10)
    for lo in range(start, n, 5000):
        hi = min(n, lo + 5000)
        specs = [
            {"name": f"job {i}", "problem": {"kind": KINDS[i % 5]},
             "optimizer": {"kind": OPTIMIZERS[i % 4]}, "seed": i % 97}
            for i in range(lo, hi)
        ]  # fmt: skip
        with ctx.write() as s:
            ids = repo.create_jobs(
                s, owner_key_id=key_id, specs=specs, total_generations=[50] * len(specs),
                now=base + timedelta(minutes=lo),
            )  # fmt: skip
            done = [
                {"jid": job_id, "st": STATUSES[i % len(STATUSES)], "g": 50,
                 "best": [(i * 7919) % 1000 / 10], "bv": (i * 7919) % 1000 / 10,
                 "at": base + timedelta(minutes=i),
                 "fin": base + timedelta(minutes=i + 1)}
                for i, job_id in zip(range(lo, hi), ids, strict=True)
                if STATUSES[i % len(STATUSES)] is not JobStatus.QUEUED
            ]  # fmt: skip
            stmt = (
                update(JOBS)
                .where(JOBS.c.id == bindparam("jid"))
                .values(status=bindparam("st"), progress_generation=bindparam("g"),
                        best_objective=bindparam("best", type_=JOBS.c.best_objective.type),
                        best_value=bindparam("bv"),
                        created_at=bindparam("at", type_=JOBS.c.created_at.type),
                        finished_at=bindparam("fin", type_=JOBS.c.finished_at.type))
            )  # fmt: skip
            s.connection().execute(stmt, done)


def python_filter(ctx: Any, key_id: str, kind: str) -> list[Any]:
    """The obvious alternative: every job of the key, labelled and filtered in Python."""
    with ctx.read() as s:
        jobs: list[Any] = []
        offset = 0
        while True:
            page = repo.list_jobs(s, owner_key_id=key_id, limit=1000, offset=offset)
            jobs.extend(page.items)
            offset += 1000
            if offset >= page.total:
                break
        labels = repo.job_labels(s, jobs)
    chosen = [j for j in jobs if labels[j.id]["problem"]["kind"] == kind]
    chosen.sort(key=lambda j: j.created_at, reverse=True)
    return chosen[:50]


def deep_cursor(get: Callable[[str], Any], page: str, depth: int) -> str | None:
    """The cursor of page ``depth + 1`` of ``page``, walked page by page."""
    cursor = None
    for _ in range(depth):
        cursor = get(page + (f"&cursor={cursor}" if cursor else ""))["next_cursor"]
    return cursor


#: The store-level searches: name -> words (``{job}``: the id of a job of the key).
SEARCHES = {
    "seed=42 (1 %)": "seed=42",
    "a job's id": "{job}",
    "nsga2 (25 %)": "nsga2",
    "2 letters (LIKE)": "zq",
}


def paired(a: Callable[[], Any], b: Callable[[], Any], repeat: int) -> tuple[float, float, float]:
    """Median ms of ``a`` and of ``b``, sampled alternately, and the median of a/b."""
    a(), b()  # warm
    ta, tb, ratio = [], [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        a()
        t1 = time.perf_counter()
        b()
        t2 = time.perf_counter()
        ta.append((t1 - t0) * 1000)
        tb.append((t2 - t1) * 1000)
        ratio.append((t1 - t0) / (t2 - t1))
    return statistics.median(ta), statistics.median(tb), statistics.median(ratio)


def store_reads(
    ctx: Any, key_id: str, n: int, job_id: str, repeat: int
) -> list[tuple[str, int, str]]:
    """The searches by index against the LIKE scan, and the two counts, in the store."""
    from services.store.session import make_engine, make_session_factory, session_scope
    from services.store.tables import JOBS

    engine = ctx.session_factory.kw["bind"]
    rows: list[tuple[str, int, str]] = []
    # The reference on PostgreSQL: the same statements, planned without bitmap scans (the only
    # way a GIN index is read), on connections of their own that prepare nothing (a prepared
    # statement keeps the plan it was prepared with, whatever the settings say later).
    reference = ctx.session_factory
    if engine.dialect.name == "postgresql":
        options = {"prepare_threshold": None, "options": "-c enable_bitmapscan=off"}
        reference = make_session_factory(make_engine(engine.url, connect_args=options))

    def search(words: str, index: bool) -> Callable[[], Any]:
        def run() -> Any:
            with session_scope(ctx.session_factory if index else reference) as s:
                f = dq.JobFilter(search=words)
                return dq.list_job_rows(s, key_id, f, search_index=index)

        return run

    for name, words in SEARCHES.items():
        words = words.format(job=job_id)
        total = search(words, True)().total
        assert total == search(words, False)().total, name
        ms_index, ms_like, ratio = paired(search(words, True), search(words, False), repeat)
        cell = f"{ms_index:.1f} / {ms_like:.1f} ({ratio:.2f}×)"
        rows.append((f"search {name}: index / LIKE scan (ms)", n, cell))
        print(f"  search {name:18s} {n:>7} index {ms_index:7.1f} ms  LIKE {ms_like:7.1f} ms"
              f"  ratio {ratio:.2f}  total {total}", file=sys.stderr)  # fmt: skip

    def count(capped: bool) -> Callable[[], Any]:
        matches = select(literal(1)).select_from(JOBS).where(JOBS.c.owner_key_id == key_id)
        if capped:
            matches = matches.limit(dq.COUNT_CAP + 1)
        stmt = select(func.count()).select_from(matches.subquery())

        def run() -> Any:
            with ctx.read() as s:
                return s.execute(stmt).scalar_one()

        return run

    ms_capped, ms_exact, _ = paired(count(True), count(False), repeat)
    rows.append((f"count: page's (≤ {dq.COUNT_CAP + 1:,}) / GET /jobs's exact (ms)", n,
                 f"{ms_capped:.2f} / {ms_exact:.2f}"))  # fmt: skip
    print(f"  counts {n:>7} capped {ms_capped:.2f} ms  exact {ms_exact:.2f} ms", file=sys.stderr)
    if reference is not ctx.session_factory:
        reference.kw["bind"].dispose()
    return rows


def timed(fn: Callable[[], Any], repeat: int) -> tuple[float, float]:
    fn()  # warm
    samples = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        samples.append((time.perf_counter() - t0) * 1000)
    samples.sort()
    return statistics.median(samples), samples[min(len(samples) - 1, int(0.95 * len(samples)))]


def bench(
    url: str, sizes: list[int], repeat: int, data_dir: Path
) -> tuple[list[tuple[str, int, str, str]], list[tuple[str, int, str]]]:
    from fastapi.testclient import TestClient

    from services.api.app import create_app
    from services.store import migrate
    from services.store.settings import Settings

    migrate.upgrade(url)
    settings = Settings.from_env(env={"LEGOPT_DATABASE_URL": url}, data_dir=data_dir)
    settings = settings.with_overrides(rate_limit_per_s=1e9, rate_limit_burst=10**9)
    app = create_app(settings, enqueue=lambda _j: None)
    ctx = app.state.context
    raw, key_hash = generate_api_key()
    with ctx.write() as s:
        key_id = api_keys.create_api_key(s, name="bench", key_hash=key_hash).id
    h = {"X-API-Key": raw}
    rows: list[tuple[str, int, str, str]] = []
    store_rows: list[tuple[str, int, str]] = []
    have = 0
    with TestClient(app) as c:

        def get(path: str) -> Any:
            r = c.get(path, headers=h)
            assert r.status_code == (422 if path.endswith("&q=zq") else 200), r.text
            return r.json()

        for n in sizes:
            t0 = time.perf_counter()
            fill(ctx, key_id, n, have)
            have = n
            t1 = time.perf_counter()
            with ctx.write() as s:
                dq.sync_labels(s, key_id, study_defaults, full=True)
            if url.startswith("postgresql"):  # what autovacuum does after a load like this
                engine = ctx.session_factory.kw["bind"]
                with engine.connect().execution_options(isolation_level="AUTOCOMMIT") as conn:
                    conn.execute(text("VACUUM ANALYZE"))
            t2 = time.perf_counter()
            print(f"  {n} jobs: insert {t1 - t0:.1f} s, labels {t2 - t1:.1f} s", file=sys.stderr)
            deep = get(
                f"/api/v1/dashboard/jobs?limit=50&offset={min(n - 50, 10_000)}&sort=finished"
            )
            page = "/api/v1/dashboard/jobs?limit=50"
            cursor_job = get(f"{page}&offset={n // 2}")["items"][0]["id"]  # one in the middle
            cursor = deep_cursor(get, page, min(200, n // 50 - 1))
            best_cursor = deep_cursor(get, f"{page}&sort=best&order=asc", min(200, n // 50 - 1))
            paths = {
                "page 1": [page],
                "page 1 + options": ["/api/v1/dashboard/options", page],
                "keyset page 200": [f"{page}&cursor={cursor}"],
                "keyset page 200 (sort best)": [f"{page}&sort=best&order=asc&cursor={best_cursor}"],
                "offset page (sort finished)": [f"{page}&offset={deep['offset']}&sort=finished"],
                "status filter": [f"{page}&status=failed"],
                "kind filter": [f"{page}&kind=quadruped_gait"],
                "search": [f"{page}&q=seed=42"],
                "search a job's id": [f"{page}&q={cursor_job}"],
                "search nsga2 (25 %)": [f"{page}&q=nsga2"],
                "search 2 letters (refused: 422)": [f"{page}&q=zq"],
                "sort by best": [f"{page}&sort=best&order=asc"],
                "GET /jobs (API list)": ["/api/v1/jobs?limit=50"],
            }
            cases: list[tuple[str, Callable[[], Any]]] = [
                (name, lambda urls=urls: [get(u) for u in urls]) for name, urls in paths.items()
            ]
            if n <= 10_000:
                cases.append(
                    ("Python filter (alternative)",
                     lambda: python_filter(ctx, key_id, "quadruped_gait"))
                )  # fmt: skip
            for name, fn in cases:
                p50, p95 = timed(fn, repeat if "Python" not in name else max(3, repeat // 10))
                rows.append((name, n, f"{p50:.1f}", f"{p95:.1f}"))
                print(f"  {name:32s} {n:>7} p50 {p50:8.1f} ms  p95 {p95:8.1f} ms", file=sys.stderr)
            store_rows += store_reads(ctx, key_id, n, cursor_job, repeat)
    ctx.close()
    return rows, store_rows


def markdown(backend: str, rows: list[tuple[str, int, str, str]], sizes: list[int]) -> str:
    names = list(dict.fromkeys(r[0] for r in rows))
    p50 = {(r[0], r[1]): float(r[2]) for r in rows}
    cell = {(r[0], r[1]): f"{r[2]} / {r[3]}" for r in rows}
    head = ["request (p50 / p95 ms)", *[f"{n:,} jobs" for n in sizes]]
    if len(sizes) > 1:  # the growth: p50 at the largest size over p50 at the smallest
        head.append(f"{sizes[-1]:,} / {sizes[0]:,}")
        for name in names:
            a, b = p50.get((name, sizes[0])), p50.get((name, sizes[-1]))
            cell[(name, -1)] = f"{b / a:.2f}×" if a and b else "—"
        sizes = [*sizes, -1]
    out = [f"**{backend}**", "", "| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    for name in names:
        out.append("| " + " | ".join([name, *[cell.get((name, n), "—") for n in sizes]]) + " |")
    return "\n".join(out)


def store_markdown(backend: str, rows: list[tuple[str, int, str]], sizes: list[int]) -> str:
    names = list(dict.fromkeys(r[0] for r in rows))
    cell = {(r[0], r[1]): r[2] for r in rows}
    head = [f"{backend}: in the store, median ms", *[f"{n:,} jobs" for n in sizes]]
    out = ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    for name in names:
        out.append("| " + " | ".join([name, *[cell.get((name, n), "—") for n in sizes]]) + " |")
    return "\n".join(out)


def machine() -> str:
    """The machine line: cores, load, SQLite and PostgreSQL versions."""
    import sqlite3

    return (f"machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f} "
            f"(1 min), SQLite {sqlite3.sqlite_version}")  # fmt: skip


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1000,10000,100000")
    ap.add_argument("--repeat", type=int, default=30)
    ap.add_argument("--backends", default="sqlite,postgres", help="sqlite and/or postgres")
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    print(machine())
    backends = args.backends.split(",")
    with tempfile.TemporaryDirectory(prefix="legopt-bench-dash-") as tmp:
        if "sqlite" in backends:
            rows, store = bench(f"sqlite:///{tmp}/legopt.db", sizes, args.repeat, Path(tmp))
            print(markdown("SQLite", rows, sizes))
            print()
            print(store_markdown("SQLite", store, sizes))
        if "postgres" in backends:
            sys.path.insert(0, str(ROOT))
            from tests.integration.stack import postgres_available, postgres_database

            if postgres_available():
                with postgres_database() as url:
                    rows, store = bench(url, sizes, args.repeat, Path(tmp))
                print()
                print(markdown("PostgreSQL", rows, sizes))
                print()
                print(store_markdown("PostgreSQL", store, sizes))
        print(f"\nafter: load {os.getloadavg()[0]:.2f} (1 min)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
