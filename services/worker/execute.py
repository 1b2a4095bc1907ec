"""Execute one job: claim it, run it generation by generation, store the outcome.

The only function the Celery task calls is :func:`execute_job`. It never raises for a problem
with the job itself: a spec that cannot run, a study that fails, an internal error — all end as
``failed`` with a message a user can act on; a lost lease ends quietly (another worker owns the
job now). Between generations it honours cancellation, heartbeats (a background thread renews
the lease), records progress and saves a checkpoint every ``checkpoint_every`` generations
(at least ``CHECKPOINT_MIN_S`` apart unless that is 1), so a redelivered or reaped job resumes
from its last checkpoint instead of generation 0.

Overhead (issue 12): generation rows are written in batches — every ``PROGRESS_FLUSH_S``
seconds, at each checkpoint and at the end — with one UPDATE and one multi-row INSERT, fronts
as float64 bytes; cancellation is read by those writes and by the heartbeat's UPDATE (no query
per generation); the recording's per-generation fronts come from memory, not from the store
(only a resumed job reads the generations of its earlier attempts back).
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
from services.store.evaluations import record_evaluations
from services.store.lifecycle import (
    claim_job,
    fail_job,
    finish_job,
    mark_cancelled,
    renew_lease,
)
from services.store.output_queries import get_hypervolume_ref, set_hypervolume_ref
from services.store.progress import latest_checkpoint, record_generations, save_checkpoint
from services.store.quotas import add_cpu_seconds
from services.store.records import (
    ArtifactIn,
    BaselineIn,
    GenerationIn,
    JobRecord,
    ParetoPointIn,
    ResultIn,
)
from services.store.repository import job_spec
from services.store.session import session_scope
from services.store.settings import Settings, get_settings
from services.worker.generation_keep import TrialKeeper, recording_fronts, thin_front
from services.worker.hypervolume import HypervolumeTracker

log = logging.getLogger("legopt.worker")

#: At most this long (s) between two writes of progress rows (a checkpoint also writes them).
PROGRESS_FLUSH_S = 0.5
#: With ``checkpoint_every`` > 1, two checkpoints are at least this long (s) apart: a job of
#: 3 ms generations is not checkpointed 60 times a second (a resume re-runs ≤ ~1 s of work).
#: ``checkpoint_every: 1`` still checkpoints every generation (what the recovery tests use).
CHECKPOINT_MIN_S = 1.0

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
    """Renews the lease every ``period`` seconds; sets ``lost`` if the lease was taken away and
    ``cancel`` if the job's cancellation was requested (the same UPDATE answers both)."""

    def __init__(self, job_id: str, wid: str, settings: Settings) -> None:
        super().__init__(name=f"heartbeat-{job_id[:8]}", daemon=True)
        self.job_id, self.wid, self.settings = job_id, wid, settings
        self.stop_event = threading.Event()
        self.lost = threading.Event()
        self.cancel = threading.Event()

    def run(self) -> None:
        while not self.stop_event.wait(self.settings.heartbeat_seconds):
            try:
                with session_scope() as s:
                    flag = renew_lease(s, self.job_id, self.wid, self.settings.lease_seconds)
            except Exception:  # a transient database error: try again next period
                log.exception("heartbeat of job %s failed", self.job_id)
                continue
            if flag is None:
                self.lost.set()
                return
            if flag:
                self.cancel.set()


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
        spec = job_spec(s, job) if job is not None else None
    if job is None:
        return Outcome(job_id, "not-claimed")
    log.info("worker %s claimed job %s (attempt %d)", wid, job_id, job.attempt_count)
    beat = _Heartbeat(job_id, wid, settings)
    beat.start()
    try:
        return _run_claimed(job, spec, wid, settings, beat)
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


class _CpuMeter:
    """CPU seconds of this process since the last ``take()`` (charged to the job's key)."""

    def __init__(self) -> None:
        self._last = time.process_time()

    def take(self) -> float:
        now = time.process_time()
        spent, self._last = now - self._last, now
        return spent


def _run_claimed(
    job: JobRecord, spec: Any, wid: str, settings: Settings, beat: _Heartbeat
) -> Outcome:
    job_id = job.id
    cpu = _CpuMeter()
    try:
        prepared = prepare(spec)
    except (ValidationError, ValueError, KeyError) as exc:
        message = format_user_error(exc, spec)
        _fail(job_id, wid, message)
        return Outcome(job_id, "failed", message=message)

    with session_scope() as s:
        ckpt = latest_checkpoint(s, job_id)
        hv = HypervolumeTracker(get_hypervolume_ref(s, job_id))
    state = from_jsonable(json.loads(ckpt.state.decode())) if ckpt is not None else None
    run = prepared.new_run(state=state)
    resumed_from = ckpt.generation if ckpt is not None else None
    if resumed_from is not None:
        log.info("job %s resumes from its checkpoint at generation %d", job_id, resumed_from)

    pending: list[GenerationIn] = []  # generation rows not yet written
    trials = TrialKeeper(prepared)  # the evaluated solutions kept for the trial table
    fronts: dict[int, Any] = {}  # this attempt's thinned fronts, for the recording
    last_flush = last_checkpoint = time.monotonic()
    min_checkpoint_s = 0.0 if settings.checkpoint_every == 1 else CHECKPOINT_MIN_S
    while not run.done:
        if beat.lost.is_set():
            raise LeaseLostError(job_id)
        if beat.cancel.is_set():
            with session_scope(immediate=True) as s:
                mark_cancelled(s, job_id, wid)
            return Outcome(job_id, "cancelled", resumed_from)
        t0 = time.perf_counter()
        progress = run.step()
        front = thin_front(progress.front_F)
        if front is not None and prepared.spec.record:
            fronts[progress.generation] = front
        pending.append(
            GenerationIn(
                generation=progress.generation,
                n_evals=progress.n_evals,
                best=[float(v) for v in progress.best_f],
                wall_time_s=time.perf_counter() - t0,
                hypervolume=hv.measure(progress.front_F),
                front=front,
            )
        )
        trials.add(progress, last=run.done)
        now = time.monotonic()
        # the last generation too keeps the spacing: a job that dies while its result is
        # stored re-runs at most the generations since its last checkpoint (a job shorter
        # than CHECKPOINT_MIN_S has none and starts again: it costs less than a checkpoint)
        checkpoint_due = (
            progress.generation % settings.checkpoint_every == 0 or run.done
        ) and now - last_checkpoint >= min_checkpoint_s
        if checkpoint_due or run.done or now - last_flush >= PROGRESS_FLUSH_S:
            # Progress rows (and the checkpoint when due) in one transaction: a generation of a
            # few ms must not wait on a database commit, and two workers on one SQLite file must
            # not serialise on it. Rows after the last checkpoint are re-run on resume and
            # ignored as duplicates. The progress UPDATE answers cancel_requested.
            blob = None
            if checkpoint_due:  # encoded before the write lock is taken
                blob = json.dumps(to_jsonable(run.state_dict()), allow_nan=False).encode()
            with session_scope(immediate=True) as s:
                if record_generations(s, job_id, wid, pending):
                    beat.cancel.set()
                record_evaluations(s, job_id, trials.take())
                if (ref := hv.take_unsaved_ref()) is not None:
                    set_hypervolume_ref(s, job_id, wid, ref)
                add_cpu_seconds(s, job_id, cpu.take())
                if blob is not None:
                    save_checkpoint(s, job_id, wid, generation=progress.generation, state=blob)
            pending.clear()
            last_flush = time.monotonic()
            if checkpoint_due:
                last_checkpoint = last_flush

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
    attempt = f"a{job.attempt_count}-{uuid.uuid4().hex[:6]}"
    kept_fronts = recording_fronts(job_id, resumed_from, fronts)
    _store_result(job_id, wid, attempt, settings, result, notes, cpu, kept_fronts)
    return Outcome(job_id, "succeeded", resumed_from)


def _store_result(
    job_id: str,
    wid: str,
    attempt: str,
    settings: Settings,
    result: RunResult,
    notes: list[str],
    cpu: _CpuMeter,
    fronts: dict[int, Any] | None = None,
) -> None:
    """Artifacts first (files under this attempt's own directory), then every row in one
    transaction; if the lease was lost meanwhile, the attempt's files are removed and nothing
    of the winner's is touched."""
    store = ArtifactStore.from_settings(settings)
    try:
        _store_attempt(job_id, wid, attempt, store, result, notes, cpu, fronts)
    except LeaseLostError:
        store.delete_attempt(job_id, attempt)
        raise
    store.prune_attempts(job_id, keep=attempt)  # what workers that died mid-write left


def _store_attempt(
    job_id: str,
    wid: str,
    attempt: str,
    store: ArtifactStore,
    result: RunResult,
    notes: list[str],
    cpu: _CpuMeter,
    fronts: dict[int, Any] | None = None,
) -> None:
    artifacts: list[ArtifactIn] = []
    warnings: list[str] = list(notes)
    # the study's extras (up to ~0.5 MB: workspaces, masks) are not made here: the API makes
    # them when they are first asked for (services.api.study_extras; issue 23: overhead)
    doc = result.to_dict(extras=False)
    blob = json.dumps(doc, separators=(",", ":")).encode()  # compact: no whitespace
    stored = store.put(job_id, "result", blob, suffix=".json", attempt=attempt)
    artifacts.append(ArtifactIn("result", *stored))
    if result.spec.record:
        rec = _write_recording(job_id, attempt, result, store, warnings, fronts)
        if isinstance(rec, ArtifactIn):
            artifacts.append(rec)
        else:
            warnings.append(rec)
    best = doc["best"]
    with session_scope(immediate=True) as s:
        add_cpu_seconds(s, job_id, cpu.take())
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
                    "optimizer": doc["optimizer"],
                    "start": doc.get("start"),
                    "history": doc["history"],
                    # the robot-relative parameters the job ran with and the rule behind each
                    # derived value (what the job page and `legopt results` show)
                    "task": doc.get("task"),
                    # how far the optimum is from the best the problem allows (issue 19)
                    "gap": doc.get("gap"),
                    # the optimum's place on the front (None: not on it, e.g. refined)
                    "best_index": doc.get("best_index"),
                },
                # the verdict, on the job row (GET /jobs, the jobs page, exports)
                feasible=doc.get("feasible"),
                violations=doc.get("violations"),
            ),
            pareto=[ParetoPointIn(i, p["x"], p["objectives"]) for i, p in enumerate(doc["pareto"])],
            baselines=[BaselineIn(name, b) for name, b in doc["baselines"].items()],
            artifacts=artifacts,
            warnings=warnings,
        )


def _write_recording(
    job_id: str,
    attempt: str,
    result: RunResult,
    store: ArtifactStore,
    warnings: list[str],
    fronts: dict[int, Any] | None = None,
) -> ArtifactIn | str:
    """Write the job's Rerun recording; a failure becomes a warning, never a failed job, and
    what the recording could not draw (e.g. a mesh outside the installed robot-description
    packages and the configured roots, which is never read) is appended to ``warnings``."""
    try:
        from services.recording.writer import write_recording
    except ImportError as exc:
        return f"recording skipped: {exc}"
    try:
        with tempfile.TemporaryDirectory(prefix="legopt-rrd-") as tmp:
            path = Path(tmp) / "recording.rrd"
            notes = write_recording(
                result, path, recording_id=job_id, fronts=fronts,
                mesh_roots=get_settings().mesh_root_dirs,
            )  # fmt: skip
            warnings.extend(f"recording: {n}" for n in notes or [])
            return ArtifactIn("recording", *store.put(job_id, "recording", path, attempt=attempt))
    except Exception as exc:
        log.warning("job %s: recording failed: %s", job_id, traceback.format_exc())
        return f"recording failed: {type(exc).__name__}: {exc}"
