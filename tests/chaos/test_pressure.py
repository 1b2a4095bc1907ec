"""Pressure, not a fault: a long-running transaction held open for a whole sweep, as a reporting
query would hold one (issue 22). On PostgreSQL an open REPEATABLE READ snapshot keeps every row
version it might see, so no job row updated meanwhile can be vacuumed; on SQLite (WAL) an open
read transaction keeps the write-ahead log from being checkpointed past it. Neither may stop the
queue: every job of the sweep must end exactly once with the usual invariants (no job queued
longer than 2 leases with an idle slot, the message bound), and the growth is reported — dead
tuples of ``jobs``/``job_events``/``generations`` on PostgreSQL, the WAL file's size on SQLite —
in the scenario's metrics (a number to watch, not a bound: it depends on the sweep's size).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from sqlalchemy import text
from sqlalchemy.engine import Connection

from tests.chaos.scenario import Scenario
from tests.chaos.workload import job_spec, submit_sweep

pytestmark = [pytest.mark.integration, pytest.mark.chaos]

SEEDS = [800 + i for i in range(8)]
GENERATIONS = 20
JOB_S = 4.0  # generous per-job time on a loaded 2-core machine (as the other scenarios)
TABLES = ("jobs", "job_events", "generations")


def _dead_tuples(conn: Connection) -> dict[str, int]:
    """Dead row versions per table (PostgreSQL; the statistics flushed first)."""
    conn.execute(text("SELECT pg_stat_force_next_flush()"))
    rows = conn.execute(
        text("SELECT relname, n_dead_tup FROM pg_stat_user_tables WHERE relname = ANY(:t)"),
        {"t": list(TABLES)},
    )
    return {str(name): int(n) for name, n in rows}


def _wal_bytes(url: str) -> int:
    wal = Path(url.removeprefix("sqlite:///") + "-wal")
    return wal.stat().st_size if wal.exists() else 0


def test_a_transaction_held_open_for_a_whole_sweep(scenario: Scenario) -> None:
    sc = scenario
    postgres = sc.stack.kind == "services"
    url = sc.stack.env["LEGOPT_DATABASE_URL"]
    sc.start_workers(1, 1)
    sc.mark("workers_ready")
    reporter = sc.view.engine.connect()
    before: dict[str, Any] = {}
    try:
        if postgres:
            before = _dead_tuples(reporter)
            reporter.commit()
            reporter.execute(text("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ"))
        else:
            before = {"wal_bytes": _wal_bytes(url)}
        # the report: one snapshot, read once and then held open while the sweep runs
        held = reporter.execute(text("SELECT count(*) FROM jobs")).scalar_one()
        doc = {"base": job_spec(generations=GENERATIONS), "seeds": SEEDS}
        _, ids = submit_sweep(sc.stack.url, sc.stack.key, doc)
        sc.add(ids)
        sc.metrics["drain_s"] = round(sc.wait_terminal(sc.bound(len(ids), JOB_S, 2)), 2)
        # still the same snapshot: the transaction really was open all along
        assert reporter.execute(text("SELECT count(*) FROM jobs")).scalar_one() == held
        if postgres:
            with sc.view.engine.connect() as other:
                after: dict[str, Any] = _dead_tuples(other)
        else:
            after = {"wal_bytes": _wal_bytes(url)}
    finally:
        reporter.rollback()
        reporter.close()
    sc.metrics["held_transaction"] = "REPEATABLE READ snapshot" if postgres else "WAL reader"
    sc.metrics["growth"] = {k: after.get(k, 0) - int(before.get(k, 0)) for k in after}
    sc.metrics["after"] = after
    sc.verify()
