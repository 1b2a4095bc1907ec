"""The jobs of the search tests (``test_store_search_index``, ``test_store_search_plumbing``):
varied names (LIKE's wildcards, quotes, case, non-ASCII), tags, kinds, optimizers, seeds,
statuses and best values, their labels written."""

from __future__ import annotations

from datetime import datetime, timedelta
from typing import Any

from sqlalchemy import bindparam, text, update
from sqlalchemy.orm import Session

from services.api.lookups import study_defaults
from services.store import dashboard_queries as dq
from services.store import repository as repo
from services.store.states import JobStatus
from services.store.tables import JOBS

NAMES = [
    "Calderon leg 100%_done", 'quote "this"', "back\\slash", "Ünïcode Straße", "wide sweep",
    "ab", "a_b", "a%b", "it's a 'test'", None,
]  # fmt: skip
TAGS = [["demo"], ["energy-time", "demo"], [], ["ci"]]
KINDS = ["path_tracking", "swing_energy", "quadruped_gait"]
N = 40


def _fill(session: Session, key_id: str, n: int = N, start: int = 0) -> list[str]:
    """``n`` jobs with varied names, tags, kinds, optimizers, seeds, statuses and best values;
    their labels written."""
    base = datetime(2026, 1, 1, tzinfo=repo.now_utc().tzinfo)
    ids = []
    for i in range(start, start + n):
        spec: dict[str, Any] = {
            "problem": {"kind": KINDS[i % 3]}, "optimizer": {"kind": ["ga", "nsga2"][i % 2]},
            "seed": i % 17, "tags": TAGS[i % 4],
        }  # fmt: skip
        if NAMES[i % len(NAMES)] is not None:
            spec["name"] = NAMES[i % len(NAMES)]
        ids += repo.create_jobs(
            session, owner_key_id=key_id, specs=[spec], total_generations=[10],
            now=base + timedelta(minutes=i // 2),
        )  # fmt: skip
    rows = [
        {"jid": j, "st": [JobStatus.SUCCEEDED, JobStatus.FAILED, JobStatus.QUEUED][i % 3],
         "bv": None if i % 4 == 0 else float((i * 7) % 5)}
        for i, j in enumerate(ids)
    ]  # fmt: skip
    stmt = (
        update(JOBS)
        .where(JOBS.c.id == bindparam("jid"))
        .values(status=bindparam("st"), best_value=bindparam("bv"))
    )
    session.connection().execute(stmt, rows)
    dq.sync_labels(session, key_id, study_defaults)
    return ids


def _fill_sweep(session: Session, key_id: str, n: int = 5) -> tuple[str, list[str]]:
    """A sweep of ``n`` jobs of the key (seeds 0..n-1); its id and its jobs' ids, labels
    written."""
    base = {"problem": {"kind": KINDS[0]}, "optimizer": {"kind": "nsga2"}, "tags": ["demo"]}
    sweep = repo.create_sweep(session, owner_key_id=key_id, base_spec=base, axes={})
    ids = repo.create_jobs(
        session, owner_key_id=key_id, overrides=[{"seed": i} for i in range(n)],
        total_generations=[10] * n, sweep_id=sweep.id,
    )  # fmt: skip
    dq.sync_labels(session, key_id, study_defaults)
    return sweep.id, ids


def _texts(session: Session, key_id: str) -> dict[str, str]:
    rows = session.execute(
        text("SELECT job_id, search FROM job_labels WHERE owner_key_id = :k"), {"k": key_id}
    )
    return {r[0]: r[1] for r in rows}


def _ids(page: dq.JobRowPage) -> list[str]:
    return [r.job.id for r in page.items]
