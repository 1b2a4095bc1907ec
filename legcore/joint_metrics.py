"""Per-joint and per-trajectory metrics of seed 000 (Tables 2–5), over batches of trajectories.

Inputs: time grid ``t`` (K,) or (..., K) s; ``q``, ``qd``, ``qdd``, ``jerk``, ``tau`` (..., K, n)
in rad, rad/s, rad/s², rad/s³, N·m (for a prismatic joint read m, m/s, …, N); optional tool/foot
positions ``tool_pos`` (..., K, 3) m. ``qd``/``qdd``/``jerk`` left out are obtained by finite
differences of the next lower derivative (second order inside, first order at the ends, as
``numpy.gradient``) — pass the analytic ones when you have them.

Per joint i (shape (..., n)):

====================  =================================  ============================
field                 definition                         unit
====================  =================================  ============================
``theta``             θ = Σ_k |q_{k+1} − q_k|  (eq 4)     rad
``displacement``      θ_min = |q_K − q_1|  (eq 3)         rad
``omega_max``         max_k |q̇_k|                         rad/s
``alpha_max``         max_k q̈_k  (largest acceleration)  rad/s²
``alpha_min``         min_k q̈_k  (signed; seed prints |α_min|, "max deceleration")  rad/s²
``jerk_max``          max_k |q⃛_k|                         rad/s³
``tau_max``           max_k |τ_k|                         N·m
``tau_sq``            T_cuad = ∫ τ² dt  (trapezoid)      N²·m²·s
``energy``            E = ∫ |τ q̇| dt  (trapezoid)        J
====================  =================================  ============================

Per trajectory (shape (...,)): ``theta_total`` θ_T = Σ_i θ_i (rad), ``tau_sq_total`` (N²·m²·s),
``path_length`` D = Σ_k ‖p_{k+1} − p_k‖ of the tool/foot (m, NaN without ``tool_pos``),
``energy_total`` Σ_i E_i (J), ``duration`` t_K − t_1 (s).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.energy import integrate, mechanical_energy, validate_time_grid

__all__ = ["JointMetrics", "MetricRow", "derivative", "joint_metrics"]

FloatArray = NDArray[np.float64]

# (field, label as in seed 000, unit)
_JOINT_ROWS: tuple[tuple[str, str, str], ...] = (
    ("theta", "θ", "rad"),
    ("displacement", "θ_min", "rad"),
    ("omega_max", "ω_max", "rad/s"),
    ("alpha_max", "α_max", "rad/s²"),
    ("alpha_min", "α_min", "rad/s²"),
    ("jerk_max", "Jerk", "rad/s³"),
    ("tau_max", "τ_max", "N·m"),
    ("tau_sq", "T_cuad", "N²·m²·s"),
    ("energy", "E", "J"),
)
_TOTAL_ROWS: tuple[tuple[str, str, str], ...] = (
    ("theta_total", "θ_T", "rad"),
    ("tau_sq_total", "T_cuad", "N²·m²·s"),
    ("path_length", "D_PFE", "m"),
    ("energy_total", "E", "J"),
    ("duration", "T", "s"),
)


@dataclass(frozen=True)
class MetricRow:
    """One table row: ``key`` (field name), ``label`` (seed notation), ``unit``, and either
    ``per_joint`` values (joint 1..n) or a single ``total``."""

    key: str
    label: str
    unit: str
    per_joint: tuple[float, ...] | None = None
    total: float | None = None


@dataclass(frozen=True, eq=False)
class JointMetrics:
    """Seed 000 metric set; per-joint fields (..., n), per-trajectory fields (...,).

    See the module docstring for definitions and units.
    """

    theta: FloatArray
    displacement: FloatArray
    omega_max: FloatArray
    alpha_max: FloatArray
    alpha_min: FloatArray
    jerk_max: FloatArray
    tau_max: FloatArray
    tau_sq: FloatArray
    energy: FloatArray
    theta_total: FloatArray
    tau_sq_total: FloatArray
    path_length: FloatArray
    energy_total: FloatArray
    duration: FloatArray

    @property
    def batch_shape(self) -> tuple[int, ...]:
        """Leading batch shape (``()`` for a single trajectory)."""
        return tuple(self.theta_total.shape)

    def as_dict(self) -> dict[str, FloatArray]:
        """All fields by name."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    def as_table(self, index: int | tuple[int, ...] = ()) -> list[MetricRow]:
        """Rows for one trajectory (``index`` into the batch): the per-joint rows of seed 000
        Table 2 followed by the per-trajectory rows of its Table 3."""
        idx = (index,) if isinstance(index, int) else tuple(index)
        if len(idx) != len(self.batch_shape):
            raise ValueError(
                f"index: need {len(self.batch_shape)} indices for batch shape "
                f"{self.batch_shape}, got {idx}"
            )
        rows = [
            MetricRow(key, label, unit, per_joint=tuple(float(v) for v in getattr(self, key)[idx]))
            for key, label, unit in _JOINT_ROWS
        ]
        rows += [
            MetricRow(key, label, unit, total=float(getattr(self, key)[idx]))
            for key, label, unit in _TOTAL_ROWS
        ]
        return rows


def derivative(y: ArrayLike, t: ArrayLike) -> FloatArray:
    """dy/dt of ``y`` (..., K, n) on ``t`` (K,) or (..., K): second-order central differences on
    a possibly non-uniform grid inside, first-order one-sided at both ends (``numpy.gradient``
    with ``edge_order=1``)."""
    y_a = np.asarray(y, dtype=np.float64)
    if y_a.ndim < 2:
        raise ValueError(f"y: expected shape (..., K, n), got {y_a.shape}")
    K = y_a.shape[-2]
    t_a = validate_time_grid(t, K)[..., None]  # (..., K, 1)
    out = np.empty(np.broadcast_shapes(y_a.shape, t_a.shape))
    out[..., 0, :] = (y_a[..., 1, :] - y_a[..., 0, :]) / (t_a[..., 1, :] - t_a[..., 0, :])
    out[..., -1, :] = (y_a[..., -1, :] - y_a[..., -2, :]) / (t_a[..., -1, :] - t_a[..., -2, :])
    if K > 2:
        h1 = t_a[..., 1:-1, :] - t_a[..., :-2, :]
        h2 = t_a[..., 2:, :] - t_a[..., 1:-1, :]
        out[..., 1:-1, :] = (
            h1**2 * y_a[..., 2:, :] - h2**2 * y_a[..., :-2, :] + (h2**2 - h1**2) * y_a[..., 1:-1, :]
        ) / (h1 * h2 * (h1 + h2))
    return out


def joint_metrics(
    t: ArrayLike,
    q: ArrayLike,
    tau: ArrayLike,
    *,
    qd: ArrayLike | None = None,
    qdd: ArrayLike | None = None,
    jerk: ArrayLike | None = None,
    tool_pos: ArrayLike | None = None,
) -> JointMetrics:
    """Seed 000 metrics of trajectories ``q`` (..., K, n) with joint torques ``tau`` (same shape).

    ``t`` (K,) or (..., K) s. Missing ``qd``/``qdd``/``jerk`` are differentiated numerically
    (:func:`derivative`); ``tool_pos`` (..., K, 3) m gives the path length D (NaN otherwise).
    """
    q_a = np.asarray(q, dtype=np.float64)
    if q_a.ndim < 2:
        raise ValueError(f"q: expected shape (..., K, n), got {q_a.shape}")
    K = q_a.shape[-2]
    t_a = validate_time_grid(t, K)
    tau_a = np.asarray(tau, dtype=np.float64)
    if tau_a.shape != q_a.shape:
        raise ValueError(f"tau: shape must equal q's {q_a.shape}, got {tau_a.shape}")

    def given(name: str, x: ArrayLike | None, lower: FloatArray) -> FloatArray:
        if x is None:
            return derivative(lower, t_a)
        a = np.asarray(x, dtype=np.float64)
        if a.shape != q_a.shape:
            raise ValueError(f"{name}: shape must equal q's {q_a.shape}, got {a.shape}")
        return a

    qd_a = given("qd", qd, q_a)
    qdd_a = given("qdd", qdd, qd_a)
    jerk_a = given("jerk", jerk, qdd_a)

    theta = np.sum(np.abs(np.diff(q_a, axis=-2)), axis=-2)
    tau_sq = integrate(tau_a**2, t_a)
    energy = mechanical_energy(qd_a, tau_a, t_a).per_joint
    batch = q_a.shape[:-2]
    if tool_pos is None:
        path_length = np.full(batch, np.nan)
    else:
        p = np.asarray(tool_pos, dtype=np.float64)
        if p.shape != (*batch, K, 3):
            raise ValueError(f"tool_pos: expected shape {(*batch, K, 3)}, got {p.shape}")
        path_length = np.sum(np.linalg.norm(np.diff(p, axis=-2), axis=-1), axis=-1)
    duration = np.broadcast_to(t_a[..., -1] - t_a[..., 0], batch).copy()
    return JointMetrics(
        theta=theta,
        displacement=np.abs(q_a[..., -1, :] - q_a[..., 0, :]),
        omega_max=np.max(np.abs(qd_a), axis=-2),
        alpha_max=np.max(qdd_a, axis=-2),
        alpha_min=np.min(qdd_a, axis=-2),
        jerk_max=np.max(np.abs(jerk_a), axis=-2),
        tau_max=np.max(np.abs(tau_a), axis=-2),
        tau_sq=tau_sq,
        energy=energy,
        theta_total=theta.sum(axis=-1),
        tau_sq_total=tau_sq.sum(axis=-1),
        path_length=path_length,
        energy_total=energy.sum(axis=-1),
        duration=duration,
    )
