"""Robots from whole URDF files over the API: locked joints, one leg of a legged robot, the
capabilities of every robot on GET /robots/{id}, and 422s naming the field."""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient

API = "/api/v1"


def _link(name: str, m: float = 1.0) -> str:
    return (
        f'<link name="{name}"><inertial><origin xyz="0 0 -0.05"/><mass value="{m}"/>'
        '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>'
    )


def _joint(name: str, parent: str, child: str, xyz: str, axis: str = "0 1 0") -> str:
    kind, lim = ("fixed", "") if axis == "" else ("revolute", (
        '<limit lower="-2" upper="2" effort="5" velocity="8"/>'))  # fmt: skip
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}"/><axis xyz="{axis or "1 0 0"}"/>{lim}</joint>'
    )


def toy_legged() -> str:
    """Two legs (A, B: hip about x, knee about y, fixed foot) and a neck on a 3 kg body."""
    parts = ['<robot name="toy">', _link("base", 3.0), _link("head", 0.2)]
    parts.append(_joint("neck", "base", "head", "0.2 0 0.1", axis="0 0 1"))
    for leg, y in (("A", 0.1), ("B", -0.1)):
        parts += [_link(f"{leg}_thigh"), _link(f"{leg}_shank"), _link(f"{leg}_foot", 0.01)]
        parts.append(_joint(f"{leg}_hip", "base", f"{leg}_thigh", f"0.15 {y} 0", "1 0 0"))
        parts.append(_joint(f"{leg}_knee", f"{leg}_thigh", f"{leg}_shank", "0 0 -0.2"))
        parts.append(_joint(f"{leg}_ankle", f"{leg}_shank", f"{leg}_foot", "0 0 -0.2", ""))
    return "\n".join([*parts, "</robot>"])


def _post(client: TestClient, headers: dict[str, str], name: str, **spec: Any) -> Any:
    body = {"name": name, "spec": {"kind": "urdf", "name": name, "urdf": toy_legged(), **spec}}
    return client.post(f"{API}/robots", json=body, headers=headers)


def test_one_leg_with_the_neck_locked(client: TestClient, alice: dict[str, str]) -> None:
    r = _post(client, alice, "leg_a", locked_joints={"neck": 0.4}, legs="auto", leg="A")
    assert r.status_code == 201, r.text
    caps = r.json()["capabilities"]
    assert caps["kind"] == "serial" and caps["serial_chain"] and caps["n_actuated"] == 2
    assert caps["end_frame"] == "A_foot" and caps["joint_names"] == ["A_hip", "A_knee"]
    assert caps["torque_limits"] and not caps["electrical"] and caps["ik_family"] is None
    got = client.get(f"{API}/robots/{r.json()['id']}", headers=alice)
    assert got.status_code == 200 and got.json()["capabilities"] == caps
    assert got.json()["inline_spec"]["leg"] == "A"


def test_validate_shows_capabilities(client: TestClient, alice: dict[str, str]) -> None:
    spec = {"kind": "urdf", "name": "t", "urdf": toy_legged(), "legs": "auto", "leg": "B",
            "locked_joints": {"neck": None}}  # fmt: skip
    r = client.post(f"{API}/robots/validate", json={"spec": spec}, headers=alice)
    assert r.status_code == 200, r.text
    assert r.json()["capabilities"]["end_frame"] == "B_foot"


def test_catalog_robots_show_capabilities(client: TestClient, alice: dict[str, str]) -> None:
    quad = client.get(f"{API}/robots/animatronic_quadruped", headers=alice).json()
    assert quad["capabilities"]["kind"] == "legged" and len(quad["capabilities"]["legs"]) == 4
    puma = client.get(f"{API}/robots/puma560", headers=alice).json()["capabilities"]
    assert puma["ik_family"] == "puma560" and puma["n_actuated"] == 6


@pytest.mark.parametrize(
    ("spec", "loc", "reason"),
    [
        ({"locked_joints": {"elbow": 0.1}}, ["locked_joints"], "'elbow' is not a moving joint"),
        ({}, ["urdf"], "do not form one serial chain"),
        ({"legs": {"A": {"foot": "A_toe"}}, "leg": "A"}, ["legs", "A", "foot"], "no frame"),
        ({"legs": {"A": {"foot": "A_foot"}}, "leg": "A"}, ["legs"], "'neck'] belong to no leg"),
        ({"legs": "auto", "tool_frame": "A_foot"}, ["tool_frame"], "a legged robot's legs end"),
        ({"legs": {"A B": {"foot": "x"}}}, ["legs", "A B"], "pattern"),
    ],
)
def test_bad_robot_files_are_422_naming_the_field(
    client: TestClient, alice: dict[str, str], spec: dict[str, Any], loc: list[Any], reason: str
) -> None:
    r = _post(client, alice, "bad", **spec)
    assert r.status_code == 422, r.text
    errors = r.json()["detail"]
    assert any(
        e["loc"][: 2 + len(loc)] == ["body", "spec", *loc] and reason in e["msg"] for e in errors
    ), errors


def test_a_whole_legged_robot(client: TestClient, alice: dict[str, str]) -> None:
    r = _post(client, alice, "toy", locked_joints={"neck": None}, legs="auto")
    assert r.status_code == 201, r.text
    caps = r.json()["capabilities"]
    assert caps["kind"] == "legged" and caps["floating_base"] and caps["n_actuated"] == 4
    assert [(g["name"], g["foot_frame"]) for g in caps["legs"]] == [
        ("A", "A_foot"),
        ("B", "B_foot"),
    ]
    got = client.get(f"{API}/robots/{r.json()['id']}", headers=alice)
    assert got.status_code == 200 and got.json()["summary"]["n_legs"] == 2
