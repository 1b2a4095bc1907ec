"""A URDF robot's visual meshes as recording items (bytes read through legcore.resource_paths)."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np

from legcore.recording.model import (
    C_LINK,
    MAX_MESH_BYTES,
    MESH_SUFFIXES,
    FloatArray,
    MeshRoots,
    PoseTrack,
)
from legcore.resource_paths import ResourceRefused, read_resource

if TYPE_CHECKING:
    from legcore.robots.model import Robot

def _rpy_matrix(r: float, p: float, y: float) -> FloatArray:
    """URDF ``rpy``: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def _floats(text: str | None, n: int, default: float = 0.0) -> list[float]:
    vals = [float(v) for v in (text or "").split()]
    return vals + [default] * (n - len(vals)) if len(vals) < n else vals[:n]


#: Mesh names listed per reason in the summary note (the rest counted).
MAX_LISTED = 20


def _urdf_mesh(
    shape: Any, mesh_roots: MeshRoots, refused: dict[str, list[str]]
) -> dict[str, Any] | None:
    """The PoseTrack fields of a ``<mesh>`` visual, its file read only inside ``mesh_roots``
    (none: no file access, DESIGN §5); a mesh not read is added to ``refused`` (reason ->
    names) and left to the link capsule."""
    name = shape.get("filename", "")
    try:
        if mesh_roots and os.path.splitext(name)[1].lower() not in MESH_SUFFIXES:
            raise ResourceRefused(
                name, f"only {', '.join(sorted(MESH_SUFFIXES))} meshes can be recorded"
            )
        path, data = read_resource(name, mesh_roots, max_bytes=MAX_MESH_BYTES)
    except ResourceRefused as exc:
        refused.setdefault(exc.reason, []).append(name)
        return None
    scale = _floats(shape.get("scale"), 3, 1.0)
    return {"geometry": "mesh", "mesh": str(path), "mesh_data": data, "half_size": tuple(scale)}


def mesh_notes(refused: dict[str, list[str]]) -> list[str]:
    """One note per reason a mesh was not read (not one per mesh): how many, which (the first
    :data:`MAX_LISTED` names), and what is drawn instead."""
    out = []
    for reason, names in refused.items():
        listed = ", ".join(repr(n) for n in names[:MAX_LISTED])
        more = f" and {len(names) - MAX_LISTED} more" if len(names) > MAX_LISTED else ""
        what = "URDF mesh" if len(names) == 1 else f"{len(names)} URDF meshes"
        out.append(f"{what} not read ({reason}): {listed}{more}; their links are drawn as "
                   "capsules")  # fmt: skip
    return out


def _urdf_visuals(
    robot: Robot, frames_path: str, notes: list[str], mesh_roots: MeshRoots = ()
) -> list[PoseTrack]:
    """The ``<visual>`` geometry of a URDF robot, each a static child of its link's frame entity:
    boxes, cylinders (as capsules) and spheres drawn as given; a mesh is drawn only when its name
    resolves to a file inside one of ``mesh_roots`` (:mod:`legcore.resource_paths`; default none:
    no file is ever opened), else noted (``notes``) and left to the link capsule."""
    import xml.etree.ElementTree as ET

    from legcore.robots.build import reject_declarations

    spec = robot.spec
    text = getattr(spec, "urdf", None)
    if not text:
        return []
    try:
        reject_declarations(text)
    except ValueError as exc:
        notes.append(f"URDF visuals not drawn: {exc}")
        return []
    model = robot.model
    index: dict[str, int] = {}
    for f in model.frames:  # the base link: a body frame on the universe joint
        if f.parentJoint == 0 and str(f.type).endswith("BODY"):
            index.setdefault(f.name, 0)
    for k, fid in enumerate(robot.link_frames, start=1):
        index[model.frames[fid].name] = k
    out: list[PoseTrack] = []
    refused: dict[str, list[str]] = {}
    for link in ET.fromstring(text).iter("link"):
        k_link = index.get(link.get("name", ""))
        if k_link is None:
            continue
        for j, visual in enumerate(link.findall("visual")):
            origin = visual.find("origin")
            xyz = np.array(_floats(origin.get("xyz") if origin is not None else None, 3))
            R = _rpy_matrix(*_floats(origin.get("rpy") if origin is not None else None, 3))
            geom = visual.find("geometry")
            shape = geom[0] if geom is not None and len(geom) else None
            if shape is None:
                continue
            path = f"{frames_path}/{k_link}/visual_{j}"
            kw: dict[str, Any] = {}
            p = xyz
            if shape.tag == "box":
                size = _floats(shape.get("size"), 3)
                kw = {"geometry": "box", "half_size": tuple(0.5 * v for v in size)}
            elif shape.tag == "cylinder":
                length, r = float(shape.get("length", "0")), float(shape.get("radius", "0"))
                p = xyz - R @ np.array([0.0, 0.0, 0.5 * length])
                kw = {"geometry": "capsule", "length": length, "radius": r}
            elif shape.tag == "sphere":
                r = float(shape.get("radius", "0"))
                kw = {"geometry": "capsule", "length": 0.0, "radius": r}
            elif shape.tag == "mesh":
                mesh = _urdf_mesh(shape, mesh_roots, refused)
                if mesh is None:
                    continue
                kw = mesh
            else:
                continue
            out.append(PoseTrack(path, None, p[None], R[None], color=C_LINK, **kw))
    notes.extend(mesh_notes(refused))
    return out
