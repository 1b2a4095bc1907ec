"""Issue 8, defect 1: a robot file must never make a worker read a file (DESIGN §5).

The review's attack: a URDF ``<mesh filename=…>`` naming a file of the worker (absolute,
``file://``, ``package://../..``, ``../`` relative, a symlink) was embedded in the job's Rerun
recording, which the submitter downloads. Here every form names a secret of its own, and
``/etc/passwd`` is named too; the recording must contain none of them (decoded chunk by chunk,
not just the raw file) and the job's warnings must say each mesh was not read.

The recording and robot-builder tests run in-process (no stack); the two marked
``integration`` run on the real stack (API + 2 workers, both backends): one job covering every
form, and the 422 of DOCTYPE/ENTITY URDFs on POST /robots and POST /jobs.
"""

from __future__ import annotations

import html
import io
import os
import secrets
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pytest

from services.client import TERMINAL, ApiError
from tests.integration.stack import ROOT, Stack

integration = pytest.mark.integration

PASSWD_MARK = b"root:x:0:0:"


def _secret(tmp: Path, name: str) -> tuple[Path, bytes]:
    token = f"LEGOPT-SECRET-{name}-{secrets.token_hex(12)}".encode()
    path = tmp / f"{name}.stl"
    path.write_bytes(b"solid x\n" + token + b"\nendsolid x\n")
    return path, token


def attack_names(tmp: Path) -> tuple[dict[str, str], dict[str, bytes]]:
    """Mesh names of every attack form → (name per form, secret token per form)."""
    tokens: dict[str, bytes] = {}
    names: dict[str, str] = {}
    p, tokens["absolute"] = _secret(tmp, "absolute")
    names["absolute"] = str(p)
    p, tokens["file_uri"] = _secret(tmp, "file_uri")
    names["file_uri"] = f"file://{p}"
    p, tokens["symlink"] = _secret(tmp, "symlink_target")
    (tmp / "innocent.stl").symlink_to(p)  # a mesh-looking name that is a link to the secret
    names["symlink"] = str(tmp / "innocent.stl")
    p, tokens["package_dotdot"] = _secret(tmp, "package_dotdot")
    names["package_dotdot"] = "package://robot/" + "../" * 12 + str(p).lstrip("/")
    p, tokens["relative_dotdot"] = _secret(tmp, "relative_dotdot")
    names["relative_dotdot"] = os.path.relpath(p, ROOT)  # from the workers' working directory
    names["etc_passwd"] = "/etc/passwd"
    return names, tokens


def leg_urdf(names: dict[str, str]) -> str:
    """A 3-joint leg (swing_energy needs a serial 3-joint leg) whose visuals name the meshes
    ``names`` in order, spread over the base link and the first two moving links; the last link
    has a box."""
    inertia = '<inertia ixx="5e-5" ixy="0" ixz="0" iyy="2e-4" iyz="0" izz="2e-4"/>'
    mesh = '<visual><geometry><mesh filename="{}"/></geometry></visual>'
    meshes = [mesh.format(html.escape(n, quote=True)) for n in names.values()]
    k = -(-len(meshes) // 3)
    per_link = [meshes[0:k], meshes[k : 2 * k], meshes[2 * k :], []]

    def link(name: str, x: float, mass: float, visuals: list[str]) -> str:
        inertial = (
            f'<inertial><origin xyz="{x} 0 0"/><mass value="{mass}"/>{inertia}</inertial>'
            if mass
            else ""
        )
        return f'<link name="{name}">{inertial}{"".join(visuals)}</link>'

    def joint(name: str, parent: str, child: str, origin: str, lo: float) -> str:
        return (
            f'<joint name="{name}" type="revolute"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin {origin}/><axis xyz="0 0 1"/>'
            f'<limit lower="{lo}" upper="{-lo}" effort="10" velocity="5"/></joint>'
        )

    box = '<visual><geometry><box size="0.02 0.02 0.02"/></geometry></visual>'
    return (
        '<robot name="leaky_leg">'
        + link("hip", 0, 0, per_link[0])
        + link("pelvis", 0.03, 0.175, per_link[1])
        + link("thigh", 0.04, 0.13, per_link[2])
        + link("shank", 0.07, 0.11, [box])
        + '<link name="foot"/>'
        + joint("hip_yaw", "hip", "pelvis", 'xyz="0 0 0"', -1.57)
        + joint("hip_pitch", "pelvis", "thigh", 'xyz="0.065 0 0" rpy="1.5707963 0 0"', -3.14)
        + joint("knee_pitch", "thigh", "shank", 'xyz="0.075 0 0"', -3.14)
        + '<joint name="foot_fixed" type="fixed"><parent link="shank"/><child link="foot"/>'
        '<origin xyz="0.15 0 0"/></joint></robot>'
    )


def leaked(rrd: bytes, tokens: dict[str, bytes]) -> list[str]:
    """Forms whose secret is in ``rrd``: in the raw file or in any decoded chunk's columns."""
    from rerun.chunk import RrdReader

    hits = {form for form, tok in tokens.items() if tok in rrd}
    if PASSWD_MARK in rrd:
        hits.add("etc_passwd")
    with tempfile.TemporaryDirectory(prefix="legopt-leak-") as folder:
        tmp = Path(folder) / "downloaded.rrd"
        tmp.write_bytes(rrd)
        for chunk in RrdReader(tmp).stream():
            sink = io.BytesIO()
            batch = chunk.to_record_batch()
            with pa.ipc.new_stream(sink, batch.schema) as w:
                w.write_batch(batch)
            data = sink.getvalue()
            hits |= {form for form, tok in tokens.items() if tok in data}
            if PASSWD_MARK in data:
                hits.add("etc_passwd")
    return sorted(hits)


def _not_read_warnings(warnings: list[str], names: dict[str, str]) -> list[str]:
    """Forms with no warning saying their mesh was not read."""
    return [
        form
        for form, name in names.items()
        if not any(repr(name) in w and "not read" in w for w in warnings)
    ]


# ---------------------------------------------------------------------------------------------
# in-process: the recording itself
# ---------------------------------------------------------------------------------------------


def test_recording_embeds_no_named_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The worker's writer (no mesh roots) reads none of the named files; each is a note."""
    from legcore.kinematics import fk
    from legcore.robots import build_robot
    from legcore.studies.study import Motion
    from services.recording import blueprint as B
    from services.recording import writer as W
    from tests.recording_fixtures import fake_result

    names, tokens = attack_names(tmp_path)
    robot = build_robot({"kind": "urdf", "name": "leaky_leg", "urdf": leg_urdf(names)})
    t = np.linspace(0.0, 1.0, 30)
    q = np.stack([0.2 * np.sin(t), 0.5 + 0.1 * t, -1.0 + 0.2 * t], axis=1)
    motion = Motion(t=t, q=q, joint_names=("hip_yaw", "hip_pitch", "knee_pitch"),
                    tool=fk(robot, q)[:, :3, 3], robot="leaky_leg")  # fmt: skip
    path = tmp_path / "leak.rrd"
    monkeypatch.chdir(ROOT)  # the relative form is relative to the worker's working directory
    result: Any = fake_result(motion, m=1, generations=2)
    notes = W.write_recording(result, path, robot=robot)
    assert leaked(path.read_bytes(), tokens) == []
    assert not any(e.endswith("/mesh") for e in B.read_entities(path))
    assert _not_read_warnings(notes or [], names) == [], notes
    assert any("no file access" in n and "drawn as capsules" in n for n in notes or []), notes


def test_a_mesh_inside_the_mesh_roots_is_recorded(tmp_path: Path) -> None:
    """With an explicit root (what a CLI run may pass for its spec's folder), a package:// mesh
    inside it is embedded — and every attack form is still refused."""
    from legcore.kinematics import fk
    from legcore.robots import build_robot
    from legcore.studies.study import Motion
    from services.recording import blueprint as B
    from services.recording import writer as W
    from tests.recording_fixtures import fake_result

    root = tmp_path / "pkg"
    (root / "meshes").mkdir(parents=True)
    mesh = b"v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nf 1 2 3\n# LEGIT-MESH-7d3a\n"
    (root / "meshes" / "tri.obj").write_bytes(mesh)
    (root / "meshes" / "out.obj").symlink_to(tmp_path / "absolute.stl")  # a link out of the root
    names, tokens = attack_names(tmp_path)
    names["symlink_in_root"] = "package://leaky/meshes/out.obj"
    names = {"legit": "package://leaky/meshes/tri.obj", **names}
    robot = build_robot({"kind": "urdf", "name": "leaky_leg", "urdf": leg_urdf(names)})
    t = np.linspace(0.0, 1.0, 10)
    q = np.stack([0.1 * t, 0.5 + 0.1 * t, -1.0 + 0.2 * t], axis=1)
    motion = Motion(t=t, q=q, joint_names=("hip_yaw", "hip_pitch", "knee_pitch"),
                    tool=fk(robot, q)[:, :3, 3], robot="leaky_leg")  # fmt: skip
    path = tmp_path / "ok.rrd"
    result: Any = fake_result(motion, m=1, generations=2)
    notes = W.write_recording(result, path, robot=robot, mesh_roots=[root])
    assert leaked(path.read_bytes(), {**tokens, "legit": b"LEGIT-MESH-7d3a"}) == ["legit"]
    meshes = [e for e, a in B.read_entities(path).items() if "rerun.archetypes.Asset3D" in a]
    assert len(meshes) == 1 and meshes[0].endswith("frames/0/visual_0/mesh"), meshes
    del names["legit"]
    assert _not_read_warnings(notes, names) == [], notes


# ---------------------------------------------------------------------------------------------
# real stack: register, submit, download
# ---------------------------------------------------------------------------------------------


def _job_spec(robot: Any) -> dict[str, Any]:
    return {
        "robot": robot,
        "problem": {"kind": "swing_energy", "dt": 0.03},
        "optimizer": {"kind": "ga", "params": {"pop_size": 8}},
        "budget": {"generations": 2},
        "seed": 1,
        "record": True,
    }


@integration
def test_uploaded_robot_meshes_are_never_read(stack: Stack, tmp_path: Path) -> None:
    """One job whose stored URDF robot names every attack form: it succeeds, its recording holds
    none of the secrets, and its warnings name each mesh as not read."""
    names, tokens = attack_names(tmp_path)
    spec = {"kind": "urdf", "name": "leaky_leg", "urdf": leg_urdf(names), "tool_frame": "foot"}
    with stack.client() as c:
        robot = c.post("/robots", {"name": "leaky_leg", "spec": spec})
        job = c.submit(_job_spec(robot["id"]))
        done = stack.wait_for(job["id"], lambda j: j["status"] in TERMINAL, timeout_s=180)
        assert done["status"] == "succeeded", (done.get("error"), stack.log_tail())
        rrd = c.recording(job["id"])
    assert rrd[:4] == b"RRF2"
    assert leaked(rrd, tokens) == [], "the recording embeds files named by the URDF"
    assert _not_read_warnings(done["warnings"], names) == [], done["warnings"]


DOCTYPES = {
    "internal_entity": '<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY a "aaaaaaaaaa">'
    '<!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">]><robot name="&b;"/>',
    "external_entity": '<!DOCTYPE robot [<!ENTITY e SYSTEM "file:///etc/passwd">]>'
    '<robot name="r"><link name="&e;"/></robot>',
    "external_dtd": '<!DOCTYPE robot SYSTEM "http://127.0.0.1:9/robot.dtd"><robot name="r"/>',
}


def test_doctype_is_refused_by_the_robot_builder() -> None:
    """In-process: every DOCTYPE form is a ``urdf:`` ValueError saying how to fix it; an XML
    declaration or a comment that mentions a DOCTYPE is fine."""
    from legcore.robots import build_robot

    for label, text in DOCTYPES.items():
        with pytest.raises(ValueError, match=r"^urdf: a <!DOCTYPE> declaration is not allowed"):
            build_robot({"kind": "urdf", "name": label, "urdf": text})
    ok = '<?xml version="1.0" encoding="UTF-8"?>\n<!-- not a <!DOCTYPE> -->\n' + leg_urdf({})
    assert build_robot({"kind": "urdf", "name": "ok", "urdf": ok}).nq == 3


@integration
def test_doctype_and_entities_are_refused(stack: Stack) -> None:
    """POST /robots and POST /jobs answer 422 naming the ``urdf`` field, with how to fix it."""
    with stack.client() as c:
        for label, text in DOCTYPES.items():
            spec = {"kind": "urdf", "name": "dtd", "urdf": text}
            for path, body, loc in (
                ("/robots", {"name": "dtd", "spec": spec}, ["body", "spec", "urdf"]),
                ("/jobs", _job_spec(spec), ["body", "robot", "urdf"]),
            ):
                with pytest.raises(ApiError) as exc:
                    c.post(path, body)
                assert exc.value.status == 422, (label, path, exc.value)
                detail = exc.value.detail
                assert [d["loc"] for d in detail] == [loc], (label, path, detail)
                assert "DOCTYPE" in detail[0]["msg"] and "remove" in detail[0]["msg"], detail
