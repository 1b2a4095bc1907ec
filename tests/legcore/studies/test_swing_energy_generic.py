"""``swing_energy`` on any leg (issue 9): chains of 2–6 joints, one leg of a legged robot, a
named foot frame, obstacle boxes, the ground height, exact ends, and the IK of the foot
positions (closed form for seed 000's leg, numerical otherwise — they agree)."""

from __future__ import annotations

import numpy as np
import pytest

from legcore.ik import solve
from legcore.kinematics import fk
from legcore.robots import build_robot, catalog
from legcore.studies.registry import get_study
from legcore.studies.swing_energy.problem import Params, SwingEnergyProblem
from legcore.studies.swing_energy.study import build

LEG = catalog.get("calderon_leg")


def _planar(n: int) -> dict[str, object]:
    """An n-joint leg hanging from its hip: joint 1 yaw, then pitch joints (z up)."""
    joints = [{"alpha": np.pi / 2, "a": 0.02, "mass": 0.1, "com": [-0.01, 0, 0],
               "inertia": [[1e-6, 0, 0], [0, 1e-5, 0], [0, 0, 1e-5]]}]
    joints += [{"a": 0.25 / (n - 1), "mass": 0.1, "com": [-0.05, 0, 0],
                "inertia": [[1e-6, 0, 0], [0, 5e-5, 0], [0, 0, 5e-5]]} for _ in range(n - 1)]
    return {"kind": "dh", "name": f"leg{n}", "joints": joints}


@pytest.mark.parametrize("n", [2, 4, 6])
def test_any_number_of_joints_with_exact_feet(n: int) -> None:
    robot = build_robot(_planar(n))
    q0 = np.r_[0.0, -0.6, np.full(n - 2, 1.2 / max(n - 2, 1))] if n > 2 else np.array([0.0, -0.8])
    yaw = np.zeros(n)
    yaw[0] = 0.15
    start, end = fk(robot, q0 - yaw)[:3, 3], fk(robot, q0 + yaw)[:3, 3]
    p = build(robot, Params(foot_start=tuple(start), foot_end=tuple(end), exact_ends=True,
                            T=1.0, dt=0.02, baselines=("calderon2008_parabolic",)))
    assert p.n_var == 10 * n and p.w_d.shape == (n,) and p.w_d.sum() == pytest.approx(1.0)
    sol = p.solution(p.coordinated_x())
    np.testing.assert_allclose(sol.motion.tool[[0, -1]], [start, end], atol=1e-9)
    base = p.baseline_solutions()
    if n == 2:  # yaw + one pitch joint: the foot moves on a sphere, a parabola is out of reach
        assert base == {}
    else:
        assert base["calderon2008_parabolic"].metrics["lift_height"] > 0.02
    with pytest.raises(ValueError, match="^w_d: 3 values for a leg of"):
        build(robot, Params(foot_start=tuple(start), foot_end=tuple(end), w_d=(0.2, 0.3, 0.5)))


def test_foot_ik_closed_form_equals_the_numerical_one() -> None:
    p = build(LEG, Params())
    feet = np.stack([p.foot_start, p.foot_end])
    cf = solve(LEG, feet, "position", q0=p.q_start)
    num = solve(LEG, feet, "position", q0=p.q_start, method="numeric")
    assert cf.method == "leg3" and num.reachable.all()
    np.testing.assert_allclose(num.q, cf.q, atol=1e-8)


def test_foot_frame_boxes_and_ground_height() -> None:
    spec = _planar(3)
    robot = build_robot(spec)
    name = robot.model.frames[robot.link_frames[-2]].name  # a frame on joint 2: refused
    with pytest.raises(ValueError, match="^foot_frame: .* is not attached to the last joint"):
        build(robot, Params(q_start=(0, -0.6, 1.2), q_end=(0.1, -0.6, 1.2), foot_frame=name))
    with pytest.raises(ValueError, match="^foot_frame: no frame 'nope'"):
        build(robot, Params(q_start=(0, -0.6, 1.2), q_end=(0.1, -0.6, 1.2), foot_frame="nope"))
    base = {"q_start": (-0.2, -0.6, 1.2), "q_end": (0.2, -0.6, 1.2)}
    p = build(robot, Params(**base))
    mid = 0.5 * (p.foot_start + p.foot_end)
    box = {"center": tuple(mid + [0, 0, 0.01]), "size": (0.02, 0.02, 0.02), "margin": 0.001}
    q = build(robot, Params(**base, obstacles=(box,), ground_height=float(p.z_ground) - 0.01))
    assert q.z_ground == pytest.approx(p.z_ground - 0.01) and len(q.boxes) == 1
    assert q.constraint_names == ("ground", "obstacle")
    _, G = q.evaluate(q.coordinated_x()[None])
    assert G[0, 1] > 0.0  # the coordinated swing goes through the box
    with pytest.raises(ValueError, match="^ground_height: 0.5 m is above"):
        build(robot, Params(**base, ground_height=0.5))


def test_a_leg_of_a_legged_robot_and_the_refusals() -> None:
    quad = catalog.get("animatronic_quadruped")
    # its legs' base frames have x down (seed 003): swing_energy needs z up
    with pytest.raises(ValueError, match="^robot: swing_energy needs the leg's base frame with z"):
        build(quad, Params(leg="FL", q_start=(0.1, 0.3), q_end=(-0.1, 0.3)))
    # with no leg named, its first front leg (FL) swings: refused the same way
    with pytest.raises(ValueError, match="^robot: .* animatronic_quadruped.FL has gravity"):
        build(quad, Params())
    with pytest.raises(ValueError, match="^leg: robot 'animatronic_quadruped' has no leg 'XX'"):
        build(quad, Params(leg="XX"))
    with pytest.raises(ValueError, match="^leg: robot 'calderon_leg' is a serial chain"):
        build(LEG, Params(leg="FL"))
    hexapod = catalog.get("citedi_hexapod")
    p = get_study("swing_energy").build(hexapod, Params(leg="L1", q_start=(-0.2, -0.3, -0.6),
                                                       q_end=(0.2, -0.3, -0.6)))
    assert isinstance(p, SwingEnergyProblem) and p.label == "citedi_hexapod.L1"
    m = p.solution(p.coordinated_x()).motion
    assert m.legs == ("L1",) and m.robot == "citedi_hexapod"
    hip = hexapod.leg("L1").hip
    assert m.scene["ground_z"] == pytest.approx(p.z_ground + hip[2, 3])
