"""Memory of a job: bytes per evaluated individual-sample, evaluation chunks, predicted peak.

An evaluation of ``B`` individuals of ``K`` time samples allocates arrays of shape
``(B, K, ...)`` — for a serial leg the link frames, chain points, trajectories and their
temporaries — so its transient peak is ``B · K · bytes_per_sample``. :func:`bytes_per_sample`
measures that coefficient once per kind of problem (its name, sizes and joints) with
``tracemalloc`` around ``_evaluate`` on :data:`CALIBRATION_ROWS` individuals (numpy reports its
buffers to tracemalloc) and remembers it for the process; ``Problem.evaluate`` measures it on
the first rows of its first batch, the service's size check on a fixed random batch. Measuring
instead of a stored table keeps the prediction right while the evaluation code changes (the
seed 000 coefficient went from 689 to 146 B during issue 12).

``Problem.evaluate`` evaluates at most :func:`chunk_rows` individuals at a time so that one
call stays within an evaluation budget (:func:`eval_budget_bytes`: 256 MiB, or
``LEGOPT_EVAL_MEMORY_MB``); the results are the same as one whole-batch call.

:func:`predicted_peak_bytes` is the peak resident memory of a process running a job: the
imported libraries and built problem (:data:`PROCESS_BASE_BYTES`), the largest chunked
evaluation (the job's own, or its companions': the seed 000 baseline GAs), and the population
state. The
service refuses a job whose prediction exceeds its per-worker limit
(``Settings.worker_memory_limit_mb``); ``benchmarks/bench_memory.py`` compares the prediction
with the measured peak RSS.
"""

from __future__ import annotations

import os
import threading
import tracemalloc
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = [
    "CALIBRATION_ROWS",
    "DEFAULT_EVAL_BUDGET_BYTES",
    "PROCESS_BASE_BYTES",
    "UNKNOWN_BYTES_PER_SAMPLE",
    "bytes_per_sample",
    "chunk_rows",
    "eval_budget_bytes",
    "eval_peak_bytes",
    "measure_bytes_per_sample",
    "predicted_peak_bytes",
]

MIB = 1024**2

#: Evaluation budget of one ``Problem.evaluate`` call when ``LEGOPT_EVAL_MEMORY_MB`` is unset.
DEFAULT_EVAL_BUDGET_BYTES = 256 * MIB

#: Peak RSS of a process that imported legcore (numpy, numba, pinocchio, scipy), built a study
#: problem and evaluated a tiny batch: 255–275 MiB for every example (measured 2026-11-23).
PROCESS_BASE_BYTES = 280 * MIB

#: Individuals evaluated under tracemalloc to measure a problem's bytes per sample.
CALIBRATION_ROWS = 16

#: Coefficient used when a problem cannot be measured (its evaluation failed): 2 KiB.
UNKNOWN_BYTES_PER_SAMPLE = 2048.0

#: Bytes per individual of the optimiser's state per decision variable (X, offspring, parents,
#: scores: a handful of (B, n_var) float arrays).
STATE_BYTES_PER_GENE = 8 * 8

_MEASURED: dict[tuple[Any, ...], float] = {}
_TRACE_LOCK = threading.Lock()


def _kind(problem: Any) -> str:
    return str(getattr(problem, "name", "")).split("[", 1)[0]


def _key(problem: Any) -> tuple[Any, ...]:
    robot = getattr(problem, "robot", None)
    return (type(problem).__qualname__, str(getattr(problem, "name", "")),
            getattr(problem, "criterion", None), int(getattr(problem, "n_var", 0)),
            int(getattr(problem, "n_constr", 0)), samples(problem),
            getattr(robot, "nq", None), len(getattr(problem, "boxes", ()) or ()))


def measure_bytes_per_sample(problem: Any, X: np.ndarray | None = None) -> float:
    """Peak bytes ``problem._evaluate`` allocates per individual-sample, measured with
    tracemalloc on ``X`` (default: :data:`CALIBRATION_ROWS` fixed random rows in the bounds)."""
    if X is None:
        rng = np.random.default_rng(12345)
        X = problem.snap(rng.uniform(problem.xl, problem.xu,
                                     (CALIBRATION_ROWS, problem.n_var)))
    X = np.ascontiguousarray(X, dtype=float)
    with _TRACE_LOCK:  # one measurement at a time: another thread's stop() would end ours
        was_tracing = tracemalloc.is_tracing()
        if not was_tracing:
            tracemalloc.start()
        try:
            before = tracemalloc.get_traced_memory()[0]
            tracemalloc.reset_peak()
            problem._evaluate(X)
            peak = tracemalloc.get_traced_memory()[1] - before
        finally:
            if not was_tracing:
                tracemalloc.stop()
    return max(1.0, peak / (X.shape[0] * samples(problem)))


def bytes_per_sample(problem: Any, X: np.ndarray | None = None) -> float:
    """Bytes per individual-sample at the peak of ``problem.evaluate``: a problem's own
    ``bytes_per_sample`` attribute (a number) if it has one, else measured once per kind of
    problem (:func:`measure_bytes_per_sample`, on ``X`` if given) and remembered."""
    own = getattr(problem, "bytes_per_sample", None)
    if isinstance(own, int | float) and own > 0:
        return float(own)
    key = _key(problem)
    found = _MEASURED.get(key)
    if found is None:
        try:
            found = measure_bytes_per_sample(problem, X)
        except Exception:  # noqa: BLE001 - evaluate reports its own errors; size conservatively
            found = UNKNOWN_BYTES_PER_SAMPLE
        _MEASURED[key] = found
    return found


def samples(problem: Any) -> int:
    """Time samples per evaluated individual (``n_samples``, 1 when the problem has none)."""
    return max(1, int(getattr(problem, "n_samples", 1) or 1))


def eval_budget_bytes(env: Mapping[str, str] | None = None) -> int:
    """The memory budget (bytes) of one ``evaluate`` call: ``LEGOPT_EVAL_MEMORY_MB`` MiB, or
    :data:`DEFAULT_EVAL_BUDGET_BYTES`."""
    value = (os.environ if env is None else env).get("LEGOPT_EVAL_MEMORY_MB", "")
    try:
        mb = float(value)
    except ValueError:
        return DEFAULT_EVAL_BUDGET_BYTES
    return int(mb * MIB) if mb > 0 else DEFAULT_EVAL_BUDGET_BYTES


def chunk_rows(problem: Any, budget: int | None = None, X: np.ndarray | None = None) -> int:
    """How many individuals one chunk of ``problem.evaluate`` may hold: ``budget //
    (K · bytes_per_sample)``, at least 1. ``budget``: bytes, default :func:`eval_budget_bytes`
    (or the problem's ``eval_budget_bytes`` attribute when set). ``X``: the batch about to be
    evaluated — all of it when even :data:`UNKNOWN_BYTES_PER_SAMPLE` fits the budget (nothing
    measured), else the coefficient is measured on its first rows."""
    if budget is None:
        own = getattr(problem, "eval_budget_bytes", None)
        budget = int(own) if own else eval_budget_bytes()
    K = samples(problem)
    if X is not None:
        if X.shape[0] * K * UNKNOWN_BYTES_PER_SAMPLE <= budget:
            return max(1, int(X.shape[0]))
        X = X[:CALIBRATION_ROWS]
    return max(1, int(budget // (K * bytes_per_sample(problem, X))))


def eval_peak_bytes(problem: Any, rows: int, budget: int | None = None) -> int:
    """Transient bytes of evaluating ``rows`` individuals in chunks (one chunk at a time)."""
    rows = min(max(1, int(rows)), chunk_rows(problem, budget))
    return int(rows * samples(problem) * bytes_per_sample(problem))


def _companions(problem: Any) -> list[tuple[Any, int]]:
    """Other problems a job evaluates, with their population (a study problem's
    ``companions()``: e.g. the baseline GAs a swing_energy job runs in ``finalize``)."""
    companions = getattr(problem, "companions", None)
    return list(companions()) if callable(companions) else []


def predicted_peak_bytes(problem: Any, population: int, budget: int | None = None) -> int:
    """Predicted peak RSS (bytes) of a process running a job of ``population`` individuals on
    ``problem``: :data:`PROCESS_BASE_BYTES` + the largest chunked evaluation (the job's or its
    baseline GAs') + the population state (``population · n_var ·`` :data:`STATE_BYTES_PER_GENE`).
    """
    population = max(1, int(population))
    peak = eval_peak_bytes(problem, population, budget)
    for other, rows in _companions(problem):
        peak = max(peak, eval_peak_bytes(other, rows, budget))
    state = population * int(getattr(problem, "n_var", 1)) * STATE_BYTES_PER_GENE
    return int(PROCESS_BASE_BYTES + peak + state)
