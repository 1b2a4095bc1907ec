"""Batched inverse dynamics of serial chains: recursive Newton–Euler (RNEA) compiled with numba.

``inverse_dynamics(robot, q, qd, qdd)`` returns the joint torques (N·m; N for prismatic joints)
that realise the motion ``q, qd, qdd`` (rad, rad/s, rad/s²; shapes ``(..., n)``, e.g. a batch of
trajectories ``(B, K, n)``), including gravity (``robot.chain.gravity``, from the Pinocchio model)
and the reflected rotor inertia ``armature · qdd`` (armature = Jm·G²). With ``friction=True`` the
joint friction of the motors is added (:func:`joint_friction`).

The fast path runs on :class:`~legcore.robots.model.Chain` (taken from the Pinocchio model, so
standard DH, modified DH and URDF robots share it) and is tested against
:func:`inverse_dynamics_reference`, a plain loop over ``pinocchio.rnea`` (agreement ~1e-14 N·m).
Implementation notes: each joint frame is first rotated (once per robot) so that its axis is the
local z axis (identity for DH robots); the kernel is scalar component-wise code in a numba loop
over the flattened samples (:mod:`legcore.rnea_kernel`); the sines/cosines of a block of
samples are computed in one vectorisable loop (:func:`legcore.sincos._sincos`). Large batches
(≥ 131072 samples) run on ``numba.get_num_threads()`` threads in chunks; results are
bit-identical to the serial kernel.
Multi-process workers should set ``NUMBA_NUM_THREADS=1`` (or pass ``parallel=False``) so that
threads do not oversubscribe the cores.

Recursion (all vectors in the moving joint frame i; ``E_i`` = rotation of frame i in frame i-1,
``d_i`` = origin of frame i in frame i-1, ``a_i`` = unit joint axis)::

    ω_i  = E_iᵀ ω_{i-1} + a_i q̇_i                                 (revolute)
    ω̇_i  = E_iᵀ ω̇_{i-1} + (E_iᵀ ω_{i-1}) × a_i q̇_i + a_i q̈_i
    v̇_i  = E_iᵀ (v̇_{i-1} + ω̇_{i-1} × d_i + ω_{i-1} × (ω_{i-1} × d_i))
           [+ 2 ω_i × a_i q̇_i + a_i q̈_i for a prismatic joint]    v̇_0 = −g
    F_i  = m_i (v̇_i + ω̇_i × c_i + ω_i × (ω_i × c_i)),   N_i = I_i ω̇_i + ω_i × I_i ω_i
    f_i  = F_i + E_{i+1} f_{i+1}
    n_i  = N_i + c_i × F_i + E_{i+1} n_{i+1} + d_{i+1} × E_{i+1} f_{i+1}
    τ_i  = a_iᵀ n_i (revolute) or a_iᵀ f_i (prismatic)  + armature_i q̈_i
"""

from __future__ import annotations

import numba
import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from legcore.rnea_kernel import _kernel_chain, _rnea_parallel, _rnea_range
from legcore.robots.model import Robot

__all__ = [
    "COULOMB_DEAD_BAND",
    "inverse_dynamics",
    "inverse_dynamics_reference",
    "joint_friction",
]

FloatArray = NDArray[np.float64]

# Samples per work chunk of the parallel kernel: each chunk allocates its own scratch arrays once.
_CHUNK = 2048
# Below this many samples the serial kernel is used (thread start-up would dominate).
_PARALLEL_MIN = 64 * _CHUNK  # 131072


def _as_motion(robot: Robot, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> tuple[
    FloatArray, FloatArray, FloatArray
]:
    """Validate ``q, qd, qdd`` (same shape ``(..., nq)``) and return them as float arrays."""
    arrays = []
    for name, x in (("q", q), ("qd", qd), ("qdd", qdd)):
        a = np.asarray(x, dtype=np.float64)
        if a.ndim == 0 or a.shape[-1] != robot.nq:
            raise ValueError(
                f"{name}: last axis must have length nq = {robot.nq} for {robot.name!r}, "
                f"got shape {a.shape}"
            )
        arrays.append(a)
    if not arrays[0].shape == arrays[1].shape == arrays[2].shape:
        raise ValueError(
            f"q, qd, qdd: shapes must be equal, got {arrays[0].shape}, {arrays[1].shape}, "
            f"{arrays[2].shape}"
        )
    return arrays[0], arrays[1], arrays[2]


#: Joint speeds (rad/s or m/s) at or below which a joint is at rest for Coulomb friction.
COULOMB_DEAD_BAND = 1e-9


def joint_friction(robot: Robot, qd: ArrayLike) -> FloatArray:
    """Joint-side friction torque (N·m) of the motors+gears at joint speeds ``qd`` (..., n) rad/s.

    ``τ_f = G²·B·q̇ + |G|·Tc(q̇)`` with ``Tc = Tc_pos`` for q̇ > 0, ``Tc_neg`` (≤ 0) for q̇ < 0 and 0
    at rest, i.e. for ``|q̇| ≤ COULOMB_DEAD_BAND`` (1e-9 rad/s: a joint that stops or reverses
    has a speed of round-off size there, whose sign would switch the full Coulomb torque on
    and off) — the torque the actuator must *add* to overcome friction (roboticstoolbox
    ``Link.friction`` with the opposite sign; see ``robots/data/puma560.json`` "conventions").
    ``B`` (N·m·s/rad) and ``Tc`` (N·m) are motor-side values from ``robot.motors``; joints without
    a motor have zero friction.
    """
    qd = np.asarray(qd, dtype=np.float64)
    if qd.ndim == 0 or qd.shape[-1] != robot.nq:
        raise ValueError(f"qd: last axis must have length nq = {robot.nq}, got shape {qd.shape}")
    m = robot.motors
    band = COULOMB_DEAD_BAND
    coulomb = np.where(qd > band, m.Tc_pos, np.where(qd < -band, m.Tc_neg, 0.0))
    return m.G**2 * m.B * qd + np.abs(m.G) * coulomb


def inverse_dynamics(
    robot: Robot,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    *,
    friction: bool = False,
    parallel: bool | None = None,
) -> FloatArray:
    """Joint torques (N·m, N for prismatic joints) for the motion ``q, qd, qdd``.

    ``q`` (rad or m), ``qd`` (rad/s), ``qdd`` (rad/s²): equal shapes ``(..., n)`` — one sample
    ``(n,)``, a trajectory ``(K, n)`` or a batch ``(B, K, n)``; returns the same shape. Includes
    gravity, rotor inertia (``armature · qdd``) and, with ``friction=True``,
    :func:`joint_friction`. ``parallel``: None picks the multi-threaded kernel for large batches;
    both kernels give bit-identical results.
    """
    q_a, qd_a, qdd_a = _as_motion(robot, q, qd, qdd)
    shape = q_a.shape
    n = robot.nq
    Q = np.ascontiguousarray(q_a.reshape(-1, n))
    QD = np.ascontiguousarray(qd_a.reshape(-1, n))
    QDD = np.ascontiguousarray(qdd_a.reshape(-1, n))
    tau = np.empty_like(Q)
    ch = _kernel_chain(robot)
    args = (
        Q,
        QD,
        QDD,
        ch.R,
        ch.p,
        ch.prismatic,
        ch.mass,
        ch.com,
        ch.I_com,
        ch.armature,
        ch.gravity,
        tau,
    )
    total = Q.shape[0]
    if parallel is None:
        parallel = total >= _PARALLEL_MIN and numba.get_num_threads() > 1
    if parallel:
        _rnea_parallel(*args, _CHUNK)
    else:
        _rnea_range(0, total, *args)
    out = tau.reshape(shape)
    if friction:
        out = out + joint_friction(robot, qd_a)
    return out


def inverse_dynamics_reference(
    robot: Robot,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    *,
    friction: bool = False,
) -> FloatArray:
    """Reference: a plain Python loop over ``pinocchio.rnea`` (includes armature; same I/O)."""
    q_a, qd_a, qdd_a = _as_motion(robot, q, qd, qdd)
    shape = q_a.shape
    n = robot.nq
    Q, QD, QDD = (np.ascontiguousarray(x.reshape(-1, n)) for x in (q_a, qd_a, qdd_a))
    tau = np.empty_like(Q)
    model, data = robot.model, robot.data()
    for s in range(Q.shape[0]):
        tau[s] = pin.rnea(model, data, Q[s], QD[s], QDD[s])
    out = tau.reshape(shape)
    if friction:
        out = out + joint_friction(robot, qd_a)
    return out
