"""Execute one job: claim it, run it generation by generation, store the outcome.

The only function the Celery task calls is :func:`execute_job`. It never raises for a problem
with the job itself: a spec that cannot run, a study that fails, an internal error — all end as
``failed`` with a message a user can act on; a lost lease ends quietly (another worker owns the
job now). Between generations it honours cancellation, heartbeats (a background thread renews
the lease), records progress and saves a checkpoint every ``checkpoint_every`` generations, so
a redelivered or reaped job resumes from its last checkpoint instead of generation 0.
"""

from __future__ import annotations

import json
import logging
import os
import socket
import tempfile
import threading
import time
import traceback
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from legcore.jobspec import spec_error_locations
from legcore.optimizers import from_jsonable, to_jsonable
from legcore.runner import RunResult, finalize, prepare
from services.store.artifacts import ArtifactStore
from services.store.errors import LeaseLostError
from services.store.lifecycle import (
    claim_job,
    fail_job,
    finish_job,
    heartbeat,
    is_cancel_requested,
    latest_checkpoint,
    mark_cancelled,
    record_generation,
    save_checkpoint,
)
from services.store.records import ArtifactIn, BaselineIn, JobRecord, ParetoPointIn, ResultIn
from services.store.session import session_scope
from services.store.settings import Settings, get_settings

log = logging.getLogger("legopt.worker")

#: At most this long (s) between two writes of progress rows (a checkpoint also writes them).
PROGRESS_FLUSH_S = 0.5

_WORKER_ID = f"{socket.gethostname()}:{os.getpid()}:{uuid.uuid4().hex[:8]}"


def worker_id() -> str:
    """This process's identity as a lease owner (host:pid:random)."""
    global _WORKER_ID
    if not _WORKER_ID.split(":")[1] == str(os.getpid()):  # forked child: new identity
        _WORKER_ID = f"{socket.gethostname()}:{os.getpid()}:{uuid.uuid4().hex[:8]}"
    return _WORKER_ID


def format_user_error(exc: BaseException, spec: Any = None) -> str:
    """A message naming the field and the reason, from a validation or value error."""
    if isinstance(exc, ValidationError):
        parts = []
        for loc, msg in spec_error_locations(exc, spec)[:10]:
            where = ".".join(str(p) for p in loc)
            parts.append(f"{where}: {msg}" if where else msg)
        return "invalid job spec: " + "; ".join(parts)
    return f"invalid job spec: {exc}"


class _Heartbeat(threading.Thread):
    """Renews the lease every ``period`` seconds; sets ``lost`` if the lease was taken away."""

    def __init__(self, job_id: str, wid: str, settings: Settings) -> None:
        super().__init__(name=f"heartbeat-{job_id[:8]}", daemon=True)
        self.job_id, self.wid, self.settings = job_id, wid, settings
        self.stop_event = threading.Event()
        self.lost = threading.Event()

    def run(self) -> None:
        while not self.stop_event.wait(self.settings.heartbeat_seconds):
            try:
                with session_scope() as s:
                    ok = heartbeat(s, self.job_id, self.wid, self.settings.lease_seconds)
            except Exception:  # a transient database error: try again next period
                log.exception("heartbeat of job %s failed", self.job_id)
                continue
            if not ok:
                self.lost.set()
                return


@dataclass(frozen=True)
class Outcome:
    """What happened to one delivery of a job (for logs and tests)."""

    job_id: str
    status: str  # not-claimed | succeeded | failed | cancelled | lease-lost
    resumed_from: int | None = None
    message: str = ""


def execute_job(job_id: str, settings: Settings | None = None, wid: str | None = None) -> Outcome:
    """Run job ``job_id`` to its end if this worker can claim it (see the module docstring)."""
    settings = settings or get_settings()
    wid = wid or worker_id()
    with session_scope(immediate=True) as s:
        job = claim_job(s, job_id, wid, settings.lease_seconds, max_attempts=settings.max_attempts)
    if job is None:
        return Outcome(job_id, "not-claimed")
    log.info("worker %s claimed job %s (attempt %d)", wid, job_id, job.attempt_count)
    beat = _Heartbeat(job_id, wid, settings)
    beat.start()
    try:
        return _run_claimed(job, wid, settings, beat)
    except LeaseLostError:
        log.warning("job %s: lease lost, another worker owns it now", job_id)
        return Outcome(job_id, "lease-lost")
    except Exception as exc:  # never let a job kill the worker
        log.exception("job %s failed", job_id)
        message = f"internal error while running the job: {type(exc).__name__}: {exc}"
        _fail(job_id, wid, message)
        return Outcome(job_id, "failed", message=message)
    finally:
        beat.stop_event.set()


def _fail(job_id: str, wid: str, message: str) -> None:
    try:
        with session_scope(immediate=True) as s:
            fail_job(s, job_id, wid, message)
    except LeaseLostError:
        pass


def _run_claimed(job: JobRecord, wid: str, settings: Settings, beat: _Heartbeat) -> Outcome:
    job_id = job.id
    try:
        prepared = prepare(job.spec)
    except (ValidationError, ValueError, KeyError) as exc:
        message = format_user_error(exc, job.spec)
        _fail(job_id, wid, message)
        return Outcome(job_id, "failed", message=message)

    with session_scope() as s:
        ckpt = latest_checkpoint(s, job_id)
    state = from_jsonable(json.loads(ckpt.state.decode())) if ckpt is not None else None
    run = prepared.new_run(state=state)
    resumed_from = ckpt.generation if ckpt is not None else None
    if resumed_from is not None:
        log.info("job %s resumes from its checkpoint at generation %d", job_id, resumed_from)

    pending: list[dict[str, Any]] = []  # generation rows not yet written
    last_flush = time.monotonic()
    while not run.done:
        if beat.lost.is_set():
            raise LeaseLostError(job_id)
        with session_scope() as s:
            cancelled = is_cancel_requested(s, job_id)
        if cancelled:
            with session_scope(immediate=True) as s:
                mark_cancelled(s, job_id, wid)
            return Outcome(job_id, "cancelled", resumed_from)
        t0 = time.perf_counter()
        progress = run.step()
        pending.append(
            {
                "generation": progress.generation,
                "n_evals": progress.n_evals,
                "best": [float(v) for v in progress.best_f],
                "wall_time_s": time.perf_counter() - t0,
                "front": _thin_front(progress.front_F),
            }
        )
        checkpoint_due = run.done or progress.generation % settings.checkpoint_every == 0
        if checkpoint_due or time.monotonic() - last_flush >= PROGRESS_FLUSH_S:
            # Progress rows (and the checkpoint when due) in one transaction: a generation of a
            # few ms must not wait on a database commit, and two workers on one SQLite file must
            # not serialise on it. Rows after the last checkpoint are re-run on resume and
            # ignored as duplicates.
            with session_scope(immediate=True) as s:
                for row in pending:
                    record_generation(s, job_id, wid, **row)
                if checkpoint_due:
                    blob = json.dumps(to_jsonable(run.state_dict()), allow_nan=False).encode()
                    save_checkpoint(s, job_id, wid, generation=progress.generation, state=blob)
            pending.clear()
            last_flush = time.monotonic()

    try:
        result = finalize(prepared, run.result())
    except (ValueError, ArithmeticError) as exc:
        message = f"the study could not decode its result: {exc}"
        _fail(job_id, wid, message)
        return Outcome(job_id, "failed", resumed_from, message)
    notes = []
    if resumed_from is not None:
        notes.append(
            f"resumed from the checkpoint of generation {resumed_from} "
            f"(attempt {job.attempt_count}) after the previous worker stopped"
        )
    _store_result(job_id, wid, settings, result, notes)
    return Outcome(job_id, "succeeded", resumed_from)


MAX_FRONT_POINTS = 300


def _thin_front(F: Any) -> list[list[float]] | None:
    """The objective vectors of a front, at most ``MAX_FRONT_POINTS`` (evenly strided), or None
    for a single-objective run (its front is just the best point)."""
    import numpy as np

    F = np.asarray(F, dtype=float)
    if F.ndim != 2 or F.shape[1] < 2 or F.shape[0] == 0:
        return None
    if F.shape[0] > MAX_FRONT_POINTS:
        F = F[np.linspace(0, F.shape[0] - 1, MAX_FRONT_POINTS).round().astype(int)]
    F = np.where(np.isfinite(F), F, np.nan)
    return [[None if v != v else float(v) for v in row] for row in F]  # type: ignore[misc]


def _fronts_from_store(job_id: str) -> dict[int, Any] | None:
    """{generation: F} of every recorded generation that has a front (across resumes)."""
    import numpy as np

    from services.store.repository import list_generations

    fronts: dict[int, Any] = {}
    after: int | None = None
    with session_scope() as s:
        while True:
            rows = list_generations(s, job_id, after=after, limit=1000)
            for g in rows:
                if g.front:
                    fronts[g.generation] = np.asarray(g.front, dtype=float)
            if len(rows) < 1000:
                break
            after = rows[-1].generation
    return fronts or None


def _store_result(
    job_id: str, wid: str, settings: Settings, result: RunResult, notes: list[str]
) -> None:
    """Artifacts first (files), then every row in one transaction."""
    store = ArtifactStore.from_settings(settings)
    artifacts: list[ArtifactIn] = []
    warnings: list[str] = list(notes)
    doc = result.to_dict()
    artifacts.append(
        ArtifactIn("result", *store.put(job_id, "result", json.dumps(doc).encode(), suffix=".json"))
    )
    if result.spec.record:
        rec = _write_recording(job_id, result, store)
        if isinstance(rec, ArtifactIn):
            artifacts.append(rec)
        else:
            warnings.append(rec)
    best = doc["best"]
    with session_scope(immediate=True) as s:
        finish_job(
            s,
            job_id,
            wid,
            result=ResultIn(
                best_x=best["x"],
                objectives={
                    "names": doc["objective_names"],
                    "values": best["objectives"],
                },
                metrics=best["metrics"],
                summary={
                    "table": best["table"],
                    "extra": best["extra"],
                    "extras": doc["extras"],
                    "optimizer": doc["optimizer"],
                    "history": doc["history"],
                },
            ),
            pareto=[ParetoPointIn(i, p["x"], p["objectives"]) for i, p in enumerate(doc["pareto"])],
            baselines=[BaselineIn(name, b) for name, b in doc["baselines"].items()],
            artifacts=artifacts,
            warnings=warnings,
        )


def _write_recording(job_id: str, result: RunResult, store: ArtifactStore) -> ArtifactIn | str:
    """Write the job's Rerun recording; a failure becomes a warning, never a failed job."""
    try:
        from services.worker.rerun_writer import write_recording
    except ImportError as exc:
        return f"recording skipped: {exc}"
    try:
        with tempfile.TemporaryDirectory(prefix="legopt-rrd-") as tmp:
            path = Path(tmp) / "recording.rrd"
            write_recording(result, path, recording_id=job_id, fronts=_fronts_from_store(job_id))
            return ArtifactIn("recording", *store.put(job_id, "recording", path))
    except Exception as exc:
        log.warning("job %s: recording failed: %s", job_id, traceback.format_exc())
        return f"recording failed: {type(exc).__name__}: {exc}"


def run_payload(job_id: str) -> dict[str, Any]:
    """Executed inside the Celery task (kept separate for tests)."""
    outcome = execute_job(job_id)
    return {"job_id": outcome.job_id, "status": outcome.status}
