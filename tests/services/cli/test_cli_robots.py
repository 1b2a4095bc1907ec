"""`legopt robots add | list | show` against a real API process, and the robot files a spec
names (``robot: {urdf_file: …}``), read by the CLI and sent inline."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest
from typer.testing import CliRunner

from services.cli import app
from services.cli.robots import parse_legs, parse_locked_joints
from services.spec_files import inline_robot_files
from tests.integration.stack import Stack

runner = CliRunner()

LEG = """<robot name="leg">
  <link name="base"/>
  <link name="thigh"><inertial><origin xyz="0 0 -0.1"/><mass value="1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.002"/></inertial></link>
  <link name="shank"><inertial><origin xyz="0 0 -0.1"/><mass value="0.5"/>
    <inertia ixx="0.005" ixy="0" ixz="0" iyy="0.005" iyz="0" izz="0.001"/></inertial></link>
  <link name="foot"/>
  <link name="toe"><visual><geometry><mesh filename="package://leg/toe.stl"/></geometry></visual>
  </link>
  <joint name="hip" type="revolute"><parent link="base"/><child link="thigh"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="8" velocity="6"/></joint>
  <joint name="knee" type="revolute"><parent link="thigh"/><child link="shank"/>
    <origin xyz="0 0 -0.2"/><axis xyz="0 1 0"/><limit lower="-2.5" upper="0" effort="8"
    velocity="6"/></joint>
  <joint name="ankle" type="fixed"><parent link="shank"/><child link="foot"/>
    <origin xyz="0 0 -0.2"/></joint>
  <joint name="toe_joint" type="revolute"><parent link="foot"/><child link="toe"/>
    <origin xyz="0.03 0 0"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1"
    velocity="1"/></joint>
</robot>
"""


def test_locked_joints_and_legs_options() -> None:
    assert parse_locked_joints(["a,b=0.1", "c=home", " d = -2e-3 "]) == {
        "a": None,
        "b": 0.1,
        "c": None,
        "d": -0.002,
    }
    with pytest.raises(ValueError, match="--locked-joints: b='x' is not a number"):
        parse_locked_joints(["b=x"])
    assert parse_legs("auto") == "auto"
    assert parse_legs("LF=LF_FOOT, RF=hip:RF_HAA,LH=hip:LH_HAA+foot:LH_FOOT") == {
        "LF": {"foot": "LF_FOOT"},
        "RF": {"hip": "RF_HAA"},
        "LH": {"hip": "LH_HAA", "foot": "LH_FOOT"},
    }
    with pytest.raises(ValueError, match="--legs: 'LF' must read LEG=FOOT"):
        parse_legs("LF")
    with pytest.raises(ValueError, match="must read FOOT, foot:FRAME or hip:JOINT"):
        parse_legs("LF=knee:X")


def test_a_spec_names_its_urdf_file(tmp_path: Path) -> None:
    (tmp_path / "robots").mkdir()
    (tmp_path / "robots" / "my leg.urdf").write_text(LEG)
    spec = {"robot": {"urdf_file": "robots/my leg.urdf", "locked_joints": {"toe_joint": None}}}
    out = inline_robot_files(spec, tmp_path)
    assert out["robot"] == {
        "kind": "urdf",
        "name": "my_leg",
        "urdf": LEG,
        "locked_joints": {"toe_joint": None},
    }
    assert "urdf_file" in spec["robot"]  # the caller's mapping is left alone
    sweep = inline_robot_files({"base": {"robot": {"urdf_file": "robots/my leg.urdf"}}}, tmp_path)
    assert sweep["base"]["robot"]["urdf"] == LEG
    with pytest.raises(ValueError, match=r"^robot.urdf_file: cannot read .*missing.urdf"):
        inline_robot_files({"robot": {"urdf_file": "missing.urdf"}}, tmp_path)
    with pytest.raises(ValueError, match="^robot: give either 'urdf'"):
        inline_robot_files({"robot": {"urdf_file": "robots/my leg.urdf", "urdf": "x"}}, tmp_path)
    (tmp_path / "bin.urdf").write_bytes(b"\xff\xfe<robot/>")
    with pytest.raises(ValueError, match="is not UTF-8 text"):
        inline_robot_files({"robot": {"urdf_file": "bin.urdf"}}, tmp_path)


def test_legopt_run_and_submit_read_the_urdf_file_of_a_spec(tmp_path: Path) -> None:
    from services.cli.common import load_spec_file

    (tmp_path / "leg.urdf").write_text(LEG)
    spec = tmp_path / "job.yaml"
    spec.write_text("robot: {urdf_file: leg.urdf, locked_joints: {toe_joint: null}}\n")
    assert load_spec_file(spec)["robot"]["urdf"] == LEG


@pytest.fixture(scope="module")
def api(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Stack]:
    """The API process alone (no worker: nothing here runs a job)."""
    tmp = tmp_path_factory.mktemp("robots-cli")
    (tmp / "data").mkdir()
    st = Stack("embedded", tmp, f"sqlite:///{tmp / 'data' / 'legopt.db'}", "filesystem://")
    st.migrate_and_key()
    st.start_api()
    try:
        yield st
    finally:
        st.stop()


def cli(stack: Stack, *args: str) -> tuple[int, str]:
    res = runner.invoke(app, ["robots", *args, "--url", stack.url, "--key", stack.key])
    return res.exit_code, res.output


@pytest.mark.integration
def test_robots_add_list_show(api: Stack, tmp_path: Path) -> None:
    path = tmp_path / "leg.urdf"
    path.write_text(LEG)
    code, out = cli(api, "add", str(path), "--locked-joints", "toe_joint=0.2")
    assert code == 0, out
    assert "robot leg" in out and "serial chain of 2 joints, end frame toe" in out

    code, out = cli(api, "add", str(path), "--name", "leg3")  # the toe joint moves too
    assert code == 0 and "serial chain of 3 joints, end frame toe" in out, out
    code, out = cli(api, "add", str(path), "--name", "leg_knee", "--tool-frame", "shank")
    assert code == 2 and "tool_frame" in out and "lock the joints after it" in out, out

    code, out = cli(api, "add", str(path), "--name", "leg2", "--locked-joints", "toe_joint=5")
    assert code == 2 and "locked_joints" in out and "outside its limits" in out

    code, out = cli(api, "list")
    assert code == 0 and "leg" in out and "urdf" in out
    code, out = cli(api, "list", "--catalog")
    assert code == 0 and "puma560" in out

    code, out = cli(api, "show", "leg")
    assert code == 0, out
    assert "hip, knee" in out and "motor data (Kt, Ke, R)" in out
    code, out = cli(api, "show", "leg", "--json")
    assert code == 0 and json.loads(out)["capabilities"]["end_frame"] == "toe"
    code, out = cli(api, "show", "calderon_leg")
    assert code == 0 and "serial chain of 3 joints" in out
    code, out = cli(api, "show", "nobody")
    assert code == 2 and "no robot 'nobody'" in out

    code, out = cli(api, "add", str(tmp_path / "none.urdf"))
    assert code == 2 and "FILE: cannot read" in out

    # remove: by name, once; a catalog robot is not yours to remove
    code, out = cli(api, "remove", "leg3")
    assert code == 0 and "robot leg3: removed" in out, out
    code, out = cli(api, "show", "leg3")
    assert code == 2 and "no robot 'leg3'" in out
    code, out = cli(api, "remove", "leg3")
    assert code == 2 and "no robot 'leg3'" in out
    code, out = cli(api, "remove", "calderon_leg")
    assert code == 2 and "catalog robot" in out
