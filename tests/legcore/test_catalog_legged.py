"""Catalog entries ``citedi_hexapod`` (seed 002) and ``animatronic_quadruped`` (seed 003)."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from legcore.gaits import TRIPOD
from legcore.ik import ELBOW_BACK, KNEE_FORWARD, leg2_fk, leg2_ik, leg3_fk, leg3_ik
from legcore.robots import LeggedRobot, Robot, build_robot
from legcore.robots.catalog import animatronic_quadruped, citedi_hexapod
from legcore.tripod_stability import UNBOUNDED_SPANS, tripod_feet, tripod_stability


@pytest.fixture(scope="module")
def hexapod() -> LeggedRobot:
    return citedi_hexapod.build()


@pytest.fixture(scope="module")
def quadruped() -> LeggedRobot:
    return animatronic_quadruped.build()


def _pin_foot(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Foot (tool frame) positions (B, 3) by Pinocchio, in the leg base frame."""
    data = robot.data()
    out = np.empty((len(q), 3))
    for k, qk in enumerate(q):
        pin.forwardKinematics(robot.model, data, qk)
        pin.updateFramePlacements(robot.model, data)
        out[k] = data.oMf[robot.tool_frame].translation
    return out


def _random_q(robot: Robot, n: int, rng: np.random.Generator) -> np.ndarray:
    return rng.uniform(robot.q_min, robot.q_max, (n, robot.nq))


# ---------------------------------------------------------------- hexapod (seed 002)


def test_hexapod_layout(hexapod: LeggedRobot) -> None:
    assert [leg.name for leg in hexapod.legs] == list(TRIPOD.legs)
    assert hexapod.body_size[:2] == (0.07, 0.10)
    cm = {leg.name: (leg.hip[:3, 3] * 100).round(9).tolist() for leg in hexapod.legs}
    assert cm == {
        "L1": [3.5, 5.0, 0.0], "L2": [3.5, 0.0, 0.0], "L3": [3.5, -5.0, 0.0],
        "L4": [-3.5, 5.0, 0.0], "L5": [-3.5, 0.0, 0.0], "L6": [-3.5, -5.0, 0.0],
    }  # fmt: skip
    for leg in hexapod.legs:  # legs point +x on the x > 0 side, −x on the other
        assert leg.hip[0, 0] == pytest.approx(math.copysign(1.0, leg.hip[0, 3]))
    robot = hexapod.legs[0].robot
    assert robot.ik_family == "leg3" and robot.nq == 3
    assert np.allclose(robot.q_min, [-math.pi / 6, -math.pi / 2, -math.pi / 2])


def test_hexapod_home_foot_height(hexapod: LeggedRobot) -> None:
    for leg in hexapod.legs:
        foot = leg.foot_in_body(leg3_fk(leg.robot.home, citedi_hexapod.LINKS))
        assert foot[2] * 100 == pytest.approx(-6.8827, abs=1e-4)  # seed 002 §4


# Seed 002 Table 2: solution -> [(leg, θ1, x cm, y cm), ...] as printed.
TABLE2 = {
    "a": [
        ("L1", 0.3883, 9.544, 7.472), ("L3", 0.5103, 9.198, -1.81), ("L5", 0.3975, -9.52, -2.528),
    ],
    "b": [
        ("L1", -0.5236, 9.155, 1.735), ("L3", -0.2223, 9.869, -6.44),
        ("L5", 0.4682, -9.327, -2.947),
    ],
    "c": [
        ("L1", -0.3883, 9.544, 2.528), ("L3", -0.5103, 9.198, -8.19),
        ("L5", -0.3975, -9.521, 2.528),
    ],
    "d": [
        ("L1", -0.3883, 9.544, 2.528), ("L3", -0.5069, 9.209, -8.17),
        ("L5", -0.3975, -9.521, 2.528),
    ],
}  # fmt: skip


@pytest.mark.parametrize("solution", sorted(TABLE2))
def test_hexapod_table2_foot_positions(hexapod: LeggedRobot, solution: str) -> None:
    rows = TABLE2[solution]
    for name, th1, x, y in rows:
        leg = hexapod.leg(name)
        q = [th1, citedi_hexapod.THETA2_0, citedi_hexapod.THETA3_0]
        foot = leg.foot_in_body(leg3_fk(q, citedi_hexapod.LINKS)) * 100.0
        assert foot[0] == pytest.approx(x, abs=1e-3)
        assert foot[1] == pytest.approx(y, abs=1e-3)
    # the same through the population helper of legcore.gaits
    th1 = np.array([[r[1] for r in rows]])
    hips = np.stack([hexapod.leg(r[0]).hip for r in rows])
    F = tripod_feet(
        th1, hips, citedi_hexapod.LINKS, citedi_hexapod.THETA2_0, citedi_hexapod.THETA3_0
    )
    assert np.allclose(F[0, :, :2] * 100, [[r[2], r[3]] for r in rows], atol=1e-3)


@pytest.mark.parametrize("solution", sorted(TABLE2))
def test_hexapod_table2_stability_matches_fig9(hexapod: LeggedRobot, solution: str) -> None:
    # Seed 002 Fig. 9b: one of the four Pareto solutions is not viable, the body centre being
    # outside the support triangle. From the printed feet that is solution b.
    th1 = np.array([r[1] for r in TABLE2[solution]])
    hips = np.stack([hexapod.leg(r[0]).hip for r in TABLE2[solution]])
    F = tripod_feet(
        th1, hips, citedi_hexapod.LINKS, citedi_hexapod.THETA2_0, citedi_hexapod.THETA3_0
    )
    p1, p3, p5 = F[0, :2], F[1, :2], F[2, :2]
    s_f, s_b = tripod_stability(front=p1, middle=p5, back=p3)
    # independent: barycentric coordinates of the centre (0, 0) in triangle (1, 3, 5)
    A = np.column_stack((p3 - p1, p5 - p1))
    u, v = np.linalg.solve(A, -p1)
    inside = u > 0 and v > 0 and u + v < 1
    assert inside == (solution != "b")
    assert inside == (s_f > 0 and s_b > 0)
    # |S_f| is the x distance from the centre to the 5-1 diagonal at y = 0 (inf if parallel)
    t = -p5[1] / (p1[1] - p5[1]) if p1[1] != p5[1] else np.inf
    x_line = p5[0] + t * (p1[0] - p5[0]) if np.isfinite(t) else np.inf
    # ... reported as unbounded (inf) beyond UNBOUNDED_SPANS tripod spans: solutions c's and d's
    # 16 642.8 m measures how parallel the diagonal is to x, not a stability distance
    span = max(np.linalg.norm(p1 - p5), np.linalg.norm(p3 - p5), np.linalg.norm(p5))
    if abs(x_line) > UNBOUNDED_SPANS * span:
        assert s_f == np.inf and solution in ("c", "d")
    else:
        assert abs(s_f) == pytest.approx(abs(x_line), abs=1e-12)


def test_hexapod_pinocchio_fk_matches_closed_form(hexapod: LeggedRobot) -> None:
    rng = np.random.default_rng(7)
    robot = hexapod.legs[0].robot
    q = _random_q(robot, 60, rng)
    p_pin = _pin_foot(robot, q)
    assert np.max(np.abs(p_pin - leg3_fk(q, citedi_hexapod.LINKS))) < 1e-12
    for leg in hexapod.legs:  # body frame: the chain built with the hip as its DH base
        based = build_robot(citedi_hexapod.leg_spec().model_copy(update={"base": leg.hip.tolist()}))
        p_body = _pin_foot(based, q)
        assert np.max(np.abs(p_body - leg.foot_in_body(leg3_fk(q, citedi_hexapod.LINKS)))) < 1e-12
    q_ik, ok = leg3_ik(
        p_pin, citedi_hexapod.LINKS, branch=np.sign(q[:, 2]), q_min=robot.q_min, q_max=robot.q_max
    )
    assert ok.all() and np.allclose(q_ik, q, atol=1e-9)


# ---------------------------------------------------------------- quadruped (seed 003)


def test_quadruped_layout_and_branches(quadruped: LeggedRobot) -> None:
    assert [leg.name for leg in quadruped.legs] == ["FL", "FR", "RL", "RR"]
    for leg in quadruped.legs:
        x, y, z = leg.hip[:3, 3]
        assert (abs(x), abs(y), z) == pytest.approx((0.11, 0.063, -0.02))
        assert (x > 0) == leg.name.startswith("F") and (y > 0) == leg.name.endswith("L")
        # leg frame: x down, y forward, z to the right
        assert np.allclose(leg.hip[:3, :3], [[0, 1, 0], [0, 0, -1], [-1, 0, 0]])
        r = leg.robot
        assert r.ik_family == "leg2" and r.nq == 2
        sign = animatronic_quadruped.BRANCH[leg.name]
        assert sign == (ELBOW_BACK if leg.name.startswith("F") else KNEE_FORWARD)
        assert sign * r.q_min[1] >= 0 and sign * r.q_max[1] >= 0  # limits hold the branch
        home_foot = leg.foot_in_body(leg2_fk(r.home, animatronic_quadruped.LINKS))
        assert home_foot == pytest.approx([x, y, z - 0.175], abs=1e-12)  # straight below
        assert abs(math.degrees(r.home[1])) == pytest.approx(19.3, abs=0.05)


def test_quadruped_pinocchio_fk_matches_closed_form(quadruped: LeggedRobot) -> None:
    rng = np.random.default_rng(8)
    for leg in quadruped.legs[::2]:  # one front, one rear chain
        robot = leg.robot
        q = _random_q(robot, 60, rng)
        p_pin = _pin_foot(robot, q)
        assert np.max(np.abs(p_pin - leg2_fk(q, animatronic_quadruped.LINKS))) < 1e-12
        spec = robot.spec.model_copy(update={"base": leg.hip.tolist()})
        p_body = _pin_foot(build_robot(spec), q)
        expect = leg.foot_in_body(leg2_fk(q, animatronic_quadruped.LINKS))
        assert np.max(np.abs(p_body - expect)) < 1e-12
        branch = animatronic_quadruped.BRANCH[leg.name]
        q_ik, ok = leg2_ik(p_pin, animatronic_quadruped.LINKS, branch, robot.q_min, robot.q_max)
        assert ok.all() and np.allclose(q_ik, q, atol=1e-9)


def test_quadruped_thigh_length_choice_levels_table2_stroke() -> None:
    # Seed 003 Table 2, first and last printed positions (link angles Ang3, Ang4 in degrees).
    ends = {"front": ((81, 61), (119, 102)), "rear": ((60, 80), (102, 118))}

    def depth(l1: float, ang: tuple[int, int]) -> float:
        q3 = math.radians(90 - ang[0])
        q34 = math.radians(90 - ang[1])
        return l1 * math.cos(q3) + 0.0925 * math.cos(q34)

    d85 = [depth(0.085, a) for pair in ends.values() for a in pair]
    d65 = [depth(0.065, a) for pair in ends.values() for a in pair]
    assert max(d85) - min(d85) < 0.0002  # eq (1)'s 0.085 m: all four ends level within 0.2 mm
    assert max(d65) - min(d65) > 0.002  # Table 1's 0.065 m: > 2 mm apart
    assert animatronic_quadruped.LINKS == (0.085, 0.0925)


def test_quadruped_servo_meta_reproduces_table2(quadruped: LeggedRobot) -> None:
    servo = quadruped.meta["servo"]  # type: ignore[index]
    off = np.array(servo["link_angle_offset_deg"])
    M = np.array(servo["link_angle_matrix"])
    for _, front, rear in animatronic_quadruped.TABLE2:
        for ang3, ang4, q3, q4 in (front, rear):
            q_deg = np.array([q3, q4], dtype=float)
            q_deg = np.mod(q_deg + 180.0, 360.0) - 180.0
            assert off + M @ q_deg == pytest.approx([ang3, ang4], abs=1e-9)
