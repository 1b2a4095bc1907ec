"""A robot given as URDF is drawn with its own <visual> geometry (boxes, cylinders, spheres and
mesh files inside allowed roots) attached to its animated link frames; without roots (an
uploaded robot) no mesh file is read."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from legcore.kinematics import fk
from legcore.robots import build_robot
from legcore.studies.study import Motion
from services.recording import blueprint as B
from services.recording import writer as W
from tests.recording_fixtures import fake_result

OBJ = """v 0 0 0
v 0.1 0 0
v 0 0.1 0
f 1 2 3
"""


def urdf(mesh: str) -> str:
    inertial = """<inertial><origin xyz="0.1 0 0"/><mass value="1"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.004" iyz="0" izz="0.004"/></inertial>"""
    return f"""<robot name="vis">
  <link name="base"><visual><geometry><box size="0.2 0.2 0.05"/></geometry></visual></link>
  <link name="upper">{inertial}
    <visual><origin xyz="0.15 0 0" rpy="0 1.5707963 0"/>
      <geometry><cylinder radius="0.03" length="0.3"/></geometry></visual></link>
  <link name="lower">{inertial}
    <visual><geometry><sphere radius="0.04"/></geometry></visual>
    <visual><geometry><mesh filename="{mesh}" scale="2 2 2"/></geometry></visual>
    <visual><geometry><mesh filename="package://nowhere/x.stl"/></geometry></visual></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="upper"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="20" velocity="3"/></joint>
  <joint name="j2" type="revolute"><parent link="upper"/><child link="lower"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="20" velocity="3"/></joint>
</robot>"""


@pytest.fixture
def robot_and_motion(tmp_path: Path):  # type: ignore[no-untyped-def]
    mesh = tmp_path / "tri.obj"
    mesh.write_text(OBJ)
    robot = build_robot({"kind": "urdf", "name": "vis", "urdf": urdf("package://vis/tri.obj")})
    t = np.linspace(0, 1, 20)
    q = np.stack([np.sin(t), np.cos(t)], axis=1)
    motion = Motion(t=t, q=q, joint_names=("j1", "j2"), tool=fk(robot, q)[:, :3, 3], robot="vis")
    return robot, motion


def test_urdf_visuals_are_recorded(robot_and_motion, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    robot, motion = robot_and_motion
    path = tmp_path / "urdf.rrd"
    W.write_recording(
        fake_result(motion, m=1, generations=2), path, robot=robot, mesh_roots=[tmp_path]
    )
    entities = B.read_entities(path)
    visuals = {e: a for e, a in entities.items() if "/visual_" in e}
    kinds = {next(iter(sorted(a)), "") for a in visuals.values() if a}
    assert any(e.endswith("frames/0/visual_0") for e in visuals), visuals  # base box
    assert "rerun.archetypes.Boxes3D" in kinds
    assert "rerun.archetypes.Capsules3D" in kinds  # the cylinder and the sphere
    assert any(e.endswith("frames/2/visual_1/mesh") and "rerun.archetypes.Asset3D" in a
               for e, a in entities.items())  # fmt: skip
    assert not any(e.endswith("frames/2/visual_2") for e in entities)  # missing mesh: skipped
    # the same robot uploaded (no roots): no file is read, the mesh is noted
    bare = tmp_path / "bare.rrd"
    notes = W.write_recording(fake_result(motion, m=1, generations=2), bare, robot=robot)
    assert not any("rerun.archetypes.Asset3D" in a for a in B.read_entities(bare).values())
    assert any("package://vis/tri.obj" in n and "no file access" in n for n in notes)


def test_missing_mesh_is_noted(robot_and_motion) -> None:  # type: ignore[no-untyped-def]
    from legcore.recording import record_motion

    robot, motion = robot_and_motion
    rec = record_motion(motion, robot)
    assert any("package://nowhere/x.stl" in n for n in rec.notes)
    cyl = next(p for p in rec.poses if p.path.endswith("frames/1/visual_0"))
    assert cyl.geometry == "capsule" and cyl.length == pytest.approx(0.3)
    # the capsule starts half a length before the visual origin along the cylinder axis (x here)
    np.testing.assert_allclose(cyl.translation[0], [0.0, 0.0, 0.0], atol=1e-6)


def test_many_missing_meshes_are_one_note_per_reason(tmp_path: Path) -> None:
    """Thirteen meshes not read give one note (how many, which), not thirteen."""
    names = [f"package://nowhere/m{i}.stl" for i in range(13)]
    text = urdf(names[0]).replace(
        '<visual><geometry><mesh filename="package://nowhere/x.stl"/></geometry></visual>',
        "".join(f'<visual><geometry><mesh filename="{n}"/></geometry></visual>' for n in names[1:]),
    )
    robot = build_robot({"kind": "urdf", "name": "vis", "urdf": text})
    t = np.linspace(0, 1, 10)
    q = np.stack([np.sin(t), np.cos(t)], axis=1)
    motion = Motion(t=t, q=q, joint_names=("j1", "j2"), tool=fk(robot, q)[:, :3, 3], robot="vis")
    notes = W.write_recording(fake_result(motion, m=1, generations=2), tmp_path / "r.rrd",
                              robot=robot, mesh_roots=[tmp_path])  # fmt: skip
    mesh_lines = [n for n in notes if "URDF mesh" in n]
    assert len(mesh_lines) == 1, notes
    assert "13 URDF meshes not read (no such file under the mesh roots)" in mesh_lines[0]
    assert all(repr(n) in mesh_lines[0] for n in names)


def test_an_example_robot_data_leg_is_drawn_with_its_installed_meshes(tmp_path: Path) -> None:
    """A Solo-12 leg as uploaded (its URDF text only): the worker's roots — the installed
    example-robot-data package — resolve its package:// STL meshes, which the recording embeds."""
    from services.store.settings import Settings
    from tests.robot_files import ERD_URDF, require_erd

    text = (require_erd() / ERD_URDF["solo12"]).read_text()
    robot = build_robot({"kind": "urdf", "name": "solo", "urdf": text, "legs": "auto",
                         "leg": "FL"})  # fmt: skip
    roots = Settings.from_env({}).mesh_root_dirs
    assert roots and all(r.is_dir() for r in roots)
    t = np.linspace(0, 1, 10)
    q = np.tile(robot.home, (10, 1)) + 0.1 * t[:, None]
    names = tuple(list(robot.model.names)[1:])
    motion = Motion(t=t, q=q, joint_names=names, tool=fk(robot, q)[:, :3, 3], robot="solo")
    path = tmp_path / "solo.rrd"
    notes = W.write_recording(fake_result(motion, m=1, generations=2), path, robot=robot,
                              mesh_roots=roots)  # fmt: skip
    meshes = [e for e, a in B.read_entities(path).items() if "rerun.archetypes.Asset3D" in a]
    assert len(meshes) >= 3, (meshes, notes)  # hip, upper leg, lower leg at least
    assert not [n for n in notes if "URDF mesh" in n and "solo12" in n], notes
