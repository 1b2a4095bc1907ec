"""Swing curves: seed 000 parabolic baseline (0.156 m step, 0.065 m height, 3 s), ellipse."""

from __future__ import annotations

import math

import numpy as np
import pytest

from legcore.trajectories import (
    SEED000_HEIGHT,
    SEED000_STEP,
    SEED000_T,
    QuinticProfile,
    SCurveProfile,
    SwingCurve,
    TrapezoidalProfile,
)

L, H, T = SEED000_STEP, SEED000_HEIGHT, SEED000_T


def seed000_swing(shape: str = "parabolic") -> SwingCurve:
    return SwingCurve([0.0, 0.0, 0.0], [L, 0.0, 0.0], H, QuinticProfile(T), shape)  # type: ignore[arg-type]


def test_seed_000_constants():
    assert (L, H, T) == (0.156, 0.065, 3.0)


@pytest.mark.parametrize("shape", ["parabolic", "elliptic"])
def test_height_at_mid_stride_and_span(shape):
    sw = seed000_swing(shape)
    s = sw.evaluate([0.0, T / 2, T])
    np.testing.assert_allclose(s.p[1], [L / 2, 0.0, H], atol=1e-15)
    np.testing.assert_allclose(s.p[2] - s.p[0], [L, 0.0, 0.0], atol=1e-15)
    dense = sw.evaluate(np.linspace(0.0, T, 3001))
    assert dense.p[:, 2].max() == pytest.approx(H, abs=1e-15)
    assert dense.t[np.argmax(dense.p[:, 2])] == pytest.approx(T / 2)
    assert dense.p[:, 2].min() >= -1e-15
    # a rest-to-rest time law: the foot starts and lands with zero velocity
    np.testing.assert_allclose(s.pd[[0, 2]], 0.0, atol=1e-15)


def test_curve_shapes():
    t = np.linspace(0.0, T, 301)
    p = seed000_swing("parabolic").evaluate(t).p
    x = p[:, 0] / L
    np.testing.assert_allclose(p[:, 2], 4 * H * x * (1 - x), atol=1e-15)
    p = seed000_swing("elliptic").evaluate(t).p
    np.testing.assert_allclose(
        ((p[:, 0] - L / 2) / (L / 2)) ** 2 + (p[:, 2] / H) ** 2, 1.0, atol=1e-12
    )


def test_parabola_arc_length_closed_form():
    # arc length of a parabola of half-span a and height h:
    # sqrt(a² + 4h²) + a²/(2h) · asinh(2h/a)  (seed 000 reports D_PFE = 0.2045 m)
    a = L / 2
    exact = math.sqrt(a**2 + 4 * H**2) + a**2 / (2 * H) * math.asinh(2 * H / a)
    s = seed000_swing().evaluate(np.linspace(0.0, T, 20001))
    numeric = np.trapezoid(s.speed, s.t)
    assert numeric == pytest.approx(exact, abs=1e-7)
    assert exact == pytest.approx(0.2117, abs=1e-4)


@pytest.mark.parametrize("shape", ["parabolic", "elliptic"])
@pytest.mark.parametrize(
    "profile", [QuinticProfile(T), TrapezoidalProfile(T, 1.0, 1.0), SCurveProfile(T, 1.0, 1.0, 0.3)]
)
def test_derivatives_match_finite_differences(shape, profile):
    sw = SwingCurve([0.1, 0.05, -0.3], [0.12, 0.05, 0.0], 0.04, profile, shape)
    h = 1e-5
    t = np.linspace(0.01, T - 0.01, 151)
    t = t[np.min(np.abs(t[:, None] - profile.breakpoints[None, :]), axis=1) > 10 * h]
    s0, sp, sm = sw.evaluate(t), sw.evaluate(t + h), sw.evaluate(t - h)
    np.testing.assert_allclose((sp.p - sm.p) / (2 * h), s0.pd, atol=1e-9)
    np.testing.assert_allclose((sp.pd - sm.pd) / (2 * h), s0.pdd, atol=1e-8)
    np.testing.assert_allclose((sp.pdd - sm.pdd) / (2 * h), s0.pddd, atol=1e-6)


def test_general_start_step_and_up():
    up = np.array([0.0, 1.0, 1.0])  # normalised on construction
    sw = SwingCurve([0.1, 0.2, -0.3], [0.0, 0.1, -0.1], 0.05, QuinticProfile(2.0), "parabolic", up)
    np.testing.assert_allclose(sw.up, up / math.sqrt(2), atol=1e-15)
    mid = sw.evaluate([1.0]).p[0]
    np.testing.assert_allclose(mid, [0.1, 0.25, -0.35] + 0.05 * up / math.sqrt(2), atol=1e-15)
    assert sw.sample(0.01).p.shape == (201, 3)


def test_invalid_swing_raises():
    with pytest.raises(ValueError, match="height"):
        SwingCurve([0, 0, 0], [L, 0, 0], -0.01, QuinticProfile(T))
    with pytest.raises(ValueError, match="shape"):
        SwingCurve([0, 0, 0], [L, 0, 0], H, QuinticProfile(T), "cycloid")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="step"):
        SwingCurve([0, 0, 0], [L, 0], H, QuinticProfile(T))
    with pytest.raises(ValueError, match="up"):
        SwingCurve([0, 0, 0], [L, 0, 0], H, QuinticProfile(T), up=[0, 0, 0])
