"""Cartesian lines/arcs/composites: seed 004 capsule, continuity, analytic derivatives."""

from __future__ import annotations

import math

import numpy as np
import pytest

from legcore.trajectories import (
    Arc,
    CompositePath,
    ConstantProfile,
    Line,
    Plane,
    QuinticProfile,
    Segment,
    capsule_path,
)

V = 0.10


@pytest.fixture(scope="module")
def capsule() -> CompositePath:
    return capsule_path()


def _far_from(t: np.ndarray, points: np.ndarray, margin: float) -> np.ndarray:
    return t[np.min(np.abs(t[:, None] - points[None, :]), axis=1) > margin]


def test_capsule_times_and_corners(capsule: CompositePath):
    assert capsule.durations == pytest.approx([4.6416, 4.0, 3.1416, 5.5], abs=1e-4)
    assert capsule.T == pytest.approx(17.2832, abs=1e-4)
    assert capsule.lengths == pytest.approx([0.1 * math.pi, 0.4, 0.1 * math.pi, 0.4], rel=1e-14)
    corners = capsule.evaluate(capsule.t_breaks).p
    expected = [[0.2, 0.2], [0.2, 0.4], [-0.2, 0.4], [-0.2, 0.2], [0.2, 0.2]]  # fig. 14, in m
    np.testing.assert_allclose(corners[:, :2], expected, atol=1e-14)
    np.testing.assert_allclose(corners[:, 2], 0.50, atol=1e-15)  # plane z = 50 cm


def test_capsule_is_closed_and_starts_and_ends_at_rest(capsule: CompositePath):
    s = capsule.evaluate([0.0, capsule.T])
    np.testing.assert_allclose(s.p[-1], s.p[0], atol=1e-14)
    np.testing.assert_allclose(s.pd, 0.0, atol=1e-15)


def test_tool_speed_is_exactly_V_in_constant_parts(capsule: CompositePath):
    t = np.linspace(3.0, capsule.T - 3.0, 2001)
    assert np.abs(capsule.evaluate(t).speed - V).max() < 1e-14
    # linear ramps: |ṗ| = V t / t_a during the first 3 s, V (T − t)/t_d during the last 3 s
    t = np.linspace(0.0, 3.0, 31)
    np.testing.assert_allclose(capsule.evaluate(t).speed, V * t / 3.0, atol=1e-14)
    t = np.linspace(capsule.T - 3.0, capsule.T, 31)
    np.testing.assert_allclose(capsule.evaluate(t).speed, V * (capsule.T - t) / 3.0, atol=1e-14)


def test_capsule_geometry(capsule: CompositePath):
    b = capsule.t_breaks
    t = np.linspace(0.0, capsule.T, 3001)
    p = capsule.evaluate(t).p
    seg = np.clip(np.searchsorted(b, t, side="right") - 1, 0, 3)
    r1 = np.linalg.norm(p[seg == 0, :2] - [0.2, 0.3], axis=1)
    r3 = np.linalg.norm(p[seg == 2, :2] - [-0.2, 0.3], axis=1)
    np.testing.assert_allclose(r1, 0.1, atol=1e-14)
    np.testing.assert_allclose(r3, 0.1, atol=1e-14)
    assert np.all(p[seg == 0, 0] >= 0.2 - 1e-14)  # right semicircle bulges to +x (CCW)
    assert np.all(p[seg == 2, 0] <= -0.2 + 1e-14)
    np.testing.assert_allclose(p[seg == 1, 1], 0.4, atol=1e-15)
    np.testing.assert_allclose(p[seg == 3, 1], 0.2, atol=1e-15)


def test_centripetal_acceleration_on_arcs(capsule: CompositePath):
    # constant speed V on a circle of radius r: |p̈| = V²/r, pointing to the centre
    b = capsule.t_breaks
    t = np.linspace(3.05, b[1] - 0.05, 50)
    s = capsule.evaluate(t)
    np.testing.assert_allclose(np.linalg.norm(s.pdd, axis=1), V**2 / 0.1, rtol=1e-12)
    inward = np.array([0.2, 0.3, 0.5]) - s.p
    cos = np.sum(inward * s.pdd, axis=1) / (np.linalg.norm(inward, axis=1) * 0.1)
    np.testing.assert_allclose(cos, 1.0, atol=1e-12)


def test_continuity_at_segment_joins(capsule: CompositePath):
    eps = 1e-9
    joins = capsule.t_breaks[1:-1]
    left = capsule.evaluate(joins - eps)
    right = capsule.evaluate(joins + eps)
    np.testing.assert_allclose(left.p, right.p, atol=1e-9)
    np.testing.assert_allclose(left.pd, right.pd, atol=1e-9)
    np.testing.assert_allclose(left.speed, V, atol=1e-9)


def test_derivatives_match_finite_differences(capsule: CompositePath):
    h = 1e-5
    kinks = np.concatenate([capsule.t_breaks, [3.0, capsule.T - 3.0]])
    t = _far_from(np.linspace(0.01, capsule.T - 0.01, 401), kinks, 10 * h)
    s0, sp, sm = capsule.evaluate(t), capsule.evaluate(t + h), capsule.evaluate(t - h)
    np.testing.assert_allclose((sp.p - sm.p) / (2 * h), s0.pd, atol=1e-9)
    np.testing.assert_allclose((sp.pd - sm.pd) / (2 * h), s0.pdd, atol=1e-9)
    np.testing.assert_allclose((sp.pdd - sm.pdd) / (2 * h), s0.pddd, atol=1e-8)


def test_capsule_in_a_tilted_plane_is_the_rotated_xy_capsule():
    ang = 0.7
    R = np.array(  # rotation about x then about z
        [[1, 0, 0], [0, math.cos(ang), -math.sin(ang)], [0, math.sin(ang), math.cos(ang)]]
    ) @ np.array([[math.cos(0.3), -math.sin(0.3), 0], [math.sin(0.3), math.cos(0.3), 0], [0, 0, 1]])
    origin = np.array([0.1, -0.2, 0.3])
    tilted = capsule_path(plane=Plane(origin, R[:, 0], R[:, 1]))
    flat = capsule_path(plane=Plane.xy(0.0))
    t = np.linspace(0.0, flat.T, 200)
    a, b = tilted.evaluate(t), flat.evaluate(t)
    np.testing.assert_allclose(a.p, origin + b.p @ R.T, atol=1e-14)
    np.testing.assert_allclose(a.pdd, b.pdd @ R.T, atol=1e-14)
    np.testing.assert_allclose((a.p - origin) @ np.cross(R[:, 0], R[:, 1]), 0.0, atol=1e-14)
    np.testing.assert_allclose(a.speed, b.speed, atol=1e-15)


def test_single_line_eq_14_and_clockwise_arc():
    # seed 004 example 1 (cm -> m): (10, 20) -> (50, 60) cm in T = 10 s, constant speed
    path = CompositePath((Segment(Line([0.10, 0.20], [0.50, 0.60]), ConstantProfile(10.0)),))
    s = path.evaluate([0.0, 2.5, 10.0])
    np.testing.assert_allclose(s.p[:, :2], [[0.1, 0.2], [0.2, 0.3], [0.5, 0.6]], atol=1e-15)
    np.testing.assert_allclose(s.pd[1], [0.04, 0.04, 0.0], atol=1e-15)
    # clockwise quarter arc: from angle 0 to −90°
    arc = Arc([0.0, 0.0], 0.2, 0.0, -math.pi / 2)
    np.testing.assert_allclose(arc.end, [0.0, -0.2], atol=1e-15)
    assert arc.length == pytest.approx(0.1 * math.pi, rel=1e-15)
    mid = CompositePath((Segment(arc, QuinticProfile(1.0)),)).evaluate(0.5).p[0]
    np.testing.assert_allclose(mid[:2], [0.2 / math.sqrt(2), -0.2 / math.sqrt(2)], atol=1e-15)


def test_seed_004_example_2_arc():
    # β = 45°, φ = 270°, centre (20, 10) cm, r = 30 cm, T = 20 s constant (eq 18)
    arc = Arc([0.20, 0.10], 0.30, math.radians(45), math.radians(270))
    path = CompositePath((Segment(arc, ConstantProfile(20.0)),))
    s = path.evaluate([0.0, 20.0])
    c = math.sqrt(0.5) * 0.3
    np.testing.assert_allclose(s.p[:, :2], [[0.2 + c, 0.1 + c], [0.2 + c, 0.1 - c]], atol=1e-15)
    np.testing.assert_allclose(s.speed, 0.3 * math.radians(270) / 20.0, rtol=1e-14)


def test_sample_uses_a_uniform_grid(capsule: CompositePath):
    s = capsule.sample(0.01)
    assert s.t.shape == (1729,) and s.p.shape == (1729, 3) and s.pddd.shape == (1729, 3)
    np.testing.assert_allclose(np.diff(s.t), 0.01, atol=1e-12)


def test_invalid_paths_raise():
    a = Segment(Line([0.0, 0.0], [0.1, 0.0]), ConstantProfile(1.0))
    b = Segment(Line([0.2, 0.0], [0.3, 0.0]), ConstantProfile(1.0))
    with pytest.raises(ValueError, match="segments\\[1\\] starts"):
        CompositePath((a, b))
    with pytest.raises(ValueError, match="orthogonal"):
        Plane([0, 0, 0], [1, 0, 0], [math.sqrt(0.5), math.sqrt(0.5), 0])
    with pytest.raises(ValueError, match="r must"):
        Arc([0, 0], -0.1, 0.0, 1.0)
    with pytest.raises(ValueError, match="w_i and w_f"):
        Line([0, 0], [0, 0])
    with pytest.raises(ValueError, match="t must lie"):
        capsule_path().evaluate([18.0])
