"""Read-only view of the service database for the chaos suite, and a poller of job states.

Tables are *reflected* (``jobs``, ``artifacts`` and, once the service has it, ``job_events``),
not imported from ``services.store.tables``: the checker must read what the running service
wrote, whatever version of the schema it has, and say so clearly when a table is missing.

``Monitor`` polls the ``jobs`` table every 0.1 s from a thread and records every change of a
job's (status, attempt, lease owner): the state timeline used while ``job_events`` does not
exist, and the record of which process claimed what (lease owners are ``host:pid:…``). It
polls the database, not the API, because the API is one of the things the suite kills.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from sqlalchemy import Engine, MetaData, Table, inspect, select

from services.store.session import make_engine

TERMINAL = frozenset({"succeeded", "failed", "cancelled"})
EVENTS_TABLE = "job_events"


def as_utc(value: Any) -> Any:
    """A datetime from either backend as an aware UTC datetime (SQLite's are naive UTC)."""
    if isinstance(value, datetime):
        return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)
    return value


def _status(value: Any) -> str:
    return str(getattr(value, "value", value))


class DbView:
    """Reflected tables of one service database (``url``: the stack's database URL)."""

    def __init__(self, url: str) -> None:
        self.engine: Engine = make_engine(url)
        self.md = MetaData()
        names = set(inspect(self.engine).get_table_names())
        self.jobs = Table("jobs", self.md, autoload_with=self.engine)
        self.artifacts = Table("artifacts", self.md, autoload_with=self.engine)
        self.sweeps = Table("sweeps", self.md, autoload_with=self.engine)
        self.events: Table | None = None
        if EVENTS_TABLE in names:
            self.events = Table(EVENTS_TABLE, self.md, autoload_with=self.engine)

    @property
    def missing_events_reason(self) -> str | None:
        if self.events is not None:
            return None
        return f"table {EVENTS_TABLE!r} does not exist in this schema yet (issue 8 adds it)"

    def close(self) -> None:
        self.engine.dispose()

    def _rows(self, table: Table, where: Any = None, order: Any = None) -> list[dict[str, Any]]:
        stmt = select(table)
        if where is not None:
            stmt = stmt.where(where)
        if order is not None:
            stmt = stmt.order_by(*order)
        with self.engine.connect() as conn:
            return [{k: as_utc(v) for k, v in row._mapping.items()} for row in conn.execute(stmt)]

    def job_rows(self, ids: Iterable[str]) -> list[dict[str, Any]]:
        rows = self._rows(self.jobs, self.jobs.c.id.in_(list(ids)))
        for r in rows:
            r["status"] = _status(r["status"])
        return sorted(rows, key=lambda r: r["created_at"])

    def jobs_created_since(self, since: datetime) -> list[dict[str, Any]]:
        rows = self._rows(self.jobs, self.jobs.c.created_at >= since)
        for r in rows:
            r["status"] = _status(r["status"])
        return rows

    def event_rows(self, ids: Iterable[str]) -> list[dict[str, Any]]:
        if self.events is None:
            return []
        ev = self.events
        rows = self._rows(ev, ev.c.job_id.in_(list(ids)), order=(ev.c.at, ev.c.id))
        for r in rows:
            r["kind"] = _status(r["kind"])
        return rows

    def artifact_rows(self, ids: Iterable[str]) -> list[dict[str, Any]]:
        return self._rows(self.artifacts, self.artifacts.c.job_id.in_(list(ids)))

    def sweep_ids_since(self, since: datetime) -> list[str]:
        rows = self._rows(self.sweeps, self.sweeps.c.created_at >= since)
        return [str(r["id"]) for r in rows]


@dataclass(frozen=True)
class Observation:
    """A job seen in a new state by the monitor."""

    at: datetime
    job_id: str
    status: str
    attempt: int
    owner: str | None
    generation: int


class Monitor(threading.Thread):
    """Polls the jobs created since ``since``; records each change (see the module docstring).
    ``on_tick`` runs about once a second (the harness refreshes its process tree there)."""

    def __init__(
        self,
        view: DbView,
        since: datetime,
        period_s: float = 0.1,
        on_tick: Callable[[], None] | None = None,
    ) -> None:
        super().__init__(name="chaos-monitor", daemon=True)
        self.view, self.since, self.period_s, self.on_tick = view, since, period_s, on_tick
        self.observations: list[Observation] = []
        self.last: dict[str, Observation] = {}
        self.errors = 0
        self._halt = threading.Event()
        self._lock = threading.Lock()

    def run(self) -> None:
        last_tick = 0.0
        while not self._halt.is_set():
            try:
                self.poll()
            except Exception:  # the database may be briefly busy; keep polling
                self.errors += 1
            if self.on_tick is not None and time.monotonic() - last_tick > 1.0:
                last_tick = time.monotonic()
                try:
                    self.on_tick()
                except Exception:
                    self.errors += 1
            self._halt.wait(self.period_s)

    def poll(self) -> None:
        t = datetime.now(UTC)
        jobs = self.view.jobs
        cols = [jobs.c.id, jobs.c.status, jobs.c.attempt_count, jobs.c.lease_owner]
        cols += [jobs.c.progress_generation]
        with self.view.engine.connect() as conn:
            rows = conn.execute(select(*cols).where(jobs.c.created_at >= self.since)).all()
        with self._lock:
            for jid, status, attempt, owner, gen in rows:
                obs = Observation(t, str(jid), _status(status), int(attempt), owner, int(gen))
                prev = self.last.get(obs.job_id)
                if prev is None or (prev.status, prev.attempt, prev.owner) != (
                    obs.status,
                    obs.attempt,
                    obs.owner,
                ):
                    self.observations.append(obs)
                self.last[obs.job_id] = obs

    def stop(self) -> None:
        self._halt.set()
        self.join(10)
        self.poll()  # a last look

    def state(self, job_id: str) -> Observation | None:
        with self._lock:
            return self.last.get(job_id)

    def snapshot(self) -> list[Observation]:
        with self._lock:
            return list(self.observations)

    def owners(self, job_ids: Iterable[str] | None = None) -> set[str]:
        """Every lease owner seen on a running job (of ``job_ids``, default all)."""
        wanted = None if job_ids is None else set(job_ids)
        return {
            o.owner
            for o in self.snapshot()
            if o.owner and o.status == "running" and (wanted is None or o.job_id in wanted)
        }


def owner_pid(owner: str | None) -> int | None:
    """The pid in a lease owner / worker id ``host:pid:random`` (None if not of that form)."""
    if not owner:
        return None
    parts = owner.split(":")
    return int(parts[1]) if len(parts) >= 2 and parts[1].isdigit() else None
