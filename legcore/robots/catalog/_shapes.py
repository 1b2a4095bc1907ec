"""Inertia helpers for catalog entries whose papers give no inertial data (SI units)."""

from __future__ import annotations

import numpy as np


def rod_inertia(mass: float, length: float, axis: int, radius: float = 0.02) -> list[list[float]]:
    """Inertia (kg·m², about the COM) of a solid cylinder of ``mass`` kg, ``length`` m and
    ``radius`` m whose long axis is coordinate ``axis`` (0=x, 1=y, 2=z)."""
    axial = 0.5 * mass * radius**2
    transverse = mass * (3.0 * radius**2 + length**2) / 12.0
    diag = [transverse, transverse, transverse]
    diag[axis] = axial
    return np.diag(diag).tolist()
