"""Whole URDF files on small hand-written robots: locked joints (given, home, clipped), mimic
joints, continuous joints, the default end frame, legs named by foot or hip or found
automatically, the inertia tolerance, and every rejection naming what to change."""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest
from pydantic import ValidationError

from legcore.kinematics import fk
from legcore.robots import LeggedRobot, build_any_robot, build_robot, parse_robot_spec

INERTIAL = """<inertial><origin xyz="{c} 0 0"/><mass value="{m}"/>
  <inertia ixx="{i}" ixy="0" ixz="0" iyy="{i}" iyz="0" izz="{i}"/></inertial>"""


def link(name: str, m: float = 1.0, c: float = 0.05, i: float = 0.01, extra: str = "") -> str:
    return f'<link name="{name}">{INERTIAL.format(m=m, c=c, i=i)}{extra}</link>'


def joint(
    name: str,
    parent: str,
    child: str,
    kind: str = "revolute",
    xyz: str = "0 0 0",
    axis: str = "0 0 1",
    lo: float = -2.0,
    hi: float = 2.0,
    extra: str = "",
) -> str:
    lim = (
        ""
        if kind in ("fixed", "continuous")
        else (f'<limit lower="{lo}" upper="{hi}" effort="30" velocity="4"/>')
    )
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="0.1 -0.2 0.3"/><axis xyz="{axis}"/>{lim}{extra}</joint>'
    )


MESHES = (
    '<visual><geometry><mesh filename="/nonexistent/arm.stl"/></geometry></visual>'
    '<visual><geometry><mesh filename="file:///etc/passwd"/></geometry></visual>'
)

ARM = "\n".join(
    [
        '<robot name="arm">',
        link("base", extra=MESHES),
        link("l1"),
        link("l2"),
        link("l3"),
        link("hand", m=0.3),
        link("finger_l", m=0.05, i=1e-5),
        link("finger_r", m=0.05, i=1e-5),
        joint("j1", "base", "l1", xyz="0 0 0.1"),
        joint("j2", "l1", "l2", xyz="0 0 0.3", axis="0 1 0", lo=0.2, hi=1.5),
        joint("j3", "l2", "l3", kind="continuous", xyz="0.25 0 0", axis="1 0 0"),
        joint("hand_fix", "l3", "hand", kind="fixed", xyz="0.1 0 0"),
        joint(
            "f1", "hand", "finger_l", kind="prismatic", xyz="0.05 0 0", axis="0 1 0", lo=0, hi=0.04
        ),
        joint(
            "f2",
            "hand",
            "finger_r",
            kind="prismatic",
            xyz="0.05 0 0",
            axis="0 -1 0",
            lo=0,
            hi=0.04,
            extra='<mimic joint="f1" multiplier="1" offset="0"/>',
        ),
        "</robot>",
    ]
)


def quad(spine: bool = False, head: bool = False) -> str:
    """A two-legged toy (legs A, B: hip about x, knee about y, a fixed foot link)."""
    parts = [
        '<robot name="toy">',
        link(
            "base",
            m=4.0,
            extra=('<collision><geometry><box size="0.4 0.2 0.1"/></geometry></collision>'),
        ),
    ]
    top = "base"
    if spine:
        parts += [link("torso"), joint("spine", "base", "torso", axis="0 0 1")]
        top = "torso"
    for leg, y in (("A", 0.1), ("B", -0.1)):
        parts += [
            link(f"{leg}_thigh"),
            link(f"{leg}_shank"),
            link(f"{leg}_foot", m=0.01, i=1e-6),
            joint(f"{leg}_hip", top, f"{leg}_thigh", xyz=f"0.15 {y} 0", axis="1 0 0"),
            joint(f"{leg}_knee", f"{leg}_thigh", f"{leg}_shank", xyz="0 0 -0.2", axis="0 1 0"),
            joint(f"{leg}_ankle", f"{leg}_shank", f"{leg}_foot", kind="fixed", xyz="0 0 -0.2"),
        ]
    if head:
        parts += [link("head"), joint("neck", "base", "head", xyz="0.2 0 0.1")]
    return "\n".join([*parts, "</robot>"])


def spec(urdf: str, **extra: object) -> dict[str, object]:
    return {"kind": "urdf", "name": "r", "urdf": urdf, **extra}


def _pin_frame(text: str, q: dict[str, float], frame: str) -> np.ndarray:
    full = pin.buildModelFromXML(text)
    data = full.createData()
    qf = pin.neutral(full)
    for name, v in q.items():
        jm = full.joints[full.getJointId(name)]
        if jm.nq == 2:  # continuous: (cos, sin)
            qf[jm.idx_q : jm.idx_q + 2] = np.cos(v), np.sin(v)
        else:
            qf[jm.idx_q] = v
    pin.framesForwardKinematics(full, data, qf)
    fid = next(
        i for i, f in enumerate(full.frames) if f.name == frame and str(f.type).endswith("BODY")
    )
    return np.asarray(data.oMf[fid].homogeneous)


def test_locked_fingers_and_their_mimic_follow() -> None:
    robot = build_robot(spec(ARM, locked_joints={"f1": 0.03}))
    assert list(robot.model.names)[1:] == ["j1", "j2", "j3"]
    assert robot.meta["locked_joints"] == {"f1": 0.03, "f2": 0.03}
    assert robot.q_max[2] == pytest.approx(2 * np.pi) and np.isinf(robot.tau_max[2])
    assert robot.qd_max[2] == 10.0  # a continuous joint without <limit>: the default speed
    q = np.array([0.4, 0.9, -2.5])
    data = robot.data()
    pin.framesForwardKinematics(robot.model, data, q)
    held = {"j1": 0.4, "j2": 0.9, "j3": -2.5, "f1": 0.03, "f2": 0.03}
    for name in ("finger_l", "finger_r", "hand"):
        fid = next(i for i, f in enumerate(robot.model.frames) if f.name == name)
        np.testing.assert_allclose(
            data.oMf[fid].homogeneous, _pin_frame(ARM, held, name), atol=1e-12
        )
    # the default end frame is the leaf farthest from the last joint: a finger
    assert robot.meta["tool_source"] in ("finger_l", "finger_r")
    np.testing.assert_allclose(
        fk(robot, q), _pin_frame(ARM, held, robot.meta["tool_source"]), atol=1e-12
    )


def test_a_locked_joint_inside_the_chain() -> None:
    robot = build_robot(spec(ARM, locked_joints={"j2": 1.1, "f1": None}, tool_frame="hand"))
    assert list(robot.model.names)[1:] == ["j1", "j3"]
    held = {"j1": -0.7, "j2": 1.1, "j3": 0.5, "f1": 0.0, "f2": 0.0}
    np.testing.assert_allclose(fk(robot, [-0.7, 0.5]), _pin_frame(ARM, held, "hand"), atol=1e-12)


def test_home_values_are_clipped_to_the_limits() -> None:
    robot = build_robot(spec(ARM, locked_joints={"j2": None, "f1": None}))
    assert robot.meta["locked_joints"]["j2"] == 0.2  # zero is below j2's lower limit


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (
            {},
            "joint 'f2' mimics 'f1', which moves; a mimic joint moves only with its master: "
            "lock 'f1'",
        ),
        ({"locked_joints": {"f2": None}}, "lock 'f1'"),
        ({"locked_joints": {"f1": 0.01, "f2": 0.02}}, "locked_joints: 'f2' mimics 'f1'"),
        ({"locked_joints": {"f1": 0.5}}, "locked_joints: 'f1' value 0.5 is outside its limits"),
        ({"locked_joints": {"wrist": 0.1}}, "locked_joints: 'wrist' is not a moving joint"),
        ({"locked_joints": {"hand_fix": 0.1}}, "'hand_fix' is not a moving joint"),
        (
            {"locked_joints": {"f1": None}, "tool_frame": "l2"},
            "tool_frame: frame 'l2' is attached to 'j2', not to the chain's last moving joint 'j3'",
        ),
        ({"locked_joints": {"f1": None}, "tool_frame": "nope"}, "tool_frame: no frame named"),
        ({"locked_joints": {"f1": None, "j1": 0, "j2": None, "j3": 0}}, "no moving joint left"),
        ({"locked_joints": {"f1": None}, "motors": {"f9": {"G": 2}}}, "motors: unknown joint"),
    ],
)
def test_arm_rejections_say_what_to_change(extra: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError) as info:
        build_robot(spec(ARM, **extra))
    assert message in str(info.value)


def test_a_tree_is_not_a_chain_and_says_so() -> None:
    text = ARM.replace('<mimic joint="f1" multiplier="1" offset="0"/>', "")
    with pytest.raises(ValueError) as info:
        build_robot(spec(text))
    msg = str(info.value)
    assert "do not form one serial chain: 'f1', 'f2' all hang from 'j3'" in msg
    assert "locked_joints" in msg and "legs" in msg


def test_legs_auto_named_by_their_joints() -> None:
    robot = build_any_robot(spec(quad(), legs="auto"))
    assert isinstance(robot, LeggedRobot)
    assert [leg.name for leg in robot.legs] == ["A", "B"]
    assert robot.body_size == (0.4, 0.2, 0.1)  # the base link's collision box
    assert robot.body_mass == pytest.approx(4.0)
    a = robot.leg("A")
    np.testing.assert_allclose(a.hip[:3, 3], [0.15, 0.1, 0.0])
    assert a.robot.meta["tool_source"] == "A_foot"
    q = {"A_hip": 0.3, "A_knee": -0.8}
    T = a.hip @ fk(a.robot, [0.3, -0.8])
    np.testing.assert_allclose(T, _pin_frame(quad(), q, "A_foot"), atol=1e-12)


@pytest.mark.parametrize(
    "legs",
    [
        {"A": {"foot": "A_foot"}, "B": {"foot": "B_foot"}},
        {"A": {"hip": "A_hip"}, "B": {"hip": "B_hip", "foot": "B_foot"}},
    ],
)
def test_named_legs_equal_the_automatic_ones(legs: dict[str, object]) -> None:
    auto = build_any_robot(spec(quad(), legs="auto"))
    named = build_any_robot(spec(quad(), legs=legs))
    assert isinstance(auto, LeggedRobot) and isinstance(named, LeggedRobot)
    for x, y in zip(auto.legs, named.legs, strict=True):
        np.testing.assert_allclose(fk(x.robot, [0.2, 0.4]), fk(y.robot, [0.2, 0.4]), atol=1e-15)


def test_a_leg_mid_way_is_a_shorter_leg() -> None:
    """A foot named at the shank (the knee's child link): the leg ends there."""
    legs = {"A": {"foot": "A_shank"}, "B": {"foot": "B_foot"}}
    robot = build_any_robot(spec(quad(), legs=legs))
    assert isinstance(robot, LeggedRobot) and robot.leg("A").robot.nq == 2


@pytest.mark.parametrize(
    ("urdf", "extra", "message"),
    [
        (
            quad(head=True),
            {"legs": {"A": {"foot": "A_foot"}, "B": {"foot": "B_foot"}}},
            "legs: joint(s) ['neck'] belong to no leg; lock them (locked_joints)",
        ),
        (
            quad(spine=True),
            {"legs": "auto"},
            "legs: joint 'spine' belongs to legs 'A_foot' and 'B_foot'",
        ),
        (
            quad(spine=True),
            {"legs": {"A": {"hip": "spine"}, "B": {"foot": "B_foot"}}},
            "legs.A.hip: the joints below 'spine' branch at 'spine' ('A_hip', 'B_hip')",
        ),
        (
            quad(spine=True),
            {"legs": {"A": {"hip": "A_hip"}, "B": {"hip": "B_hip"}}},
            "legs.A: joint(s) ['spine'] between the base and the hip 'A_hip' move; lock them",
        ),
        (
            quad(),
            {"legs": {"A": {"foot": "base"}, "B": {"foot": "B_foot"}}},
            "legs.A.foot: 'base' is on the base",
        ),
        (
            quad(),
            {"legs": {"A": {"foot": "A_toe"}, "B": {"foot": "B_foot"}}},
            "legs.A.foot: no frame or link named 'A_toe'",
        ),
        (
            quad(),
            {"legs": {"A": {"hip": "B_hip", "foot": "A_foot"}, "B": {"foot": "B_foot"}}},
            "legs.A: hip 'B_hip' is not between the base and the foot 'A_foot'",
        ),
        (
            quad(),
            {"legs": {"A": {"hip": "A_ankle"}, "B": {"foot": "B_foot"}}},
            "legs.A.hip: no moving joint named 'A_ankle'",
        ),
        (quad(), {"legs": "auto", "leg": "C"}, "leg: no leg 'C'; the legs are ['A', 'B']"),
    ],
)
def test_leg_rejections_say_what_to_change(
    urdf: str, extra: dict[str, object], message: str
) -> None:
    with pytest.raises(ValueError) as info:
        build_any_robot(spec(urdf, **extra))
    assert message in str(info.value)


def test_locking_what_no_leg_uses_makes_legs() -> None:
    robot = build_any_robot(
        spec(quad(head=True, spine=True), legs="auto", locked_joints={"neck": 0.3, "spine": None})
    )
    assert isinstance(robot, LeggedRobot) and [g.name for g in robot.legs] == ["A", "B"]


def test_build_robot_refuses_a_whole_legged_robot_naming_the_leg_option() -> None:
    with pytest.raises(ValueError, match=r"legs: 'r' is a legged robot \(2 legs\).*give 'leg'"):
        build_robot(spec(quad(), legs="auto"))
    assert build_robot(spec(quad(), legs="auto", leg="B")).name == "r.B"


@pytest.mark.parametrize(
    ("extra", "loc", "message"),
    [
        ({"legs": "auto", "tool_frame": "x"}, "", "tool_frame: a legged robot's legs end"),
        ({"leg": "A"}, "", "leg: 'A' names a leg of a legged robot; give 'legs' too"),
        ({"legs": {"A": {"foot": "A_foot"}}, "leg": "B"}, "", "leg: no leg 'B' in legs ['A']"),
        ({"legs": {"A B": {"foot": "f"}}}, "legs", "should match pattern"),
        ({"legs": {}}, "legs", "1 to 8 legs"),
        ({"legs": {"A": {}}}, "legs", "name the leg by its 'hip' joint"),
        ({"legs": "all"}, "legs", ""),
        ({"locked_joints": {"f1": "open"}}, "locked_joints.f1", "valid number"),
    ],
)
def test_spec_field_errors(extra: dict[str, object], loc: str, message: str) -> None:
    with pytest.raises(ValidationError) as info:
        parse_robot_spec(spec(ARM, **extra))
    errors = [(".".join(str(p) for p in e["loc"]), e["msg"]) for e in info.value.errors()]
    assert any(lo.startswith(loc) and message in msg for lo, msg in errors), errors


def test_a_floating_joint_in_the_file_is_refused_naming_legs() -> None:
    text = quad().replace('type="revolute"', 'type="floating"', 1)
    with pytest.raises(ValueError, match="floating base comes from 'legs'"):
        build_any_robot(spec(text, legs="auto"))


def test_inertia_tolerance_is_relative_to_the_robot() -> None:
    """An 11 kg, 1 m robot: scale ≈ 11 kg·m², tolerance ≈ 1.1e-4 kg·m². A link violating the
    triangle inequality by 5e-5 kg·m² passes; by 5e-3 it is refused, naming the link and the
    fix."""

    def robot(violation: float) -> str:
        bad = (
            f'<link name="sensor"><inertial><mass value="0.001"/><inertia ixx="1e-6" '
            f'ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="{2e-6 + violation}"/></inertial></link>'
        )
        return "\n".join(
            [
                '<robot name="big">',
                link("base"),
                link("arm", m=10.0, c=1.0, i=1.0),
                bad,
                joint("j", "base", "arm"),
                joint("s", "arm", "sensor", kind="fixed", xyz="1 0 0"),
                "</robot>",
            ]
        )

    build_robot(spec(robot(5e-5)))
    with pytest.raises(ValueError) as info:
        build_robot(spec(robot(5e-3)))
    msg = str(info.value)
    assert msg.startswith("urdf: link 'sensor' inertia: principal moments")
    assert re.search(r"the tolerance is 1\.\de-04 kg·m²", msg), msg
    assert "correct the link's <inertia>" in msg
