"""Closed-form leg kinematics: seed 002 (3-DOF leg) and seed 003 (2-DOF leg)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from legcore.ik import (
    ELBOW_BACK,
    KNEE_DOWN,
    KNEE_FORWARD,
    KNEE_UP,
    leg2_fk,
    leg2_ik,
    leg2_link_angles_deg,
    leg2_q_from_link_angles_deg,
    leg3_fk,
    leg3_ik,
)

L_HEX = np.array([0.01, 0.035, 0.06])  # seed 002 §4, m
L_QUAD = np.array([0.085, 0.0925])  # seed 003 eq (1), m


# ---------------------------------------------------------------- 3-DOF leg (seed 002)


def test_seed002_foot_height_at_initial_posture() -> None:
    p = leg3_fk([0.0, -math.pi / 8, -math.pi / 4], L_HEX)
    # Seed 002 §4: "la altura de las tres patas también permanece constante z = −6,8827 cm".
    assert abs(p[2] * 100.0 - (-6.8827)) < 1e-4
    # Independent evaluation of eqs (5)-(7) in cm.
    r = 1.0 + 3.5 * math.cos(-math.pi / 8) + 6.0 * math.cos(-3 * math.pi / 8)
    assert p * 100.0 == pytest.approx([r, 0.0, -6.882669208], abs=1e-9)


def test_leg3_fk_matches_dh_product() -> None:
    rng = np.random.default_rng(1)
    q = rng.uniform(-math.pi, math.pi, (20, 3))

    def dh(theta: float, a: float, alpha: float) -> np.ndarray:
        c, s, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
        return np.array(
            [[c, -s * ca, s * sa, a * c], [s, c * ca, -c * sa, a * s], [0, sa, ca, 0], [0, 0, 0, 1]]
        )

    p = leg3_fk(q, L_HEX)
    for k in range(len(q)):
        T = dh(q[k, 0], L_HEX[0], math.pi / 2) @ dh(q[k, 1], L_HEX[1], 0) @ dh(q[k, 2], L_HEX[2], 0)
        assert np.allclose(p[k], T[:3, 3], atol=1e-15)


@pytest.mark.parametrize("branch", [KNEE_UP, KNEE_DOWN])
def test_leg3_ik_round_trip_random_reachable_batch(branch: int) -> None:
    rng = np.random.default_rng(2)
    n = 4000
    q = np.column_stack(
        (
            rng.uniform(-math.pi, math.pi, n),
            rng.uniform(-math.pi, math.pi, n),
            branch * rng.uniform(0.0, math.pi, n),
        )
    )
    p = leg3_fk(q, L_HEX)
    q_ik, ok = leg3_ik(p, L_HEX, branch=branch)
    assert ok.all()
    assert np.max(np.abs(leg3_fk(q_ik, L_HEX) - p)) < 1e-9
    assert np.all(branch * q_ik[:, 2] >= 0.0)
    # Where the foot is outboard of the yaw axis the solution is eq (8)'s and equals q itself.
    R = L_HEX[0] + L_HEX[1] * np.cos(q[:, 1]) + L_HEX[2] * np.cos(q[:, 1] + q[:, 2])
    front = R > 1e-3
    wrap = np.mod(q_ik - q + math.pi, 2 * math.pi) - math.pi
    assert np.max(np.abs(wrap[front])) < 1e-7


def test_leg3_eq9_equals_textbook_two_link_solution() -> None:
    rng = np.random.default_rng(3)
    q = np.column_stack(
        (rng.uniform(-0.5, 0.5, 500), rng.uniform(-1.2, 1.2, 500), rng.uniform(-2.8, -0.05, 500))
    )
    R = L_HEX[0] + L_HEX[1] * np.cos(q[:, 1]) + L_HEX[2] * np.cos(q[:, 1] + q[:, 2])
    q = q[R > 0.0]  # foot outboard of the yaw axis: eq (8)'s family
    p = leg3_fk(q, L_HEX)
    q_ik, ok = leg3_ik(p, L_HEX, branch=KNEE_UP)
    # independent: q3 = −acos(D), q2 = atan2(z, r) − atan2(L3 sin q3, L2 + L3 cos q3)
    r = np.hypot(p[:, 0], p[:, 1]) - L_HEX[0]
    D = (r**2 + p[:, 2] ** 2 - L_HEX[1] ** 2 - L_HEX[2] ** 2) / (2 * L_HEX[1] * L_HEX[2])
    q3 = -np.arccos(np.clip(D, -1, 1))
    q2 = np.arctan2(p[:, 2], r) - np.arctan2(
        L_HEX[2] * np.sin(q3), L_HEX[1] + L_HEX[2] * np.cos(q3)
    )
    assert ok.all()
    wrap = np.mod(q_ik[:, 1:] - np.column_stack((q2, q3)) + math.pi, 2 * math.pi) - math.pi
    assert np.max(np.abs(wrap)) < 1e-7


def test_leg3_unreachable_flagged_not_clipped() -> None:
    reach = L_HEX.sum()
    p = np.array(
        [
            [reach + 1e-6, 0.0, 0.0],  # just beyond full extension
            [reach - 1e-6, 0.0, 0.0],  # just inside
            [0.005, 0.0, 0.0],  # inside the hole |L3 − L2| on both sides of the yaw axis
            [0.0, 0.0, -0.5],  # far below
            [np.nan, 0.0, 0.0],
        ]
    )
    q, ok = leg3_ik(p, L_HEX)
    assert ok.tolist() == [False, True, False, False, False]
    assert np.all(np.isnan(q[~ok])) and np.all(np.isfinite(q[ok]))


def test_leg3_limits_and_yaw_flip() -> None:
    p = np.array([-0.06, 0.0, -0.03])  # foot behind the hip's yaw axis
    q, ok = leg3_ik(p, L_HEX)  # eq (8): q1 = atan2(0, −0.06) = π
    assert ok and q[0] == pytest.approx(math.pi)
    assert np.allclose(leg3_fk(q, L_HEX), p, atol=1e-15)
    # Seed 002's coxa range |q1| <= π/6 rules eq (8)'s solution out; the femur can still reach
    # back over the yaw axis (q1 = 0, q2 near π) when its range allows it ...
    lo, hi = [-math.pi / 6, -math.pi, -math.pi], [math.pi / 6, math.pi, math.pi]
    q, ok = leg3_ik(p, L_HEX, q_min=lo, q_max=hi)
    assert ok and q[0] == 0.0 and abs(q[1]) > math.pi / 2
    assert np.allclose(leg3_fk(q, L_HEX), p, atol=1e-15)
    # ... and with hobby-servo ranges |q2|, |q3| <= π/2 nothing reaches it.
    lo, hi = [-math.pi / 6, -math.pi / 2, -math.pi / 2], [math.pi / 6, math.pi / 2, math.pi / 2]
    q, ok = leg3_ik(p, L_HEX, q_min=lo, q_max=hi)
    assert not ok and np.all(np.isnan(q))


def test_leg3_per_sample_branch_and_shapes() -> None:
    q = np.array([[[0.1, -0.3, -0.8], [0.2, 0.4, 0.9]]])  # (1, 2, 3)
    p = leg3_fk(q, L_HEX)
    assert p.shape == (1, 2, 3)
    q_ik, ok = leg3_ik(p, L_HEX, branch=np.array([[KNEE_UP, KNEE_DOWN]]))
    assert ok.shape == (1, 2) and ok.all()
    assert np.allclose(q_ik, q, atol=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"p": np.zeros((4, 2)), "L": L_HEX}, "p: last axis"),
        ({"p": np.zeros((4, 3)), "L": [0.01, 0.035]}, "L: expected 3"),
        ({"p": np.zeros((4, 3)), "L": [0.01, -0.035, 0.06]}, "L: link lengths must be positive"),
        ({"p": np.zeros((4, 3)), "L": L_HEX, "branch": 0}, "branch"),
        ({"p": np.zeros((4, 3)), "L": L_HEX, "branch": np.ones(3)}, "branch"),
        ({"p": np.zeros((4, 3)), "L": L_HEX, "q_min": [0, 0]}, "q_min"),
    ],
)
def test_leg3_bad_arguments(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        leg3_ik(**kwargs)


# ---------------------------------------------------------------- 2-DOF leg (seed 003)


@pytest.mark.parametrize("branch", [ELBOW_BACK, KNEE_FORWARD])
def test_leg2_round_trip_random_reachable_batch(branch: int) -> None:
    rng = np.random.default_rng(4)
    q = np.column_stack(
        (rng.uniform(-math.pi, math.pi, 3000), branch * rng.uniform(0, math.pi, 3000))
    )
    p = leg2_fk(q, L_QUAD)
    assert np.all(p[:, 2] == 0.0)
    q_ik, ok = leg2_ik(p, L_QUAD, branch)
    assert ok.all()
    assert np.max(np.abs(leg2_fk(q_ik, L_QUAD) - p)) < 1e-9
    assert np.all(branch * q_ik[:, 1] >= 0.0)
    assert np.max(np.abs(np.mod(q_ik - q + math.pi, 2 * math.pi) - math.pi)) < 1e-6
    # planar (..., 2) targets give the same answer
    q2d, ok2d = leg2_ik(p[:, :2], L_QUAD, branch)
    assert ok2d.all() and np.array_equal(q2d, q_ik)


def test_leg2_law_of_cosines_by_hand() -> None:
    # Foot 0.16 m straight below the hip: cos q4 = (0.16² − l1² − l2²)/(2 l1 l2).
    c4 = (0.16**2 - 0.085**2 - 0.0925**2) / (2 * 0.085 * 0.0925)
    q4 = math.acos(c4)
    q3 = -math.atan2(0.0925 * math.sin(q4), 0.085 + 0.0925 * c4)
    q, ok = leg2_ik([0.16, 0.0], L_QUAD, ELBOW_BACK)
    assert ok and q == pytest.approx([q3, q4], abs=1e-14)
    q, ok = leg2_ik([0.16, 0.0], L_QUAD, KNEE_FORWARD)
    assert ok and q == pytest.approx([-q3, -q4], abs=1e-14)


def test_leg2_unreachable_flagged_not_clipped() -> None:
    p = np.array(
        [
            [0.1775 + 1e-7, 0.0, 0.0],  # beyond l1 + l2
            [0.1775 - 1e-7, 0.0, 0.0],  # just inside
            [0.005, 0.0, 0.0],  # inside the hole |l1 − l2| = 7.5 mm
            [0.1, 0.05, 0.01],  # out of the leg plane
            [0.1, np.inf, 0.0],
        ]
    )
    q, ok = leg2_ik(p, L_QUAD, ELBOW_BACK)
    assert ok.tolist() == [False, True, False, False, False]
    assert np.all(np.isnan(q[~ok])) and np.all(np.isfinite(q[ok]))
    # joint limits: the rear-leg branch is outside a front leg's q4 range [0, 135°]
    q, ok = leg2_ik(p[1], L_QUAD, KNEE_FORWARD, q_min=[-math.pi / 2, 0.0], q_max=[math.pi / 2, 2.4])
    assert not ok and np.all(np.isnan(q))


def _dog_step(depth: float, length: float, height: float, n: int) -> np.ndarray:
    """Hip-frame (x down, y forward) foot path of one step: a half-ellipse swing forward, then a
    straight stance stroke back — n samples per phase."""
    u = np.linspace(0.0, 1.0, n)
    swing = np.column_stack((depth - height * np.sin(np.pi * u), -0.5 * length * np.cos(np.pi * u)))
    stance = np.column_stack((np.full(n, depth), 0.5 * length - length * u))
    return np.vstack((swing, stance))


def test_quadruped_leg_follows_a_dog_step_with_the_anatomical_branch() -> None:
    path = _dog_step(depth=0.165, length=0.10, height=0.035, n=200)
    for branch, sign in ((ELBOW_BACK, +1.0), (KNEE_FORWARD, -1.0)):
        q, ok = leg2_ik(
            path,
            L_QUAD,
            branch,
            q_min=[-math.pi / 2, -3 * math.pi / 4],
            q_max=[math.pi / 2, 3 * math.pi / 4],
        )
        assert ok.all()
        assert np.all(sign * q[:, 1] > 0.0)  # front: elbow back (q4 > 0); rear: knee forward
        assert np.max(np.abs(leg2_fk(q, L_QUAD)[:, :2] - path)) < 1e-12
        assert np.max(np.abs(np.diff(q, axis=0))) < 0.05  # a smooth joint path, no branch jump


def test_elbow_back_geometry() -> None:
    # With q4 > 0 the elbow lies behind (smaller y than) the hip–foot line at the elbow's depth.
    q = np.array([0.1, 0.6])
    elbow = L_QUAD[0] * np.array([math.cos(q[0]), math.sin(q[0])])
    foot = leg2_fk(q, L_QUAD)[:2]
    y_line = foot[1] * elbow[0] / foot[0]
    assert elbow[1] < y_line


# Seed 003 Table 2: (Ang3, Ang4, q3, q4) in degrees, front and rear legs, printed rows.
TABLE2_FRONT = [
    (81, 61, 369, 20), (82, 62, 368, 20), (83, 63, 367, 20), (84, 64, 366, 20),
    (116, 99, 334, 17), (117, 100, 333, 17), (118, 101, 332, 17), (119, 102, 331, 17),
]  # fmt: skip
TABLE2_REAR = [
    (60, 80, 30, 340), (61, 81, 29, 340), (62, 82, 28, 340), (63, 83, 27, 340),
    (99, 115, 351, 344), (100, 116, 350, 344), (101, 117, 349, 344), (102, 118, 348, 344),
]  # fmt: skip


@pytest.mark.parametrize(("rows", "sign"), [(TABLE2_FRONT, +1), (TABLE2_REAR, -1)])
def test_seed003_table2_link_angles_map_to_dh_angles(rows: list, sign: int) -> None:
    t = np.array(rows, dtype=float)
    q = leg2_q_from_link_angles_deg(t[:, :2])
    diff = np.mod(np.degrees(q) - t[:, 2:] + 180.0, 360.0) - 180.0
    assert np.max(np.abs(diff)) < 1e-9
    assert np.all(sign * q[:, 1] > 0)  # front elbow back, rear knee forward
    assert np.allclose(leg2_link_angles_deg(q), t[:, :2], atol=1e-12)
