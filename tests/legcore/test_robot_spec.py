"""Robot specification validation: every bad model is rejected with the field and the reason."""

from __future__ import annotations

import math

import pytest
from pydantic import ValidationError

from legcore.robots import build_robot, parse_robot_spec


def _joint(**over):
    j = {
        "type": "revolute",
        "d": 0.0,
        "a": 0.3,
        "alpha": 0.0,
        "q_min": -1.0,
        "q_max": 1.0,
        "mass": 1.0,
        "com": [-0.15, 0.0, 0.0],
        "inertia": [[0.001, 0, 0], [0, 0.008, 0], [0, 0, 0.008]],
    }
    j.update(over)
    return j


def _spec(*joints, **over):
    s = {"kind": "dh", "name": "arm", "joints": list(joints) or [_joint(), _joint()]}
    s.update(over)
    return s


def _errors(data) -> list[tuple[str, str]]:
    with pytest.raises(ValidationError) as info:
        parse_robot_spec(data)
    return [(".".join(str(p) for p in e["loc"]), e["msg"]) for e in info.value.errors()]


def test_valid_spec_builds():
    robot = build_robot(_spec())
    assert robot.nq == 2
    assert robot.model.nq == 2


@pytest.mark.parametrize(
    ("joint_over", "field", "reason"),
    [
        ({"mass": -1.0}, "joints.1.mass", "mass must be >= 0"),
        (
            {"inertia": [[0.001, 0, 0], [0, -0.008, 0], [0, 0, 0.008]]},
            "joints.1.inertia",
            "not positive semi-definite",
        ),
        (
            {"inertia": [[0.001, 0.002, 0], [0, 0.008, 0], [0, 0, 0.008]]},
            "joints.1.inertia",
            "not symmetric",
        ),
        (
            {"inertia": [[0.001, 0, 0], [0, 0.001, 0], [0, 0, 0.008]]},
            "joints.1.inertia",
            "triangle inequality",
        ),
        ({"q_min": 1.0, "q_max": -1.0}, "joints.1", "q_min (1.0) must be < q_max (-1.0)"),
        ({"type": "spherical"}, "joints.1.type", "Input should be 'revolute' or 'prismatic'"),
        ({"a": math.nan}, "joints.1.a", "finite number"),
        ({"d": math.inf}, "joints.1.d", "finite number"),
        ({"com": [0.0, 0.0]}, "joints.1.com", "at least 3 items"),
        ({"colour": "red"}, "joints.1.colour", "Extra inputs are not permitted"),
        ({"qd_max": 0.0}, "joints.1.qd_max", "must be > 0"),
    ],
)
def test_bad_joint_is_rejected_naming_the_field(joint_over, field, reason):
    errors = _errors(_spec(_joint(), _joint(**joint_over)))
    assert any(loc.startswith(field) and reason in msg for loc, msg in errors), errors


def test_nan_inside_inertia_names_the_entry():
    errors = _errors(_spec(_joint(inertia=[[math.nan, 0, 0], [0, 1, 0], [0, 0, 1]])))
    assert any(loc.startswith("joints.0.inertia.0.0") for loc, _ in errors), errors


def test_too_many_or_no_joints():
    assert any(loc == "joints" for loc, _ in _errors(_spec(*[_joint()] * 13)))
    assert any(loc == "joints" for loc, _ in _errors({"kind": "dh", "name": "x", "joints": []}))


def test_unknown_kind_and_home_checks():
    assert any("kind" in loc or "tag" in msg for loc, msg in _errors({"kind": "sdf", "name": "x"}))
    errors = _errors(_spec(_joint(), home=[0.0, 0.0]))
    assert any("home" in msg for _, msg in errors), errors
    errors = _errors(_spec(_joint(), _joint(), home=[0.0, 2.0]))
    assert any("home.1" in msg for _, msg in errors), errors


def test_bad_base_transform():
    base = [[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
    errors = _errors(_spec(base=base))
    assert any("base" in msg and "rotation" in msg for _, msg in errors), errors


def test_bad_motor_data():
    errors = _errors(_spec(_joint(motor={"G": 0.0})))
    assert any(loc == "joints.0.motor.G" for loc, _ in errors), errors
    errors = _errors(_spec(_joint(motor={"R": -1.0})))
    assert any(loc == "joints.0.motor.R" for loc, _ in errors), errors


URDF_BAD_INERTIA = """<robot name="r">
  <link name="base"/>
  <link name="thigh"><inertial><mass value="1"/><origin xyz="0 0 0"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="thigh"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="10" velocity="2"/></joint>
</robot>"""


def test_urdf_physical_checks_name_the_link():
    with pytest.raises(ValueError, match="link 'thigh' inertia: .*triangle inequality"):
        build_robot({"kind": "urdf", "name": "r", "urdf": URDF_BAD_INERTIA})
    with pytest.raises(ValueError, match="urdf: not well-formed XML"):
        build_robot({"kind": "urdf", "name": "r", "urdf": "<robot"})
    neg = URDF_BAD_INERTIA.replace('mass value="1"', 'mass value="-1"')
    with pytest.raises(ValueError, match="link 'thigh' mass"):
        build_robot({"kind": "urdf", "name": "r", "urdf": neg})
