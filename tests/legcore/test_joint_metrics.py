"""Seed 000 metric set on analytic trajectories with hand-computed values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from legcore.joint_metrics import JointMetrics, derivative, joint_metrics

A = np.array([0.4, 0.15])  # rad
W = np.array([2.0, 4.0])  # rad/s (joint 2 runs two periods)
T = 2 * math.pi / W[0]  # one period of joint 1, s
INERTIA = np.array([0.3, 0.05])  # kg·m²: τ = I q̈ (a pure inertia per joint)


def _sine(K: int = 4001):
    t = np.linspace(0.0, T, K)  # K - 1 divisible by 8: all extrema and zeros are samples
    s, c = np.sin(W * t[:, None]), np.cos(W * t[:, None])
    q = A * s
    qd = A * W * c
    qdd = -A * W**2 * s
    jerk = -A * W**3 * c
    tau = INERTIA * qdd
    return t, q, qd, qdd, jerk, tau


def test_sine_trajectory_hand_values():
    t, q, qd, qdd, jerk, tau = _sine()
    r = 0.05  # foot on a circle of radius 5 cm, once around
    phi = 2 * math.pi * t / T
    p = np.stack([r * np.cos(phi), r * np.sin(phi), np.full_like(t, 0.1)], axis=-1)
    m = joint_metrics(t, q, tau, qd=qd, qdd=qdd, jerk=jerk, tool_pos=p)
    periods = np.array([1, 2])
    np.testing.assert_allclose(m.theta, 4 * A * periods, rtol=1e-12)  # Σ|Δq| = 4A per period
    np.testing.assert_allclose(m.displacement, 0.0, atol=1e-12)
    np.testing.assert_allclose(m.omega_max, A * W, rtol=1e-12)
    np.testing.assert_allclose(m.alpha_max, A * W**2, rtol=1e-12)
    np.testing.assert_allclose(m.alpha_min, -A * W**2, rtol=1e-12)
    np.testing.assert_allclose(m.jerk_max, A * W**3, rtol=1e-12)
    np.testing.assert_allclose(m.tau_max, INERTIA * A * W**2, rtol=1e-12)
    # ∫ (I A ω² sin)² dt over whole periods = I² A² ω⁴ T / 2 (trapezoid exact for trig polys)
    np.testing.assert_allclose(m.tau_sq, INERTIA**2 * A**2 * W**4 * T / 2, rtol=1e-12)
    # E = ∫|τ q̇| dt: each quarter period moves ½ I A² ω² in or out -> 2 I A² ω² per period
    np.testing.assert_allclose(m.energy, 2 * INERTIA * A**2 * W**2 * periods, rtol=1e-5)
    assert m.theta_total == pytest.approx(4 * A[0] + 8 * A[1])
    assert m.energy_total == pytest.approx(m.energy.sum())
    assert m.tau_sq_total == pytest.approx(m.tau_sq.sum())
    N = len(t) - 1
    assert m.path_length == pytest.approx(N * 2 * r * math.sin(math.pi / N), rel=1e-13)
    assert m.duration == pytest.approx(T)


def test_numerical_derivatives_when_not_given():
    t, q, qd, qdd, jerk, tau = _sine()
    m = joint_metrics(t, q, tau)  # qd, qdd, jerk by finite differences
    np.testing.assert_allclose(m.omega_max, A * W, rtol=1e-5)
    np.testing.assert_allclose(m.alpha_max, A * W**2, rtol=1e-4)
    np.testing.assert_allclose(m.jerk_max, A * W**3, rtol=1e-3)
    assert np.isnan(m.path_length)
    # derivative on a non-uniform grid is exact for quadratics inside
    tt = np.array([0.0, 0.3, 0.4, 1.0, 1.7])
    d = derivative((tt**2)[:, None], tt)
    np.testing.assert_allclose(d[1:-1, 0], 2 * tt[1:-1], rtol=1e-13)


def test_batch_equals_single_and_seed_theta_total():
    # Three monotone joint ramps moving seed 000 Table 2 (Calderón, 2008) angles: θ_T = 2.412 rad
    t = np.linspace(0.0, 3.0, 31)
    s = (t / 3.0)[:, None]
    q1 = np.array([0.6458, -1.2007, 0.5655]) * s
    q2 = np.array([0.6458, 0.00348, 0.0]) * s  # Tian & Collins: θ_T = 0.6493 rad (Table 3)
    tau = np.ones_like(q1)
    batch = joint_metrics(t, np.stack([q1, q2]), np.stack([tau, tau]))
    assert batch.batch_shape == (2,)
    # the paper prints 4 decimals (0.6458 + 0.00348 = 0.64928 -> 0.6493)
    np.testing.assert_allclose(batch.theta_total, [2.412, 0.6493], atol=5e-5)
    assert batch.theta_total[0] == pytest.approx(2.412, abs=1e-12)
    single = joint_metrics(t, q2, tau)
    for key, value in single.as_dict().items():
        np.testing.assert_allclose(getattr(batch, key)[1], value, rtol=1e-14, err_msg=key)


def test_as_table_rows():
    t, q, qd, qdd, jerk, tau = _sine(K=401)
    m = joint_metrics(t, np.stack([q, q, q]), np.stack([tau] * 3))
    rows = m.as_table(1)
    by_key = {row.key: row for row in rows}
    assert [r.label for r in rows[:9]] == [
        "θ", "θ_min", "ω_max", "α_max", "α_min", "Jerk", "τ_max", "T_cuad", "E",
    ]
    assert by_key["energy"].unit == "J"
    assert by_key["tau_sq"].unit == "N²·m²·s"
    assert by_key["theta"].per_joint == pytest.approx(tuple(m.theta[1]))
    assert by_key["theta_total"].total == pytest.approx(float(m.theta_total[1]))
    assert by_key["theta_total"].per_joint is None
    with pytest.raises(ValueError, match="index"):
        m.as_table()
    assert isinstance(m, JointMetrics)


def test_bad_shapes():
    t = np.linspace(0, 1, 5)
    with pytest.raises(ValueError, match="tau"):
        joint_metrics(t, np.zeros((5, 2)), np.zeros((5, 3)))
    with pytest.raises(ValueError, match="tool_pos"):
        joint_metrics(t, np.zeros((5, 2)), np.zeros((5, 2)), tool_pos=np.zeros((5, 2)))
    with pytest.raises(ValueError, match="t:"):
        joint_metrics(t[::-1], np.zeros((5, 2)), np.zeros((5, 2)))
