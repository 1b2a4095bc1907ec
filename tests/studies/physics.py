"""Independent physical checks of decoded motions (Pinocchio, per sample; test-only loops).

``energy_variation(robot, q, qd)``: the total variation ``Σ_k |E(t_{k+1}) − E(t_k)|`` of a
fixed-base chain's mechanical energy ``E = T + V`` (kinetic + potential, Pinocchio). With no
external force doing work, ``Σ_i τ_i q̇_i = dE/dt``, so the mechanical energy a study reports,
``Σ_i ∫ |τ_i q̇_i| dt``, is at least this bound: the gravity (and inertia) bound of the motion.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from legcore.robots import Robot


def mechanical_energy(robot: Robot, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """(K,) J: kinetic + potential energy of the chain at each sample."""
    model, data = robot.model, robot.data()
    out = np.empty(q.shape[0])
    for k in range(q.shape[0]):
        out[k] = pin.computeKineticEnergy(model, data, q[k], qd[k]) + pin.computePotentialEnergy(
            model, data, q[k]
        )
    return out


def energy_variation(robot: Robot, q: np.ndarray, qd: np.ndarray) -> float:
    """Total variation (J) of the chain's mechanical energy over the samples."""
    return float(np.abs(np.diff(mechanical_energy(robot, q, qd))).sum())


def tool_positions(robot: Robot, q: np.ndarray) -> np.ndarray:
    """(K, 3) m: the chain's tool frame by Pinocchio (independent of legcore's fast path)."""
    model, data = robot.model, robot.data()
    out = np.empty((q.shape[0], 3))
    for k in range(q.shape[0]):
        pin.framesForwardKinematics(model, data, q[k])
        out[k] = data.oMf[robot.tool_frame].translation
    return out
