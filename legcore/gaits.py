"""Gait sequences of legged robots: which legs are on the ground at each phase of the cycle.

Gaits are periodic: the *phase* ``φ ∈ [0, 1)`` runs once per cycle (``φ = (t − t0)/T mod 1``).
Each leg leaves the ground at its ``offset`` and stays in the air for ``1 − duty`` of the cycle::

    u = (φ − offset) mod 1          leg-local phase
    in the air  for u ∈ [0, 1 − duty)      (lifted, then moved forward: "retracción"/"recuperación")
    on the ground for u ∈ [1 − duty, 1)    (pushing the body forward: "avance")

so every leg swings exactly once per cycle. The source figures are kept as data in
:attr:`Gait.states` (equal-length states); the tests check that the offsets/duty reproduce them.

* :data:`TRIPOD` — seed 002 Fig. 3 (hexapod, legs ``L1``…``L6``): six states starting from legs
  1, 3, 5 on the ground and 2, 4, 6 lifted. 1 advance of 1-3-5; 2 recovery of 2-4-6 (θ1 → 0);
  3 transition (2-4-6 down, then 1-3-5 up); 4 advance of 2-4-6; 5 recovery of 1-3-5;
  6 transition. Hence legs 2, 4, 6: offset 0, legs 1, 3, 5: offset 1/2, duty 2/3.
* :data:`QUADRUPED_FIG8` — seed 003 Fig. 8 as printed (legs ``FL, FR, RL, RR`` = the paper's
  PDI, PDD, PTI, PTD): diagonal pairs alternate, FL+RR retract while RL+FR push, then the
  reverse. The printed four "tiempos" are two cycles of this 2-beat (trot-like) sequence.
* :data:`QUADRUPED_WALK` — the 4-beat walk of seed 003's text: "the four legs out of phase by
  exactly a quarter of the cycle". Fig. 8 and the text disagree (Fig. 8 has diagonal partners in
  phase); we keep Fig. 8's pairing — FL and RR swing in one half-cycle, RL and FR in the other —
  and split each pair by a quarter cycle. Of the orders that do so, FL → RR → FR → RL is the
  lateral-sequence walk (LH, LF, RH, RF) that a walking dog — the animal the paper copies — uses,
  and the only one of all six 4-beat orders that keeps the centre inside the support triangle
  with the feet sliding back evenly (margin ≥ 0, zero only at the beat boundaries for duty 3/4).
  Offsets FL 0, RR 1/4, FR 1/2, RL 3/4; duty 3/4.

Support polygon and stability margin: :mod:`legcore.support_polygon`. Seed 002's support
triangle of the tripod: :mod:`legcore.tripod_stability`.

Units: m and rad (any consistent length unit works for the geometric functions).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "GAITS",
    "Gait",
    "GaitState",
    "QUADRUPED_FIG8",
    "QUADRUPED_WALK",
    "TRIPOD",
    "gait_phase",
    "leg_phase",
    "support_flags",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


# ----------------------------------------------------------------------------------------------
# Gait sequences
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class GaitState:
    """One state of a source figure's gait table (all states of a gait last equally long).

    ``support``: legs on the ground during the state (in a transition both tripods touch the
    ground: the lifted ones are put down before the others are lifted); ``moving``: legs whose
    joints move during it; ``action``: what happens, in words (with the paper's term).
    """

    name: str
    support: frozenset[str]
    moving: frozenset[str]
    action: str


@dataclass(frozen=True)
class Gait:
    """A periodic gait: per-leg lift-off phase ``offsets`` (fractions of the cycle, [0, 1)) and the
    stance fraction ``duty`` (0 < duty < 1), plus the source figure's state table."""

    name: str
    legs: tuple[str, ...]
    offsets: tuple[float, ...]
    duty: float
    states: tuple[GaitState, ...] = ()
    source: str = ""

    def __post_init__(self) -> None:
        if len(self.offsets) != len(self.legs):
            raise ValueError(
                f"offsets: {len(self.offsets)} values for {len(self.legs)} legs {self.legs}"
            )
        if len(set(self.legs)) != len(self.legs):
            raise ValueError(f"legs: names must be unique, got {self.legs}")
        if not all(0.0 <= o < 1.0 for o in self.offsets):
            raise ValueError(f"offsets: must lie in [0, 1), got {self.offsets}")
        if not 0.0 < self.duty < 1.0:
            raise ValueError(f"duty: stance fraction must be in (0, 1), got {self.duty}")

    @property
    def n_legs(self) -> int:
        return len(self.legs)

    def with_duty(self, duty: float) -> Gait:
        """The same sequence with another stance fraction (e.g. > 3/4 for a 4-beat walk with
        four-leg overlap); the state table is dropped when it no longer applies."""
        states = self.states if duty == self.duty else ()
        return Gait(self.name, self.legs, self.offsets, duty, states, self.source)


def gait_phase(t: ArrayLike, period: float, t0: float = 0.0) -> FloatArray:
    """Cycle phase ``((t − t0) / period) mod 1`` (same shape as ``t``; t, t0, period in s)."""
    if not (np.isfinite(period) and period > 0.0):
        raise ValueError(f"period: must be a positive number of seconds, got {period}")
    return np.mod((np.asarray(t, dtype=float) - t0) / period, 1.0)


def leg_phase(gait: Gait, phase: ArrayLike) -> FloatArray:
    """Leg-local phase ``u = (φ − offset) mod 1``, shape ``phase.shape + (n_legs,)``.

    ``u < 1 − duty``: in the air (``u / (1 − duty)`` is the swing progress);
    otherwise on the ground (``(u − (1 − duty)) / duty`` is the stance progress).
    """
    phi = np.asarray(phase, dtype=float)
    return np.mod(phi[..., None] - np.asarray(gait.offsets), 1.0)


def support_flags(gait: Gait, phase: ArrayLike) -> BoolArray:
    """True where a leg is on the ground, shape ``phase.shape + (n_legs,)`` (legs in
    ``gait.legs`` order). ``phase`` is the cycle phase in [0, 1) (see :func:`gait_phase`)."""
    return leg_phase(gait, phase) >= 1.0 - gait.duty - 1e-12


def _fs(*names: str) -> frozenset[str]:
    return frozenset(names)


_HEX = ("L1", "L2", "L3", "L4", "L5", "L6")
_A = _fs("L1", "L3", "L5")
_B = _fs("L2", "L4", "L6")

TRIPOD = Gait(
    name="tripod",
    legs=_HEX,
    offsets=(0.5, 0.0, 0.5, 0.0, 0.5, 0.0),
    duty=2.0 / 3.0,
    states=(
        GaitState(
            "1 advance",
            _A,
            _A,
            "1, 3, 5 on the ground push back (θ1,1 and θ1,3 by −Δθ1, "
            "θ1,5 by +Δθ1): the body advances; 2, 4, 6 stay lifted",
        ),
        GaitState("2 recovery", _A, _B, "2, 4, 6 (in the air) return to θ1 = 0"),
        GaitState(
            "3 transition", _fs(*_HEX), _fs(*_HEX), "2, 4, 6 are put down, then 1, 3, 5 lifted"
        ),
        GaitState("4 advance", _B, _B, "2, 4, 6 on the ground push back; 1, 3, 5 stay lifted"),
        GaitState("5 recovery", _B, _A, "1, 3, 5 (in the air) return to θ1 = 0"),
        GaitState(
            "6 transition", _fs(*_HEX), _fs(*_HEX), "1, 3, 5 are put down, then 2, 4, 6 lifted"
        ),
    ),
    source="seed 002 Fig. 3 (six-state tripod cycle)",
)

_Q = ("FL", "FR", "RL", "RR")

QUADRUPED_FIG8 = Gait(
    name="quadruped_fig8",
    legs=_Q,
    offsets=(0.0, 0.5, 0.5, 0.0),
    duty=0.5,
    states=(
        GaitState(
            "tiempo 1",
            _fs("FR", "RL"),
            _fs(*_Q),
            "retracción PDI (FL) and PTD (RR); avance PTI (RL) and PDD (FR)",
        ),
        GaitState(
            "tiempo 2",
            _fs("FL", "RR"),
            _fs(*_Q),
            "avance PDI (FL) and PTD (RR); retracción PTI (RL) and PDD (FR)",
        ),
    ),
    source="seed 003 Fig. 8 as printed (its tiempos 3, 4 repeat 1, 2)",
)

QUADRUPED_WALK = Gait(
    name="quadruped_walk",
    legs=_Q,
    offsets=(0.0, 0.5, 0.75, 0.25),
    duty=0.75,
    states=(
        GaitState("beat 1", _fs("FR", "RL", "RR"), _fs(*_Q), "FL (PDI) swings; others push"),
        GaitState("beat 2", _fs("FL", "FR", "RL"), _fs(*_Q), "RR (PTD) swings; others push"),
        GaitState("beat 3", _fs("FL", "RL", "RR"), _fs(*_Q), "FR (PDD) swings; others push"),
        GaitState("beat 4", _fs("FL", "FR", "RR"), _fs(*_Q), "RL (PTI) swings; others push"),
    ),
    source="seed 003 text (quarter-cycle offsets) with Fig. 8's diagonal pairing per half cycle",
)


GAITS: dict[str, Gait] = {g.name: g for g in (TRIPOD, QUADRUPED_WALK, QUADRUPED_FIG8)}
"""The built-in gaits by name (``LeggedRobot.meta["gait"]`` names the catalog robots' default)."""
