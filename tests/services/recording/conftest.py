"""The recording every writer and replay test reads (``written``)."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from legcore.studies.study import Box
from services.recording import writer as W
from tests.recording_fixtures import arm_motion, fake_result

SCENE = {
    "targets": np.array([[0.5, 0.0, 0.5], [0.6, 0.0, 0.5]]),
    "obstacles": [Box((0.3, 0.0, 0.5), (0.03, 0.02, 0.013))],
    "support_polygon": np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]]),
}


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, SimpleNamespace, dict]:
    """One recording of a 3-objective run with per-generation fronts and two baselines."""
    path = tmp_path_factory.mktemp("rec") / "job.rrd"
    res = fake_result(
        arm_motion(K=5000, **SCENE),
        generations=20,
        baselines={"parabolic": arm_motion(K=600), "min energy": arm_motion(K=300)},
    )
    rng = np.random.default_rng(3)
    fronts = {g: rng.random((40 + g, 3)) for g in range(1, 21)}
    W.write_recording(res, path, recording_id="job-123", fronts=fronts)
    return path, res, fronts
