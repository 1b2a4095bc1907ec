"""The warm-up leaves every kernel the studies use compiled (issue 23): after
``python -m legcore.warmup`` — what ``run.py`` runs once after installing — a fresh process that
runs a short job of every study kind and the numerical IK compiles nothing (numba's
``numba:compile`` event fires only on a cache miss; ``legcore.warmup.compiled_during``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from legcore.warmup import compiled_during

ROOT = Path(__file__).resolve().parents[2]


def test_compiled_during_sees_a_compile_and_not_a_second_call() -> None:
    import numba

    @numba.njit
    def twice(x: float) -> float:
        return 2.0 * x

    assert len(compiled_during(lambda: twice(1.0))) == 1
    assert compiled_during(lambda: twice(2.0)) == []  # the same signature: no new compile


@pytest.mark.integration
def test_after_the_warmup_a_fresh_process_compiles_nothing() -> None:
    warm = subprocess.run([sys.executable, "-m", "legcore.warmup"], cwd=ROOT,
                          capture_output=True, text=True, timeout=3600)  # fmt: skip
    assert warm.returncode == 0, warm.stdout[-3000:] + warm.stderr[-3000:]
    check = subprocess.run([sys.executable, "-m", "legcore.warmup", "--check"], cwd=ROOT,
                           capture_output=True, text=True, timeout=3600)  # fmt: skip
    assert check.returncode == 0, check.stdout[-5000:] + check.stderr[-2000:]
    assert "warmup: 0 kernels compiled" in check.stdout
