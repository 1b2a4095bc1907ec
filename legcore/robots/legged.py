"""Multi-legged robots: a rigid body carrying several serial legs.

Each leg is an ordinary serial :class:`~legcore.robots.model.Robot` whose base frame is the hip;
``Leg.hip`` places that base in the body frame (x forward, y left, z up; m). Studies that need a
floating-base model work leg by leg on these chains plus the body geometry here.

A legged robot built from one URDF (:mod:`legcore.robots.urdf_legs`) also keeps its ``spec``
and its whole Pinocchio ``model`` with a free-flyer root (catalog robots have neither).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from legcore.robots.model import Robot
from legcore.robots.spec import URDFRobotSpec

__all__ = ["Leg", "LeggedRobot"]


@dataclass(frozen=True, eq=False)
class Leg:
    """One leg: its serial chain and the hip placement ``hip`` (4×4) in the body frame."""

    name: str
    robot: Robot
    hip: NDArray[np.float64]

    def foot_in_body(self, p_leg: NDArray[np.float64]) -> NDArray[np.float64]:
        """Map foot positions (…, 3) from the leg base frame to the body frame (m)."""
        p_leg = np.asarray(p_leg, dtype=float)
        return p_leg @ self.hip[:3, :3].T + self.hip[:3, 3]

    def foot_in_leg(self, p_body: NDArray[np.float64]) -> NDArray[np.float64]:
        """Map foot positions (…, 3) from the body frame to the leg base frame (m)."""
        p_body = np.asarray(p_body, dtype=float)
        return (p_body - self.hip[:3, 3]) @ self.hip[:3, :3]


@dataclass(frozen=True, eq=False)
class LeggedRobot:
    """A body of size ``body_size`` (length x, width y, height z; m) and mass ``body_mass`` (kg)
    carrying ``legs``. ``meta`` holds source notes (e.g. servo mappings) for studies and docs.
    ``spec``: the URDF specification it was built from; ``model``: the whole robot with a
    free-flyer root (``pinocchio.Model``, read-only) — both None for catalog robots."""

    name: str
    legs: tuple[Leg, ...]
    body_size: tuple[float, float, float]
    body_mass: float = 0.0
    meta: dict[str, object] | None = None
    spec: URDFRobotSpec | None = None
    model: pin.Model | None = None

    def leg(self, name: str) -> Leg:
        for leg in self.legs:
            if leg.name == name:
                return leg
        raise KeyError(f"no leg named {name!r}; legs are {[leg.name for leg in self.legs]}")

    @property
    def n_legs(self) -> int:
        return len(self.legs)
