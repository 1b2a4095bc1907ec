"""Energy models of a joint trajectory: mechanical (seed 000) and DC-motor electrical (seed 001).

Every model is a function of the sampled motion and torques over a time grid:
``q, qd, qdd, tau`` with shape ``(..., K, n)`` (rad, rad/s, rad/s², N·m) and ``t`` with shape
``(K,)`` — or ``(..., K)`` when the trajectories of a batch have different time grids — in s,
strictly increasing. ``tau`` is the joint-side torque the actuator delivers, as returned by
:func:`legcore.dynamics.inverse_dynamics` (it already includes the reflected rotor inertia
``Jm·G²·q̈`` and, with ``friction=True``, the gear/motor friction); the energy models add nothing
to it.

Integration over time is the trapezoidal rule on the samples,
``∫ y dt ≈ Σ_k (y_k + y_{k+1}) / 2 · (t_{k+1} − t_k)`` (:func:`integrate`), applied to the
*sampled* integrand (e.g. ``|τ ω|`` is taken per sample, then integrated).

Models (``ENERGY_MODELS``; each returns an :class:`EnergyResult`):

- ``mechanical``: ``E_i = ∫ |τ_i ω_i| dt`` (J) — seed 000 Tables 2–5 (power = torque × angular
  velocity, every watt counted whether the joint drives or brakes).
- ``positive_work``: ``E_i = ∫ max(τ_i ω_i, 0) dt`` (J) — braking is free, nothing recovered.
- ``torque_squared``: ``∫ τ_i² dt`` (N²·m²·s) — seed 000's T_cuad; not an energy.
- ``electrical``: DC motors through the gear, seed 001 eqs 9–14 (J)::

      τ_m = τ / G,   ω_m = G q̇                      (motor torque N·m, motor speed rad/s)
      I = τ_m / K_t,  V_e = K_e ω_m                   (eqs 9, 10)
      P = R I² + V_e I = R (τ / (G K_t))² + (K_e / K_t) τ q̇     (eqs 11–13, W)
      E_i = ∫ P_i dt                                   (eq 14)

  The gear is ideal (no efficiency loss); the sign of G cancels in ``V_e I``. A holding torque
  at rest costs ``R (τ/(G K_t))² T``. Only joints with electrical data
  (``robot.motors.electrical``) are counted; others are NaN per joint and left out of the total.
  By default (``regenerative=True``) the power is integrated as signed, exactly as eq 14 writes it
  (braking returns energy to the supply); ``regenerative=False`` clips each motor's power at 0.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.robots.model import MotorArrays, Robot

__all__ = [
    "ENERGY_MODELS",
    "ElectricalEnergy",
    "EnergyResult",
    "electrical_energy",
    "energy",
    "integrate",
    "joules_to_kwh",
    "kwh_to_joules",
    "mechanical_energy",
    "mechanical_power",
    "positive_work",
    "torque_squared",
    "validate_time_grid",
]

FloatArray = NDArray[np.float64]

J_PER_KWH = 3.6e6


def joules_to_kwh(E: ArrayLike) -> FloatArray:
    """Energy in kWh from J (1 kWh = 3.6·10⁶ J)."""
    return np.asarray(E, dtype=np.float64) / J_PER_KWH


def kwh_to_joules(E: ArrayLike) -> FloatArray:
    """Energy in J from kWh."""
    return np.asarray(E, dtype=np.float64) * J_PER_KWH


@dataclass(frozen=True, eq=False)
class EnergyResult:
    """An integrated quantity per joint and in total.

    ``per_joint`` (..., n), ``total`` (...,) = sum over the counted joints, ``power`` (..., K, n)
    the integrand sampled on the grid (W for energies), ``unit`` of ``per_joint``/``total``,
    ``joints`` (n,) bool mask of the joints counted in ``total`` (the others are NaN).
    """

    per_joint: FloatArray
    total: FloatArray
    power: FloatArray
    unit: str
    joints: NDArray[np.bool_]

    @property
    def total_kwh(self) -> FloatArray:
        """``total`` in kWh (only meaningful when ``unit == 'J'``)."""
        if self.unit != "J":
            raise ValueError(f"total_kwh: result unit is {self.unit!r}, not an energy in J")
        return joules_to_kwh(self.total)


@dataclass(frozen=True, eq=False)
class ElectricalEnergy(EnergyResult):
    """:class:`EnergyResult` of the DC-motor model plus its signals (NaN on non-electrical joints).

    ``current`` I (..., K, n) A, ``back_emf`` V_e (..., K, n) V, ``joule`` R I² (..., K, n) W,
    ``joule_energy`` ∫R I² dt (..., n) J (the part of ``per_joint`` lost in the windings).
    """

    current: FloatArray
    back_emf: FloatArray
    joule: FloatArray
    joule_energy: FloatArray


def validate_time_grid(t: ArrayLike, K: int) -> FloatArray:
    """Check a time grid ``t`` (K,) or (..., K) s: finite, strictly increasing, K >= 2."""
    t_a = np.asarray(t, dtype=np.float64)
    if t_a.ndim == 0 or t_a.shape[-1] != K:
        raise ValueError(f"t: last axis must have length K = {K} samples, got shape {t_a.shape}")
    if K < 2:
        raise ValueError("t: need at least 2 samples to integrate over time")
    if not np.all(np.isfinite(t_a)):
        raise ValueError("t: times must be finite")
    if np.any(np.diff(t_a, axis=-1) <= 0.0):
        raise ValueError("t: times must be strictly increasing")
    return t_a


def integrate(y: ArrayLike, t: ArrayLike) -> FloatArray:
    """Trapezoidal ``∫ y dt`` of ``y`` (..., K, n) over ``t`` (K,) or (..., K) s -> (..., n)."""
    y_a = np.asarray(y, dtype=np.float64)
    if y_a.ndim < 2:
        raise ValueError(f"y: expected shape (..., K, n), got {y_a.shape}")
    t_a = validate_time_grid(t, y_a.shape[-2])
    dt = np.diff(t_a, axis=-1)[..., None]  # (..., K-1, 1)
    return np.sum(0.5 * (y_a[..., 1:, :] + y_a[..., :-1, :]) * dt, axis=-2)


def _qd_tau(qd: ArrayLike, tau: ArrayLike) -> tuple[FloatArray, FloatArray]:
    qd_a = np.asarray(qd, dtype=np.float64)
    tau_a = np.asarray(tau, dtype=np.float64)
    if qd_a.shape != tau_a.shape:
        raise ValueError(f"qd, tau: shapes must be equal, got {qd_a.shape} and {tau_a.shape}")
    if qd_a.ndim < 2:
        raise ValueError(f"qd, tau: expected shape (..., K, n), got {qd_a.shape}")
    return qd_a, tau_a


def _result(power: FloatArray, t: ArrayLike, unit: str) -> EnergyResult:
    per_joint = integrate(power, t)
    mask = np.ones(power.shape[-1], dtype=bool)
    return EnergyResult(per_joint, per_joint.sum(axis=-1), power, unit, mask)


def mechanical_power(qd: ArrayLike, tau: ArrayLike) -> FloatArray:
    """Signed joint power ``τ_i q̇_i`` (W), shape of ``qd`` (positive: the joint drives)."""
    qd_a, tau_a = _qd_tau(qd, tau)
    return tau_a * qd_a


def mechanical_energy(qd: ArrayLike, tau: ArrayLike, t: ArrayLike) -> EnergyResult:
    """``E_i = ∫ |τ_i ω_i| dt`` (J) per joint and summed (seed 000); ``power`` = ``|τ ω|`` (W)."""
    return _result(np.abs(mechanical_power(qd, tau)), t, "J")


def positive_work(qd: ArrayLike, tau: ArrayLike, t: ArrayLike) -> EnergyResult:
    """``E_i = ∫ max(τ_i ω_i, 0) dt`` (J): only driving work counts, braking is free."""
    return _result(np.maximum(mechanical_power(qd, tau), 0.0), t, "J")


def torque_squared(tau: ArrayLike, t: ArrayLike) -> EnergyResult:
    """``∫ τ_i² dt`` (N²·m²·s) per joint and summed (seed 000's T_cuad); ``power`` = τ²."""
    tau_a = np.asarray(tau, dtype=np.float64)
    if tau_a.ndim < 2:
        raise ValueError(f"tau: expected shape (..., K, n), got {tau_a.shape}")
    return _result(tau_a**2, t, "N^2*m^2*s")


def electrical_energy(
    qd: ArrayLike,
    tau: ArrayLike,
    t: ArrayLike,
    motors: MotorArrays | Robot,
    *,
    regenerative: bool = True,
) -> ElectricalEnergy:
    """DC-motor electrical energy (J) per joint and total, seed 001 eqs 9–14 through the gear.

    ``qd`` (..., K, n) rad/s and ``tau`` (..., K, n) N·m joint side; ``t`` (K,) or (..., K) s;
    ``motors`` a robot or its :class:`MotorArrays`. Per sample ``I = τ/(G K_t)`` (A),
    ``V_e = K_e G q̇`` (V), ``P = R I² + V_e I`` (W). Joints without K_t, K_e, R are NaN and not
    in ``total``; raises ValueError if no joint has electrical data. ``regenerative=False``
    integrates ``max(P, 0)`` per motor instead of the signed power of eq 14.
    """
    m = motors.motors if isinstance(motors, Robot) else motors
    qd_a, tau_a = _qd_tau(qd, tau)
    n = qd_a.shape[-1]
    if m.G.shape[0] != n:
        raise ValueError(f"motors: data for {m.G.shape[0]} joints, but qd/tau have {n}")
    mask = m.electrical
    if not mask.any():
        raise ValueError(
            "motors: no joint has electrical data (Kt, Ke and R); electrical energy undefined"
        )
    nan = np.where(mask, 1.0, np.nan)
    Kt = np.where(mask, m.Kt, 1.0)
    Ke = np.where(mask, m.Ke, 0.0)
    R = np.where(mask, m.R, 0.0)
    current = tau_a / (m.G * Kt) * nan  # eq 9 with τ_m = τ / G
    back_emf = Ke * m.G * qd_a * nan  # eq 10 with ω_m = G q̇
    joule = R * current**2  # eq 11
    power = joule + back_emf * current  # eqs 12, 13
    if not regenerative:
        power = np.maximum(power, 0.0) * nan  # keep NaN (np.maximum propagates it anyway)
    per_joint = integrate(power, t)  # eq 14
    total = np.sum(np.where(mask, per_joint, 0.0), axis=-1)
    return ElectricalEnergy(
        per_joint=per_joint,
        total=total,
        power=power,
        unit="J",
        joints=mask,
        current=current,
        back_emf=back_emf,
        joule=joule,
        joule_energy=integrate(joule, t),
    )


EnergyModel = Callable[
    [ArrayLike, ArrayLike, ArrayLike, ArrayLike, ArrayLike, "Robot | None"], EnergyResult
]
"""Uniform signature of ``ENERGY_MODELS`` entries: ``(q, qd, qdd, tau, t, robot) -> result``."""


def _mech(
    q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, tau: ArrayLike, t: ArrayLike, robot: Robot | None
) -> EnergyResult:
    return mechanical_energy(qd, tau, t)


def _pos(
    q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, tau: ArrayLike, t: ArrayLike, robot: Robot | None
) -> EnergyResult:
    return positive_work(qd, tau, t)


def _tsq(
    q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, tau: ArrayLike, t: ArrayLike, robot: Robot | None
) -> EnergyResult:
    return torque_squared(tau, t)


def _elec(
    q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, tau: ArrayLike, t: ArrayLike, robot: Robot | None
) -> EnergyResult:
    if robot is None:
        raise ValueError("robot: the electrical model needs the robot's motor data")
    return electrical_energy(qd, tau, t, robot)


ENERGY_MODELS: dict[str, EnergyModel] = {
    "mechanical": _mech,
    "positive_work": _pos,
    "torque_squared": _tsq,
    "electrical": _elec,
}


def energy(
    model: str,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    tau: ArrayLike,
    t: ArrayLike,
    robot: Robot | None = None,
) -> EnergyResult:
    """Evaluate the energy model named ``model`` (a key of ``ENERGY_MODELS``) on one motion.

    Uniform signature for problems that take the model name from a job spec; ``robot`` is needed
    by ``electrical`` only.
    """
    if model not in ENERGY_MODELS:
        raise ValueError(f"model: unknown energy model {model!r}; known: {sorted(ENERGY_MODELS)}")
    return ENERGY_MODELS[model](q, qd, qdd, tau, t, robot)
