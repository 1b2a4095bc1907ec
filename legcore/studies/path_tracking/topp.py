"""The time-optimal parametrisation of a fixed joint path: TOPP-RA (``toppra``, the field's
standard), rest to rest, under joint speed, acceleration and torque limits.

A ``path_tracking`` task fixes the joints as functions of arc length, q = Q(σ) (rad; σ in m,
:class:`~legcore.studies.path_tracking.joints.JointPath`). Along it, with x = σ̇² and
u = σ̈ (m²/s², m/s²)::

    q̇ = Q′ σ̇,   q̈ = Q′ u + Q″ x,   τ = M(Q) Q′ u + (M(Q) Q″ + C(Q, Q′) Q′) x + g(Q)

so the acceleration and torque limits are linear in (u, x) and the speed limit bounds x. TOPP-RA
(Pham & Pham, IEEE T-RO 2018) finds, on a grid σ_0 = 0 < … < σ_N = L, the largest x at every
gridpoint with u constant on every interval (x linear in σ there: the form of
:func:`~legcore.studies.path_tracking.timelaw.profile_law`) — the minimum time T = Σ 2 Δσ_i /
(σ̇_i + σ̇_{i+1}) for that grid, which falls to the true minimum as the grid is refined.

The limits are imposed at *both ends of every interval*, each end with its own interval's side
of Q″ (the path's curvature, so Q″, jumps where two segments join; a join that is a gridpoint
is then right on both sides) — TOPP-RA's "interpolation" discretisation, written here with
one-sided derivatives. Between gridpoints the limits can still be exceeded by O(Δσ²); the
caller checks the profile on a dense resampling and tightens them (``scale``). The torque
coefficients come from one batched RNEA call each (:func:`legcore.dynamics.inverse_dynamics`):
a = τ(Q, 0, Q′) − g, b = τ(Q, Q′, Q″) − g, c = g = τ(Q, 0, 0).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import toppra
import toppra.algorithm
import toppra.constraint
from numpy.typing import NDArray
from toppra.interpolator import AbstractGeometricPath

from legcore.dynamics import inverse_dynamics
from legcore.robots.model import Robot
from legcore.studies.path_tracking.joints import JointPath

__all__ = ["TimeOptimal", "time_optimal"]

FloatArray = NDArray[np.float64]

logging.getLogger("toppra").setLevel(logging.WARNING)  # it logs every solve at INFO

_LEFT = 1e-12  # × L: a left-hand limit of Q's derivatives is taken this far before a knot


@dataclass(frozen=True)
class TimeOptimal:
    """A time-optimal profile on a grid: ``grid`` (N + 1,) m, ``speed`` σ̇ (N + 1,) m/s at its
    gridpoints (0 at both ends), ``T`` s its duration, ``scale`` the factor (≤ 1) the limits
    were multiplied by to get it."""

    grid: FloatArray
    speed: FloatArray
    T: float
    scale: float


class _Geometry(AbstractGeometricPath):
    """``toppra``'s view of Q(σ) (only its interval and dof are read: the constraints below
    evaluate Q themselves, one-sided)."""

    def __init__(self, joints: JointPath) -> None:
        self._joints = joints

    def __call__(self, path_positions: FloatArray, order: int = 0) -> FloatArray:
        return np.asarray(self._joints.poly(np.asarray(path_positions, dtype=float), order))

    @property
    def dof(self) -> int:
        return int(self._joints.q.shape[1])

    @property
    def path_interval(self) -> FloatArray:
        return np.array([0.0, self._joints.length])

    @property
    def waypoints(self) -> None:
        return None


def _one_sided(joints: JointPath, grid: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Q, Q′, Q″ (3, N + 1, n) at the gridpoints from the right (the interval after each; the
    last from the left) and from the left (the interval before each; the first from the
    right)."""
    L = joints.length
    right = np.stack([joints.poly(grid, nu) for nu in range(3)])
    s_left = np.concatenate([grid[:1], grid[1:] - _LEFT * L])
    left = np.stack([joints.poly(s_left, nu) for nu in range(3)])
    left[0] = right[0]  # Q itself is continuous
    right[:, -1] = left[:, -1]
    return right, left


def _coefficients(robot: Robot, Q: FloatArray, qdd_max: FloatArray, tau_max: FloatArray
                  ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(a, b, c) of v = a u + b x + c with v = (q̈ of the joints with a finite acceleration
    limit, τ of those with a finite torque limit) at the points of ``Q`` (3, P, n)."""
    q, q1, q2 = Q
    z = np.zeros_like(q)
    g = inverse_dynamics(robot, q[None], z[None], z[None])[0]
    a_tau = inverse_dynamics(robot, q[None], z[None], q1[None])[0] - g
    b_tau = inverse_dynamics(robot, q[None], q1[None], q2[None])[0] - g
    acc, tau = np.isfinite(qdd_max), np.isfinite(tau_max)
    a = np.concatenate([q1[:, acc], a_tau[:, tau]], axis=1)
    b = np.concatenate([q2[:, acc], b_tau[:, tau]], axis=1)
    c = np.concatenate([np.zeros_like(q1[:, acc]), g[:, tau]], axis=1)
    return a, b, c


class _Limits(toppra.constraint.LinearConstraint):
    """Joint speed, acceleration and torque limits of Q on a grid, imposed at both ends of
    every interval with that interval's one-sided derivatives (module docstring)."""

    def __init__(self, robot: Robot, joints: JointPath, qd_max: FloatArray,
                 qdd_max: FloatArray, tau_max: FloatArray) -> None:
        super().__init__()
        self.set_discretization_type(toppra.constraint.DiscretizationType.Interpolation)
        self.identical = True
        self._robot, self._joints = robot, joints
        self._qd_max, self._qdd_max, self._tau_max = qd_max, qdd_max, tau_max

    def compute_constraint_params(self, path: AbstractGeometricPath, gridpoints: FloatArray,
                                  *args: object, **kwargs: object) -> tuple[object, ...]:
        grid = np.asarray(gridpoints, dtype=float)
        right, left = _one_sided(self._joints, grid)
        lim = np.concatenate([self._qdd_max[np.isfinite(self._qdd_max)],
                              self._tau_max[np.isfinite(self._tau_max)]])
        m = lim.size
        # x ≤ (q̇_max / |Q′|)² on both sides of every gridpoint
        with np.errstate(divide="ignore"):
            cap = np.minimum(np.min((self._qd_max / np.abs(right[1])) ** 2, axis=1),
                             np.min((self._qd_max / np.abs(left[1])) ** 2, axis=1))
        xbound = np.stack([np.zeros_like(cap), np.minimum(cap, 1e12)], axis=1)
        if m == 0:
            return None, None, None, None, None, None, xbound
        aR, bR, cR = _coefficients(self._robot, right, self._qdd_max, self._tau_max)
        aL, bL, cL = _coefficients(self._robot, left, self._qdd_max, self._tau_max)
        N = grid.size - 1
        delta = np.diff(grid)
        # row i: the limits at σ_i (its interval's side) in (u_i, x_i), and at σ_{i+1} (the
        # same interval's side) with x_{i+1} = x_i + 2 Δσ_i u_i
        a = np.zeros((N + 1, 2 * m))
        b = np.zeros((N + 1, 2 * m))
        c = np.zeros((N + 1, 2 * m))
        a[:, :m], b[:, :m], c[:, :m] = aR, bR, cR
        a[:-1, m:] = aL[1:] + 2.0 * delta[:, None] * bL[1:]
        b[:-1, m:], c[:-1, m:] = bL[1:], cL[1:]
        a[-1, m:], b[-1, m:], c[-1, m:] = aL[-1], bL[-1], cL[-1]
        F1 = np.vstack([np.eye(m), -np.eye(m)])
        F = np.zeros((4 * m, 2 * m))
        F[: 2 * m, :m] = F1
        F[2 * m:, m:] = F1
        g1 = np.concatenate([lim, lim])
        return a, b, c, F, np.concatenate([g1, g1]), None, xbound


def time_optimal(robot: Robot, joints: JointPath, grid: FloatArray, qd_max: FloatArray,
                 qdd_max: FloatArray, tau_max: FloatArray, scale: float = 1.0
                 ) -> TimeOptimal | None:
    """The rest-to-rest time-optimal profile of ``joints`` on ``grid`` (N + 1,) m (from 0 to
    its length, strictly increasing) under joint speed ``qd_max`` (rad/s), acceleration
    ``qdd_max`` (rad/s²) and torque ``tau_max`` (N·m) limits (n,) — inf: none — each
    multiplied by ``scale``; None when no profile exists (a torque limit below what gravity
    alone asks somewhere on the path, or the path not even crawlable)."""
    grid = np.asarray(grid, dtype=float)
    limits = _Limits(robot, joints, scale * np.asarray(qd_max, dtype=float),
                     scale * np.asarray(qdd_max, dtype=float),
                     scale * np.asarray(tau_max, dtype=float))
    algorithm = toppra.algorithm.TOPPRA([limits], _Geometry(joints), gridpoints=grid,
                                        parametrizer="ParametrizeConstAccel")
    _, sd, _ = algorithm.compute_parameterization(0.0, 0.0)
    if sd is None or not np.all(np.isfinite(sd)):
        return None
    speed = np.maximum(np.asarray(sd, dtype=float), 0.0)
    speed[0] = speed[-1] = 0.0
    pair = speed[:-1] + speed[1:]
    if np.any(pair <= 0.0):
        return None
    T = float(np.sum(2.0 * np.diff(grid) / pair))
    return TimeOptimal(grid=grid, speed=speed, T=T, scale=scale)
