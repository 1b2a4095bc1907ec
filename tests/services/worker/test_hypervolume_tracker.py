"""The worker's per-generation hypervolume (``HypervolumeTracker``, the unchecked fast path of
``legcore.metrics.hypervolume_value``) equals the checked ``legcore.metrics.hypervolume``:
fronts with points outside the reference box and non-finite rows, one fixed reference point."""

from __future__ import annotations

import numpy as np

from legcore.metrics import hypervolume, reference_point
from services.worker.hypervolume import HypervolumeTracker


def test_the_tracker_equals_the_checked_hypervolume() -> None:
    rng = np.random.default_rng(3)
    first = rng.random((40, 3))
    tracker = HypervolumeTracker()
    assert tracker.measure(first) == hypervolume(first, reference_point(first)).value
    ref = reference_point(first)
    assert tracker.take_unsaved_ref() == [float(v) for v in ref]
    for n in (1, 7, 300):
        F = rng.random((n, 3)) * 1.3  # some points leave the box
        F[0, 1] = np.inf
        finite = F[np.isfinite(F).all(axis=1)]
        expected = hypervolume(finite, ref).value if len(finite) else None
        assert tracker.measure(F) == expected
    assert tracker.measure(np.full((2, 3), np.inf)) is None
    assert tracker.measure(rng.random((5, 1))) is None  # one objective: no hypervolume
    assert HypervolumeTracker([1.0, np.nan, 1.0]).measure(first) is None
