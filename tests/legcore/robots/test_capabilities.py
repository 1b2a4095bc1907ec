"""What a robot offers (capabilities) and why a study refuses it: the reason names the missing
capability and what the robot has, never a robot family."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from legcore.robots import build_any_robot, build_robot, catalog
from legcore.robots.capabilities import Needs, capabilities, refusal, require


def test_catalog_capabilities() -> None:
    puma = capabilities(catalog.get("puma560"))
    assert puma.kind == "serial" and puma.serial_chain and puma.n_actuated == 6
    assert puma.ik_family == "puma560" and puma.electrical_joints == 3 and not puma.electrical
    assert puma.end_frame == "tool" and puma.legs == ()
    quad = capabilities(catalog.get("animatronic_quadruped"))
    assert quad.kind == "legged" and len(quad.legs) == 4 and not quad.floating_base
    assert quad.n_actuated == sum(leg.n_joints for leg in quad.legs)
    assert quad.as_dict()["legs"][0]["name"] == quad.legs[0].name


@pytest.mark.parametrize(
    ("robot", "needs", "reason"),
    [
        ("calderon_leg", Needs(serial=True, min_joints=5),
         "path_tracking needs ≥ 5 actuated joints; robot calderon_leg has 3"),
        ("puma560", Needs(serial=True, min_joints=5), None),
        ("articulated_5dof", Needs(serial=True, min_joints=6),
         "path_tracking needs ≥ 6 actuated joints; robot articulated_5dof has 5"),
        ("animatronic_quadruped", Needs(serial=True),
         "path_tracking needs a serial chain; robot animatronic_quadruped is legged"),
        ("puma560", Needs(legged=True),
         "path_tracking needs a legged robot; robot puma560 is a serial chain"),
        ("animatronic_quadruped", Needs(legged=True, n_legs=(4,), leg_joints=(2, 3)), None),
        ("citedi_hexapod", Needs(legged=True, n_legs=(4,)),
         "path_tracking needs 4 legs; robot citedi_hexapod has 6 legs"),
        ("calderon_leg", Needs(electrical=True),
         "path_tracking needs motor data (Kt, Ke, R) on every joint for the electrical energy; "
         "robot calderon_leg has it on 0 of 3"),
        ("calderon_leg", Needs(serial=True, min_joints=2, max_joints=6), None),
    ],
)  # fmt: skip
def test_refusal_names_the_missing_capability(robot: str, needs: Needs, reason: str | None) -> None:
    got = refusal("path_tracking", needs, catalog.get(robot))
    if reason is None:
        assert got is None
    else:
        assert got is not None and got.startswith(reason), got


def test_require_raises_on_the_robot_field() -> None:
    joints = [{"a": 0.1, "mass": 1.0, "inertia": [[0.01, 0, 0], [0, 0.01, 0], [0, 0, 0.01]]}] * 7
    seven = build_robot({"kind": "dh", "name": "seven", "joints": joints})
    with pytest.raises(ValueError, match=r"^robot: swing_energy needs 2–6 actuated joints; "):
        require("swing_energy", Needs(min_joints=2, max_joints=6), seven)
    require("swing_energy", Needs(min_joints=2, max_joints=6), catalog.get("calderon_leg"))


def test_urdf_robots_capabilities(erd_urdf: Callable[[str], str]) -> None:
    go1 = capabilities(
        build_any_robot({"kind": "urdf", "name": "go1", "urdf": erd_urdf("go1"), "legs": "auto"})
    )
    assert go1.kind == "legged" and go1.floating_base and go1.n_actuated == 12
    assert [(g.name, g.n_joints, g.foot_frame) for g in go1.legs][0] == ("FL", 3, "FL_foot")
    assert go1.joint_names[0] == "FL.FL_hip_joint" and go1.torque_limits
    ur5 = capabilities(build_any_robot({"kind": "urdf", "name": "ur5", "urdf": erd_urdf("ur5")}))
    assert ur5.end_frame == "tool0" and ur5.ik_family is None and not ur5.electrical
    assert refusal("path_placement", Needs(serial=True, min_joints=6), ur5) is None
