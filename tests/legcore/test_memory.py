"""Issue 12, bounded memory: the bytes-per-sample coefficients, chunked evaluation (same
results as one whole batch, never more than ``chunk_rows`` rows at once) and the predicted
peak of a job (pinned formula; measured peak RSS within 20 % in a fresh process)."""

from __future__ import annotations

import json
import subprocess
import sys
import tracemalloc
from typing import Any

import numpy as np
import pytest

from legcore.memory import (
    DEFAULT_EVAL_BUDGET_BYTES,
    MIB,
    PROCESS_BASE_BYTES,
    STATE_BYTES_PER_GENE,
    UNKNOWN_BYTES_PER_SAMPLE,
    bytes_per_sample,
    chunk_rows,
    eval_budget_bytes,
    measure_bytes_per_sample,
    predicted_peak_bytes,
)
from legcore.problems.base import Problem
from legcore.problems.benchmarks import ZDT1
from legcore.runner import prepare

SWING: dict[str, Any] = {"problem": {"kind": "swing_energy"}}
OBSTACLE: dict[str, Any] = {"problem": {"kind": "swing_energy", "obstacle": True}}
TRACKING: dict[str, Any] = {"problem": {"kind": "path_tracking", "n_samples": 60}}


def _population(problem: Problem, n: int) -> np.ndarray:
    rng = np.random.default_rng(3)
    return problem.snap(rng.uniform(problem.xl, problem.xu, (n, problem.n_var)))


@pytest.mark.parametrize("spec", [SWING, OBSTACLE, TRACKING], ids=["flat", "obstacle", "track"])
def test_chunked_evaluation_equals_one_batch(spec: dict[str, Any]) -> None:
    problem = prepare(spec).problem
    X = _population(problem, 23)
    F1, G1 = problem.evaluate(X)
    per_row = problem.n_samples * bytes_per_sample(problem)
    problem.eval_budget_bytes = int(5.5 * per_row)  # chunks of 5, 5, 5, 5, 3 rows
    assert problem.chunk_rows(X) == 5
    F2, G2 = problem.evaluate(X)
    np.testing.assert_array_equal(F1, F2)
    np.testing.assert_array_equal(G1, G2)


def test_evaluate_passes_at_most_chunk_rows() -> None:
    seen: list[int] = []

    class Spy(ZDT1):
        def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
            seen.append(X.shape[0])
            return super()._evaluate(X)

    p = Spy(n_var=4)
    p.bytes_per_sample = 1000.0  # type: ignore[attr-defined]  # a problem's own coefficient
    p.eval_budget_bytes = 7 * 1000
    assert p.chunk_rows() == 7
    F, G = p.evaluate(_population(p, 30))
    assert seen == [7, 7, 7, 7, 2]
    assert F.shape == (30, 2) and G.shape == (30, 0)
    np.testing.assert_array_equal(F, ZDT1(n_var=4).evaluate(_population(p, 30))[0])


def test_chunk_rows_and_budget() -> None:
    problem = prepare(SWING).problem
    bps = bytes_per_sample(problem)
    # remembered from the first evaluation of this kind in the process, which may also count
    # one-time buffers (a (B, K, 3) float array: 24 B per sample) a later measurement reuses
    measured = measure_bytes_per_sample(problem)
    assert 0.95 * measured <= bps <= 1.25 * measured
    assert bytes_per_sample(problem) == bps
    assert chunk_rows(problem, 10 * MIB) == int(10 * MIB // (301 * bps))
    assert chunk_rows(problem, 1) == 1
    small = np.zeros((100, problem.n_var))  # fits even at 2 KiB per sample: one chunk
    assert 100 * 301 * UNKNOWN_BYTES_PER_SAMPLE <= 256 * MIB
    assert chunk_rows(problem, 256 * MIB, X=small) == 100
    assert eval_budget_bytes({}) == DEFAULT_EVAL_BUDGET_BYTES
    assert eval_budget_bytes({"LEGOPT_EVAL_MEMORY_MB": "64"}) == 64 * MIB
    assert eval_budget_bytes({"LEGOPT_EVAL_MEMORY_MB": "junk"}) == DEFAULT_EVAL_BUDGET_BYTES


def test_predicted_peak_formula_is_pinned() -> None:
    problem = prepare(SWING).problem  # 30 genes, 301 samples, baseline GAs of 100
    subs = [sub for sub, _ in problem.companions()]
    assert sorted(p.name for p in subs) == [
        "swing_energy[energy]", "swing_energy[multi_criteria]", "swing_energy[theta_total]"]
    per_row = max(bytes_per_sample(p) for p in [problem, *subs]) * 301
    assert predicted_peak_bytes(problem, 100) == PROCESS_BASE_BYTES + int(100 * per_row) + (
        100 * 30 * STATE_BYTES_PER_GENE)
    assert predicted_peak_bytes(problem, 10) == (  # the baselines' population dominates
        PROCESS_BASE_BYTES + int(100 * per_row) + 10 * 30 * STATE_BYTES_PER_GENE)
    big = prepare({"problem": {"kind": "swing_energy", "dt": 0.0005}}).problem  # 6001 samples
    assert predicted_peak_bytes(big, 2000) < (
        PROCESS_BASE_BYTES + DEFAULT_EVAL_BUDGET_BYTES + 2000 * 30 * STATE_BYTES_PER_GENE)


@pytest.mark.parametrize("spec", [SWING, OBSTACLE, TRACKING], ids=["flat", "obstacle", "track"])
def test_bytes_per_sample_is_the_evaluation_peak(spec: dict[str, Any]) -> None:
    """The coefficient (measured on 16 rows) predicts the tracemalloc peak of 80 rows ±20 %."""
    problem = prepare(spec).problem
    X = _population(problem, 80)
    problem.evaluate(X[:2])  # compile
    tracemalloc.start()
    try:
        problem.evaluate(X)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    measured = peak / (80 * problem.n_samples)
    assert measured == pytest.approx(bytes_per_sample(problem), rel=0.2)


_CHILD = """
import json, sys
from legcore.runner import job_size, prepare, run
spec = json.loads(sys.argv[1])
size = job_size(prepare(spec))
run(spec)
# VmHWM: this process image's peak RSS (ru_maxrss would also count the forking parent's)
hwm = next(ln for ln in open("/proc/self/status") if ln.startswith("VmHWM:"))
print(json.dumps({"peak": size.peak_bytes, "rss": int(hwm.split()[1]) * 1024}))
"""


@pytest.mark.integration
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc/self/status VmHWM")
def test_measured_peak_within_20_percent() -> None:
    """A fresh process running 1000 × 1501 (2 generations, 2-generation baselines): a size
    where the per-sample term is ~40 % of the prediction, so the prediction fails this test if
    the bytes per sample are wrong by half, not only if the fixed process base is."""
    spec = {"problem": {"kind": "swing_energy", "dt": 0.002, "baseline_generations": 2},
            "optimizer": {"kind": "ga", "params": {"pop_size": 1000}},
            "budget": {"generations": 2}}
    out = subprocess.run([sys.executable, "-c", _CHILD, json.dumps(spec)], check=True,
                         capture_output=True, text=True, timeout=300).stdout
    got = json.loads(out.strip().splitlines()[-1])
    assert got["peak"] - PROCESS_BASE_BYTES > 0.3 * got["peak"]  # the per-sample part matters
    assert got["rss"] == pytest.approx(got["peak"], rel=0.2)
