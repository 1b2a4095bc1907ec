"""Velocity profiles: seed 004 numbers (eqs 19–53), boundary values, analytic derivatives."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from legcore.trajectories import (
    AccelProfile,
    ConstantProfile,
    DecelProfile,
    Profile,
    QuinticProfile,
    SCurveProfile,
    TrapezoidalProfile,
    segment_time,
)

V = 0.10  # m/s, seed 004 capsule cruise speed (10 cm/s)
D_ARC = 0.10 * math.pi  # m, semicircle r = 10 cm
D_LINE = 0.40  # m


def all_profiles() -> list[Profile]:
    return [
        ConstantProfile(4.0),
        TrapezoidalProfile(6.0, 1.0, 2.0),
        TrapezoidalProfile(4.0, 2.0, 2.0),  # triangle
        AccelProfile.from_distance(D_ARC, V, 3.0),
        DecelProfile.from_distance(D_LINE, V, 3.0),
        QuinticProfile(3.0),
        SCurveProfile(6.0, 2.0, 1.5, 0.5),
        SCurveProfile(6.0, 2.0, 2.0, 1.0),  # no constant-acceleration phase
        SCurveProfile(5.0, 2.0, 0.0, 0.4),  # S-curve acceleration-only
        SCurveProfile(5.0, 0.0, 2.0, 0.4),  # S-curve deceleration-only
    ]


# --- seed 004 numbers ---------------------------------------------------------------------------


def test_capsule_segment_times_match_seed_004():
    T = [
        segment_time(D_ARC, V, t_a=3.0),  # eq 20
        segment_time(D_LINE, V),  # eq 22
        segment_time(D_ARC, V),  # eq 22
        segment_time(D_LINE, V, t_d=3.0),  # eq 24
    ]
    assert T == pytest.approx([4.6416, 4.0, 3.1416, 5.5], abs=1e-4)
    assert sum(T) == pytest.approx(17.2832, abs=1e-4)
    # the paper's own closed forms, eq 20 and eq 24
    assert T[0] == pytest.approx((V * 3.0 + 2 * D_ARC) / (2 * V), rel=1e-14)
    assert T[3] == pytest.approx((V * 3.0 + 2 * D_LINE) / (2 * V), rel=1e-14)
    # full trapezoid: area under the speed curve = D
    T_full = segment_time(D_LINE, V, 1.0, 2.0)
    assert V * 1.0 / 2 + V * (T_full - 3.0) + V * 2.0 / 2 == pytest.approx(D_LINE, rel=1e-14)


def test_s1_accel_profile_coefficients_eq_50():
    p = AccelProfile.from_distance(D_ARC, V, 3.0)
    assert p.v == pytest.approx(0.3183, abs=1e-4)
    t = np.linspace(0.0, 2.999, 50)
    c = np.polyfit(t, p.s(t), 2)
    assert c == pytest.approx([0.0531, 0.0, 0.0], abs=1e-4)
    t = np.linspace(3.0, p.T, 50)
    c = np.polyfit(t, p.s(t), 1)
    assert c == pytest.approx([0.3183, -0.4775], abs=1e-4)


def test_s4_decel_profile_coefficients_eq_53():
    p = DecelProfile.from_distance(D_LINE, V, 3.0)
    assert p.T == pytest.approx(5.5, abs=1e-12)
    assert p.v == pytest.approx(0.25, abs=1e-12)
    t = np.linspace(0.0, 2.499, 50)
    assert np.polyfit(t, p.s(t), 1) == pytest.approx([0.25, 0.0], abs=1e-4)
    t = np.linspace(2.5, 5.5, 50)
    c = np.polyfit(t, p.s(t), 2)
    assert c == pytest.approx([-0.0417, 0.4583, -0.2604], abs=1e-4)


def test_constant_profiles_eq_51_52():
    assert ConstantProfile.from_distance(D_LINE, V).s(np.array([1.0, 2.0])) == pytest.approx(
        [0.25, 0.5], abs=1e-15
    )
    p3 = ConstantProfile.from_distance(D_ARC, V)
    assert p3.T == pytest.approx(3.1416, abs=1e-4)
    assert p3.s(1.0) == pytest.approx(1.0 / math.pi, rel=1e-14)


def test_trapezoid_matches_eq_11_with_t_a_in_first_piece():
    T, t_a, t_d = 7.0, 2.0, 3.0
    v = 2.0 / (2 * T - t_a - t_d)  # eq 13
    t = np.linspace(0.0, T, 701)
    expected = np.where(
        t < t_a,
        v / (2 * t_a) * t**2,
        np.where(
            t < T - t_d,
            v * t - v * t_a / 2,
            -v / (2 * t_d) * t**2 + v * T / t_d * t + 1 - v * T**2 / (2 * t_d),
        ),
    )
    p = TrapezoidalProfile(T, t_a, t_d)
    assert p.v == pytest.approx(v, rel=1e-15)
    np.testing.assert_allclose(p.s(t), expected, atol=1e-14)


def test_accel_and_decel_are_trapezoids_with_one_ramp():
    t = np.linspace(0.0, 5.0, 101)
    np.testing.assert_allclose(
        AccelProfile(5.0, 2.0).derivatives(t),
        TrapezoidalProfile(5.0, 2.0, 0.0).derivatives(t),
        atol=1e-14,
    )
    np.testing.assert_allclose(
        DecelProfile(5.0, 2.0).derivatives(t),
        TrapezoidalProfile(5.0, 0.0, 2.0).derivatives(t),
        atol=1e-14,
    )
    np.testing.assert_allclose(
        ConstantProfile(5.0).derivatives(t),
        TrapezoidalProfile(5.0, 0.0, 0.0).derivatives(t),
        atol=1e-14,
    )


# --- boundary values and shape --------------------------------------------------------------------


@pytest.mark.parametrize("p", all_profiles(), ids=lambda p: repr(p))
def test_boundary_values_and_monotone(p: Profile):
    d = p.derivatives(np.array([0.0, p.T]))
    assert d[0] == pytest.approx([0.0, 1.0], abs=1e-13)
    s = p.s(np.linspace(0.0, p.T, 2001))
    assert np.all(np.diff(s) >= -1e-15)
    # area under ṡ is one (trapezoid rule on a fine grid)
    t = np.linspace(0.0, p.T, 20001)
    assert np.trapezoid(p.sd(t), t) == pytest.approx(1.0, abs=1e-6)


def test_rest_conditions():
    rest_to_rest = (
        TrapezoidalProfile(6.0, 1.0, 2.0),
        QuinticProfile(3.0),
        SCurveProfile(6, 2, 1.5, 0.5),
    )
    for p in rest_to_rest:
        assert p.sd(np.array([0.0, p.T])) == pytest.approx([0.0, 0.0], abs=1e-13)
    for p in (QuinticProfile(3.0), SCurveProfile(6, 2, 1.5, 0.5)):  # smooth: also s̈ = 0
        assert p.sdd(np.array([0.0, p.T])) == pytest.approx([0.0, 0.0], abs=1e-13)
    a = AccelProfile(5.0, 2.0)
    assert a.sd(np.array([0.0, 5.0])) == pytest.approx([0.0, a.v], abs=1e-14)
    d = DecelProfile(5.0, 2.0)
    assert d.sd(np.array([0.0, 5.0])) == pytest.approx([d.v, 0.0], abs=1e-14)
    c = ConstantProfile(5.0)
    assert c.sd(np.array([0.0, 5.0])) == pytest.approx([0.2, 0.2], abs=1e-15)


def test_quintic_closed_form_and_peak_speed():
    T = 3.0
    p = QuinticProfile(T)
    t = np.linspace(0.0, T, 31)
    tau = t / T
    np.testing.assert_allclose(p.s(t), 10 * tau**3 - 15 * tau**4 + 6 * tau**5, atol=1e-14)
    assert p.sd(T / 2) == pytest.approx(15.0 / (8.0 * T), rel=1e-13)


def test_scurve_limits_and_continuity():
    p = SCurveProfile(6.0, 2.0, 1.5, 0.5)
    t = np.linspace(0.0, p.T, 60001)
    assert p.sd(t).max() == pytest.approx(p.v, rel=1e-12)
    assert p.v == pytest.approx(2.0 / (2 * 6.0 - 3.5), rel=1e-15)
    assert np.abs(p.sddd(t)).max() == pytest.approx(p.jerk_max, rel=1e-12)
    # the accel ramp jerk: v / ((t_a − t_j) t_j) = v / 0.75, decel ramp v / 0.5
    assert p.jerk_max == pytest.approx(p.v / 0.5, rel=1e-14)
    # s̈ is continuous at every breakpoint (a trapezoid's is not)
    eps = 1e-9
    b = p.breakpoints[1:-1]
    np.testing.assert_allclose(p.sdd(b - eps), p.sdd(b + eps), atol=1e-7)
    tr = TrapezoidalProfile(6.0, 2.0, 1.5)
    assert abs(tr.sdd(2.0 - eps) - tr.sdd(2.0 + eps)) > 0.1


def test_scurve_with_zero_jerk_time_is_the_trapezoid():
    t = np.linspace(0.0, 6.0, 301)
    np.testing.assert_allclose(
        SCurveProfile(6.0, 2.0, 1.5, 0.0).derivatives(t)[:3],
        TrapezoidalProfile(6.0, 2.0, 1.5).derivatives(t)[:3],
        atol=1e-14,
    )
    assert SCurveProfile(6.0, 2.0, 1.5, 0.0).jerk_max == math.inf


def test_scurve_from_distance_reaches_speed():
    p = SCurveProfile.from_distance(D_LINE, V, 3.0, 3.0, 1.0)
    assert p.T == pytest.approx(segment_time(D_LINE, V, 3.0, 3.0), rel=1e-15)
    assert D_LINE * p.v == pytest.approx(V, rel=1e-14)  # tool speed = D ṡ


# --- analytic derivatives vs finite differences --------------------------------------------------


@pytest.mark.parametrize("p", all_profiles(), ids=lambda p: repr(p))
def test_derivatives_match_finite_differences(p: Profile):
    h = 1e-5
    t = np.linspace(0.0, p.T, 97)[1:-1]
    # keep samples away from the breakpoints where a derivative jumps
    far = np.min(np.abs(t[:, None] - p.breakpoints[None, :]), axis=1) > 10 * h
    t = t[far]
    assert t.size > 50
    d = p.derivatives(t)
    for k in range(3):
        f = getattr(p, ("s", "sd", "sdd")[k])
        fd = (f(t + h) - f(t - h)) / (2 * h)
        np.testing.assert_allclose(d[k + 1], fd, atol=1e-6 * max(1.0, np.abs(d[k + 1]).max()))


def test_vectorised_shapes():
    p = TrapezoidalProfile(6.0, 1.0, 2.0)
    t = np.linspace(0.0, 6.0, 12).reshape(3, 4)
    assert p.s(t).shape == (3, 4)
    assert p.derivatives(t).shape == (4, 3, 4)
    np.testing.assert_array_equal(p.s(t).ravel(), p.s(t.ravel()))


# --- errors ---------------------------------------------------------------------------------------


def test_invalid_arguments_raise_clear_errors():
    with pytest.raises(ValueError, match="T"):
        ConstantProfile(0.0)
    with pytest.raises(ValueError, match="t_a \\+ t_d"):
        TrapezoidalProfile(3.0, 2.0, 2.0)
    with pytest.raises(ValueError, match="t_j"):
        SCurveProfile(6.0, 2.0, 2.0, 1.5)
    with pytest.raises(ValueError, match="too short"):
        segment_time(0.1, V, 3.0, 3.0)
    with pytest.raises(ValueError, match="V"):
        segment_time(0.4, 0.0)
    with pytest.raises(ValueError, match=r"\[0, T\]"):
        QuinticProfile(3.0).s(np.array([0.0, 3.1]))
    with pytest.raises(dataclasses.FrozenInstanceError):
        QuinticProfile(3.0).T = 2.0  # type: ignore[misc]
