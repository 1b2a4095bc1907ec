"""Hypervolume of a running job's front, generation by generation, against one reference point.

A hypervolume means something only next to the point it was measured against, and values of
one job are comparable only if that point stays fixed. The worker fixes it at the first
generation that has a front of two or more objectives: ``nadir + 10 % of the span`` of that
front (:func:`legcore.metrics.reference_point`), i.e. of the initial population's best. It is
stored on the job (``jobs.hypervolume_ref``) in the transaction that writes that generation's
row, and a resumed job reads it back, so every generation of a job, across attempts, uses the
same point (a job that resumes before it was stored recomputes the same point: runs are
deterministic). Later fronts that leave the box only lose the part outside it.
Single-objective jobs have no hypervolume (None).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from legcore.metrics import hypervolume_value, reference_point

__all__ = ["HypervolumeTracker"]


class HypervolumeTracker:
    """Measures each generation's front against the job's reference point (set on first use)."""

    def __init__(self, ref: Sequence[float] | None = None) -> None:
        """``ref``: the job's stored reference point, or None to derive it from the first front."""
        self.ref: np.ndarray | None = None if ref is None else np.asarray(ref, dtype=float)
        self._unsaved: list[float] | None = None
        self._ref_fits: bool | None = None

    def measure(self, F: Any) -> float | None:
        """Hypervolume (objective units multiplied) of the front ``F`` (k, m), or None when
        there is no front of two or more objectives with a finite point."""
        F = np.asarray(F, dtype=float)
        if F.ndim != 2 or F.shape[1] < 2:
            return None
        finite = np.isfinite(F).all(axis=1)
        if not finite.all():
            F = F[finite]
        if F.shape[0] == 0:
            return None
        if self.ref is None:
            self.ref = reference_point(F)
            self._unsaved = [float(v) for v in self.ref]
        if self._ref_fits is None:  # checked once: the point is fixed for the job
            self._ref_fits = bool(self.ref.ndim == 1 and np.all(np.isfinite(self.ref)))
        if not self._ref_fits or self.ref.shape != (F.shape[1],):
            return None
        return hypervolume_value(F, self.ref)

    def take_unsaved_ref(self) -> list[float] | None:
        """The reference point if it was derived here and not handed out for storing yet."""
        ref, self._unsaved = self._unsaved, None
        return ref
