"""Real robots' URDF files (example-robot-data) build as they are, with only what a user adds:
locked gripper joints, and ``legs`` for a legged robot. Each chain's kinematics and dynamics
equal Pinocchio's on the whole file (the other joints held where the chain holds them), and a
leg's end is its foot, not its knee."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin
import pytest

from legcore.dynamics import inverse_dynamics
from legcore.kinematics import fk
from legcore.robots import LeggedRobot, Robot, build_any_robot, build_robot

Urdf = Callable[[str], str]

ARMS = {
    # name: (extra spec fields, joints, end frame)
    "ur5": ({}, 6, "tool0"),
    "panda": ({"locked_joints": {"panda_finger_joint1": 0.02}}, 7, "panda_hand_tcp"),
    "kinova": ({}, 6, "j2s6s200_end_effector"),
    "z1": ({"locked_joints": {"jointGripper": None}}, 6, "gripperMover"),
    "so100": ({"locked_joints": {"gripper": None}}, 5, "jaw"),
}


def _full(text: str) -> tuple[pin.Model, pin.Data]:
    model = pin.buildModelFromXML(text)
    return model, model.createData()


def _body(model: pin.Model, name: str) -> int:
    return next(
        i for i, f in enumerate(model.frames) if f.name == name and f.type == pin.FrameType.BODY
    )


def _full_q(model: pin.Model, values: dict[str, float]) -> np.ndarray:
    q = pin.neutral(model)
    for name, v in values.items():
        q[model.joints[model.getJointId(name)].idx_q] = v
    return q


@pytest.mark.parametrize("name", sorted(ARMS))
def test_arm_builds_with_its_end_frame(name: str, erd_urdf: Urdf) -> None:
    extra, n, end = ARMS[name]
    robot = build_robot({"kind": "urdf", "name": name, "urdf": erd_urdf(name), **extra})
    assert robot.nq == n
    assert robot.meta["tool_source"] == end
    if name == "kinova":  # continuous joints become revolute ±2π
        assert robot.q_max[0] == pytest.approx(2 * np.pi)


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_arm_equals_pinocchio_on_the_whole_file(name: str, erd_urdf: Urdf) -> None:
    extra, n, end = ARMS[name]
    text = erd_urdf(name)
    robot = build_robot({"kind": "urdf", "name": name, "urdf": text, **extra})
    full, data = _full(text)
    held = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02} if name == "panda" else {}
    rng = np.random.default_rng(3)
    names = list(robot.model.names)[1:]
    tool = _body(full, end)
    for _ in range(5):
        q, qd, qdd = rng.uniform(-1.0, 1.0, (3, n))
        qf = _full_q(full, {**held, **dict(zip(names, q, strict=True))})
        vf, af = np.zeros(full.nv), np.zeros(full.nv)
        for i, jn in enumerate(names):
            iv = full.joints[full.getJointId(jn)].idx_v
            vf[iv], af[iv] = qd[i], qdd[i]
        pin.framesForwardKinematics(full, data, qf)
        np.testing.assert_allclose(fk(robot, q), data.oMf[tool].homogeneous, atol=1e-12)
        tau_full = pin.rnea(full, data, qf, vf, af)
        idx = [full.joints[full.getJointId(jn)].idx_v for jn in names]
        np.testing.assert_allclose(inverse_dynamics(robot, q, qd, qdd), tau_full[idx], atol=1e-9)


LEGGED = {
    "solo12": ({"legs": "auto"}, ("FL", "FR", "HL", "HR"), "{}_FOOT"),
    "anymal": ({"legs": "auto"}, ("LF", "LH", "RF", "RH"), "{}_FOOT"),
    "go1": (
        {
            "legs": {
                "FL": {"foot": "FL_foot"},
                "FR": {"hip": "FR_hip_joint"},
                "RL": {"hip": "RL_hip_joint", "foot": "RL_foot"},
                "RR": {"foot": "RR_foot"},
            }
        },
        ("FL", "FR", "RL", "RR"),
        "{}_foot",
    ),
}


@pytest.mark.parametrize("name", sorted(LEGGED))
def test_legged_robot_legs_are_the_files_legs(name: str, erd_urdf: Urdf) -> None:
    extra, legs, foot = LEGGED[name]
    text = erd_urdf(name)
    robot = build_any_robot({"kind": "urdf", "name": name, "urdf": text, **extra})
    assert isinstance(robot, LeggedRobot)
    assert tuple(leg.name for leg in robot.legs) == legs
    full, data = _full(text)
    assert robot.model is not None and robot.model.nq == 7 + full.nq  # free flyer + joints
    total = sum(full.inertias[j].mass for j in range(full.njoints))
    legs_mass = sum(leg.robot.chain.mass.sum() for leg in robot.legs)
    assert robot.body_mass + legs_mass == pytest.approx(total, rel=1e-12)
    rng = np.random.default_rng(7)
    for leg in robot.legs:
        rb = leg.robot
        assert rb.nq == 3 and rb.meta["tool_source"] == foot.format(leg.name)
        names = list(rb.model.names)[1:]
        foot_id = _body(full, foot.format(leg.name))
        idx = [full.joints[full.getJointId(jn)].idx_v for jn in names]
        for _ in range(3):
            q, qd, qdd = rng.uniform(-1.0, 1.0, (3, 3))
            qf = _full_q(full, dict(zip(names, q, strict=True)))
            vf, af = np.zeros(full.nv), np.zeros(full.nv)
            vf[idx], af[idx] = qd, qdd
            pin.framesForwardKinematics(full, data, qf)
            # the foot, in the body frame, through the leg's chain and its hip placement
            T = leg.hip @ fk(rb, q)
            np.testing.assert_allclose(T, data.oMf[foot_id].homogeneous, atol=1e-12)
            tau = inverse_dynamics(rb, q, qd, qdd)
            np.testing.assert_allclose(tau, pin.rnea(full, data, qf, vf, af)[idx], atol=1e-9)


def test_one_leg_is_a_serial_chain_ending_at_its_foot(erd_urdf: Urdf) -> None:
    text = erd_urdf("solo12")
    spec = {"kind": "urdf", "name": "solo12", "urdf": text, "legs": "auto", "leg": "FL"}
    leg = build_robot(spec)
    assert isinstance(leg, Robot) and leg.name == "solo12.FL"
    assert list(leg.model.names)[1:] == ["FL_HAA", "FL_HFE", "FL_KFE"]
    full, data = _full(text)
    pin.framesForwardKinematics(full, data, pin.neutral(full))
    hip = data.oMi[full.getJointId("FL_HAA")].translation
    foot = data.oMf[_body(full, "FL_FOOT")].translation
    knee = data.oMi[full.getJointId("FL_KFE")].translation
    tip = fk(leg, np.zeros(3))[:3, 3]
    np.testing.assert_allclose(tip, foot - hip, atol=1e-12)  # base at the hip, body axes
    assert np.linalg.norm(tip - (knee - hip)) > 0.1  # the foot, not the knee
    # the leg's own spec rebuilds the same leg (it is what a job stores)
    again = build_robot(leg.spec)
    np.testing.assert_allclose(fk(again, [0.3, -0.5, 1.1]), fk(leg, [0.3, -0.5, 1.1]))


def test_tiny_dummy_inertias_are_accepted(erd_urdf: Urdf) -> None:
    """ANYmal's and Go1's base links are 1e-6 kg dummies whose inertia (all six entries 1e-6)
    is slightly unphysical: negligible at the robot's scale, so accepted."""
    for name in ("anymal", "go1"):
        assert "1e-6" in erd_urdf(name).replace("1e-06", "1e-6")
        build_any_robot({"kind": "urdf", "name": name, "urdf": erd_urdf(name), "legs": "auto"})


def test_a_wrong_link_inertia_is_refused_saying_what_to_change(erd_urdf: Urdf) -> None:
    """ANYmal C's front camera violates I_a + I_b >= I_c by half its largest moment."""
    with pytest.raises(ValueError) as info:
        build_any_robot({"kind": "urdf", "name": "c", "urdf": erd_urdf("anymal_c"), "legs": "auto"})
    msg = str(info.value)
    assert msg.startswith("urdf: link 'depth_camera_front_camera' inertia:")
    assert "triangle inequality" in msg and "correct the link's <inertia>" in msg


def test_legs_auto_leaves_an_arm_out_and_says_which_joints_to_lock(erd_urdf: Urdf) -> None:
    """ANYmal with a Kinova arm: ``legs: auto`` takes the four lowest branch ends as legs and
    refuses the moving arm, naming its joints; with them locked the robot has its 4 legs."""
    urdf = erd_urdf("anymal_kinova")
    with pytest.raises(ValueError) as info:
        build_any_robot({"kind": "urdf", "name": "ak", "urdf": urdf, "legs": "auto"})
    msg = str(info.value)
    assert msg.startswith("legs: auto found 4 legs") and "locked_joints" in msg
    arm = [f"j2s6s200_joint_{i}" for i in range(1, 7)]
    assert all(j in msg for j in arm)
    robot = build_any_robot({"kind": "urdf", "name": "ak", "urdf": urdf, "legs": "auto",
                             "locked_joints": dict.fromkeys(arm)})  # fmt: skip
    assert sorted(leg.name for leg in robot.legs) == ["LF", "LH", "RF", "RH"]


def test_anymal_named_legs_equal_legs_auto(erd_urdf: Urdf) -> None:
    """ANYmal with its legs named by foot frame (the file's ``LF_FOOT`` … links), and by hip
    joint + foot, builds the same robot as ``legs: auto``: same legs in the same order, same
    joints, hips, foot frames, masses, limits, kinematics and dynamics. (Named legs keep the
    order they are written in; ``auto`` takes them in the model's joint order.)"""
    text = erd_urdf("anymal")
    auto = build_any_robot({"kind": "urdf", "name": "anymal", "urdf": text, "legs": "auto"})
    by_foot = {n: {"foot": f"{n}_FOOT"} for n in ("LF", "LH", "RF", "RH")}  # the model's order
    by_hip_and_foot = {n: {"hip": f"{n}_HAA", "foot": f"{n}_FOOT"} for n in by_foot}
    rng = np.random.default_rng(11)
    q, qd, qdd = rng.uniform(-1.0, 1.0, (3, 4, 3))
    assert isinstance(auto, LeggedRobot)
    for legs in (by_foot, by_hip_and_foot):
        named = build_any_robot({"kind": "urdf", "name": "anymal", "urdf": text, "legs": legs})
        assert isinstance(named, LeggedRobot)
        assert [leg.name for leg in named.legs] == [leg.name for leg in auto.legs]
        assert named.body_mass == auto.body_mass and named.body_size == auto.body_size
        assert named.model is not None and auto.model is not None
        assert list(named.model.names) == list(auto.model.names)
        for k, (a, b) in enumerate(zip(auto.legs, named.legs, strict=True)):
            ra, rb = a.robot, b.robot
            assert b.robot.meta["tool_source"] == a.robot.meta["tool_source"] == f"{a.name}_FOOT"
            assert list(rb.model.names) == list(ra.model.names)
            np.testing.assert_array_equal(b.hip, a.hip)
            np.testing.assert_array_equal(rb.chain.mass, ra.chain.mass)
            for lim in ("q_min", "q_max", "qd_max", "tau_max"):
                np.testing.assert_array_equal(getattr(rb, lim), getattr(ra, lim))
            np.testing.assert_array_equal(fk(rb, q[k]), fk(ra, q[k]))
            np.testing.assert_array_equal(inverse_dynamics(rb, q[k], qd[k], qdd[k]),
                                          inverse_dynamics(ra, q[k], qd[k], qdd[k]))


@pytest.mark.parametrize(("name", "default", "chosen"),
                         [("z1", "gripperMover", "gripperStator"), ("so100", "jaw", "gripper")])
def test_locked_fingers_end_at_the_farthest_leaf_unless_tool_frame(
    name: str, default: str, chosen: str, erd_urdf: Urdf
) -> None:
    """docs/robots.md "Limits": with the gripper locked the default end is the farthest leaf —
    a finger link — and ``tool_frame`` puts it where the user means (Pinocchio on the file)."""
    extra, n, _ = ARMS[name]
    text = erd_urdf(name)
    robot = build_robot({"kind": "urdf", "name": name, "urdf": text, **extra})
    assert robot.meta["tool_source"] == default
    chosen_robot = build_robot({"kind": "urdf", "name": name, "urdf": text, **extra,
                                "tool_frame": chosen})
    assert chosen_robot.meta["tool_source"] == chosen
    full, data = _full(text)
    names = list(robot.model.names)[1:]
    q = np.random.default_rng(5).uniform(-1.0, 1.0, n)
    pin.framesForwardKinematics(full, data, _full_q(full, dict(zip(names, q, strict=True))))
    for rb, frame in ((robot, default), (chosen_robot, chosen)):
        np.testing.assert_allclose(fk(rb, q), data.oMf[_body(full, frame)].homogeneous,
                                   atol=1e-12)
    assert not np.allclose(fk(robot, q)[:3, 3], fk(chosen_robot, q)[:3, 3], atol=1e-3)
