"""How a recording draws a Pareto front: named axes, and a box that fits the front's spread.

Objectives have different units and spans (a 5-35 s cycle time against a 14.1-14.5 J energy),
and a Rerun 2-D or 3-D view draws one unit the same length on every axis, so the raw front
would be a flat line. The front's points keep their true values (hovering one shows them);
what changes is how they are drawn: each front entity gets a static ``Transform3D`` that maps
the box ``lo .. hi`` of the objectives to the unit square (cube), and axis lines with the
objective's name and unit and tick labels with true values are drawn in the same box.
Pure numpy: the writer (``services.recording.writer``) turns it into archetypes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["AxisLine", "FrontDisplay", "front_display"]

FloatArray = NDArray[np.float64]

#: Ticks per axis (the box's ends and its middle).
TICKS = 3
#: Length of a tick mark, in the unit box.
TICK = 0.02


@dataclass(frozen=True)
class AxisLine:
    """A labelled line of the axes, in objective space: ``points`` (2, d)."""

    points: FloatArray
    label: str


@dataclass(frozen=True, eq=False)
class FrontDisplay:
    """The box ``lo .. hi`` (d,) drawn as the unit square/cube, and the axis labels (d)."""

    lo: FloatArray
    hi: FloatArray
    labels: tuple[str, ...]

    @property
    def dims(self) -> int:
        return int(self.lo.shape[0])

    @property
    def scale(self) -> FloatArray:
        """Per-axis scale of the drawing transform (1 / span)."""
        return 1.0 / (self.hi - self.lo)

    @property
    def translation(self) -> FloatArray:
        """Translation of the drawing transform (``-lo / span``)."""
        return -self.lo * self.scale

    def transform(self) -> tuple[FloatArray, FloatArray]:
        """``(translation, scale)`` (3,) of the drawing transform; in 2-D the second objective
        grows upwards (a 2-D view's y axis points down)."""
        t, s = self.translation, self.scale
        if self.dims == 3:
            return t, s
        return np.array([t[0], 1.0 - t[1], 0.0]), np.array([s[0], -s[1], 1.0])

    def axes(self) -> tuple[list[FloatArray], list[AxisLine]]:
        """The box's lower edges, one per objective (``(2, d)`` each), and the labelled marks:
        per axis its name (on a short segment at 60-90 % of the axis, clear of the ticks) and
        ticks with their true values."""
        lines, marks = [], []
        span = self.hi - self.lo
        for k in range(self.dims):
            end = self.lo.copy()
            end[k] = self.hi[k]
            lines.append(np.stack([self.lo, end]))
            a, b = self.lo.copy(), self.lo.copy()
            a[k], b[k] = self.lo[k] + 0.6 * span[k], self.lo[k] + 0.9 * span[k]
            marks.append(AxisLine(np.stack([a, b]), self.labels[k]))
            other = (k + 1) % self.dims
            for v in np.linspace(self.lo[k], self.hi[k], TICKS):
                a = self.lo.copy()
                a[k] = v
                b = a.copy()
                b[other] -= TICK * span[other]
                marks.append(AxisLine(np.stack([a, b]), f"{v:.4g}"))
        return lines, marks


def front_display(
    fronts: Sequence[FloatArray],
    names: Sequence[str],
    kind: str | None = None,
    *,
    labels: Sequence[str] | None = None,
) -> FrontDisplay | None:
    """The display of fronts ``(k, d)`` (d = 2 or 3) with objective ``names`` of the study
    ``kind``: the box of every finite point, grown by 5 % (a flat axis gets a span of 1), and
    the axis labels ``readable name [unit]`` (:mod:`legcore.studies.metric_names`), or the
    given ``labels``."""
    from legcore.studies.metric_names import metric_name

    pts = [np.asarray(F, dtype=float) for F in fronts if np.asarray(F).size]
    if not pts:
        return None
    A = np.concatenate([p.reshape(-1, p.shape[-1]) for p in pts])
    A = A[np.all(np.isfinite(A), axis=1)]
    if A.shape[0] == 0 or A.shape[1] not in (2, 3):
        return None
    lo, hi = A.min(axis=0), A.max(axis=0)
    span = hi - lo
    span = np.where(span > 0, span, np.maximum(np.abs(lo), 1.0))
    lo, hi = lo - 0.05 * span, hi + 0.05 * span
    shown = list(labels or [])[: A.shape[1]]
    for name in list(names)[len(shown) : A.shape[1]]:
        m = metric_name(str(name), kind)
        shown.append(f"{m.label} [{m.unit}]" if m.unit else m.label)
    shown += [f"f{i + 1}" for i in range(len(shown), A.shape[1])]
    return FrontDisplay(lo, hi, tuple(shown))
