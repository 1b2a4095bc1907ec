"""Deadlines a busy machine cannot break: time counted in *quiet-machine seconds*.

A test's wait (a service to answer, a job to finish) has a bound only to catch a hang. Wall
time is the wrong clock for it on a shared CI machine: with the CPU oversubscribed k times,
every process gets about 1/k of a core and the same work takes k times longer. ``Patience``
advances by ``dt / max(1, runnable / cores)`` per poll (``runnable``: the instantaneous count
of runnable threads, field 4 of ``/proc/loadavg``), so a budget of 60 s means "what 60 s of a
quiet machine would do" — and a hard cap of ``hard_factor`` × the budget in wall time still
ends a real hang.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

LOADAVG = Path("/proc/loadavg")


def oversubscription() -> float:
    """Runnable threads per core now (>= 1; 1 where ``/proc/loadavg`` is absent)."""
    try:
        runnable = int(LOADAVG.read_text().split()[3].split("/")[0])
    except (OSError, ValueError, IndexError):
        return 1.0
    return max(1.0, runnable / (os.cpu_count() or 1))


class Patience:
    """A budget of ``budget_s`` quiet-machine seconds; call :meth:`expired` once per poll."""

    def __init__(self, budget_s: float, *, hard_factor: float = 10.0) -> None:
        self.budget_s = budget_s
        self.hard_s = hard_factor * budget_s
        self.start = self._last = time.monotonic()
        self.quiet_s = 0.0

    def expired(self) -> bool:
        """True once the budget (quiet-machine seconds) or the hard cap (wall) is spent."""
        now = time.monotonic()
        self.quiet_s += (now - self._last) / oversubscription()
        self._last = now
        return self.quiet_s > self.budget_s or now - self.start > self.hard_s

    @property
    def wall_s(self) -> float:
        return time.monotonic() - self.start

    def __str__(self) -> str:
        return (f"{self.budget_s:.0f} s of a quiet machine ({self.wall_s:.0f} s wall, "
                f"{self.quiet_s:.0f} s counted)")  # fmt: skip
