"""Read URDF text as data: refuse declarations, check what Pinocchio does not, list the joints.

A robot file is data (DESIGN §5). Neither this parse nor Pinocchio's (``buildModelFromXML``:
urdfdom + tinyxml2, kinematics and inertias only) opens any file or URL named in the text —
``<mesh>``, ``<texture>`` and the like stay strings. A document type declaration (the only place
an entity can be declared) is refused before anything else reads the text.

Units: m, rad, kg, kg·m².
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Any
from xml.parsers import expat

import numpy as np
from numpy.typing import NDArray

__all__ = ["Mimic", "ParsedURDF", "lock_xml", "parse_urdf", "reject_declarations"]

#: Moving joints a file may hold before locking (a full humanoid has ~40).
MAX_FILE_JOINTS = 300


class _Prolog(Exception):
    """Raised inside the expat prolog scan: a declaration (``what``) or the root element."""

    def __init__(self, what: str = "") -> None:
        super().__init__(what)
        self.what = what


def reject_declarations(text: str) -> None:
    """Raise ``ValueError("urdf: …")`` when the XML ``text`` declares a document type
    (``<!DOCTYPE …>``, the only place ``<!ENTITY …>`` can appear).

    A robot file is data (DESIGN §5): entity expansion ("billion laughs") and external entities
    or DTDs (``SYSTEM "file:///…"``, ``http://…``) are refused outright rather than trusted to
    each parser's defaults. Only the prolog is scanned (expat stops at the root element), with
    parameter-entity parsing off; malformed XML is left to the full parse that follows.
    """
    parser = expat.ParserCreate()
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)

    def declaration(*_: Any) -> None:
        raise _Prolog("<!DOCTYPE>")

    def entity(*_: Any) -> None:
        raise _Prolog("<!ENTITY>")

    def root(*_: Any) -> None:
        raise _Prolog()

    parser.StartDoctypeDeclHandler = declaration
    parser.EntityDeclHandler = entity
    parser.StartElementHandler = root
    try:
        parser.Parse(text, True)
    except _Prolog as stop:
        if stop.what:
            raise ValueError(
                f"urdf: a {stop.what} declaration is not allowed (robot files get no entity "
                "expansion and no external references); remove the <!DOCTYPE …> block and write "
                "any entity's value out in full"
            ) from None
    except expat.ExpatError:
        return


@dataclass(frozen=True)
class Mimic:
    """A ``<mimic>`` joint: ``q = multiplier · q[master] + offset``."""

    master: str
    multiplier: float
    offset: float


@dataclass(frozen=True)
class ParsedURDF:
    """A checked URDF: ``xml`` (continuous joints rewritten as revolute ±2π, ready for
    Pinocchio), the ``movable`` joint names in file order with their ``limits`` (lower, upper;
    rad or m), the ``mimic`` joints, each link's ``(name, mass kg, 3×3 inertia kg·m²)`` for the
    physical checks made once the model's scale is known, and the size (m) of the root body's
    largest box geometry (``root_box``), if any."""

    xml: str
    movable: tuple[str, ...]
    limits: dict[str, tuple[float, float]]
    mimic: dict[str, Mimic]
    inertias: tuple[tuple[str, float, NDArray[np.float64]], ...]
    root_box: tuple[float, float, float] | None


def _float(el: ET.Element, attr: str, default: str, what: str) -> float:
    try:
        return float(el.get(attr, default))
    except ValueError:
        raise ValueError(f"urdf: {what}: {attr}={el.get(attr)!r} is not a number") from None


def _joints(
    root: ET.Element,
) -> tuple[list[str], dict[str, tuple[float, float]], dict[str, Mimic]]:
    movable: list[str] = []
    limits: dict[str, tuple[float, float]] = {}
    mimic: dict[str, Mimic] = {}
    for joint in root.iter("joint"):
        jtype = joint.get("type", "")
        name = joint.get("name", "?")
        if jtype in {"floating", "planar"}:
            raise ValueError(
                f"urdf: joint {name!r} has type {jtype!r}; only 1-DOF joints (a legged robot's "
                "floating base comes from 'legs': remove the joint and root the file at the body)"
            )
        if jtype == "continuous":
            joint.set("type", "revolute")
            limit = joint.find("limit")
            if limit is None:  # effort/velocity 0 = unknown (no torque limit, default speed)
                limit = ET.SubElement(joint, "limit", effort="0", velocity="0")
            limit.set("lower", str(-2 * math.pi))
            limit.set("upper", str(2 * math.pi))
        if joint.get("type") not in {"revolute", "prismatic"}:
            continue
        movable.append(name)
        limit = joint.find("limit")
        if limit is None:
            raise ValueError(f"urdf: joint {name!r} needs a <limit> element")
        lo = _float(limit, "lower", "0", f"joint {name!r} limit")
        hi = _float(limit, "upper", "0", f"joint {name!r} limit")
        if not (math.isfinite(lo) and math.isfinite(hi)) or not lo < hi:
            raise ValueError(f"urdf: joint {name!r} limits must satisfy lower < upper")
        if name in limits:
            raise ValueError(f"urdf: two joints are named {name!r}")
        limits[name] = (lo, hi)
        m = joint.find("mimic")
        if m is not None:
            mult = _float(m, "multiplier", "1", f"joint {name!r} mimic")
            off = _float(m, "offset", "0", f"joint {name!r} mimic")
            if not (math.isfinite(mult) and math.isfinite(off)):
                raise ValueError(f"urdf: joint {name!r} mimic values must be finite")
            mimic[name] = Mimic(m.get("joint", ""), mult, off)
    if len(movable) > MAX_FILE_JOINTS:
        raise ValueError(f"urdf: {len(movable)} moving joints, at most {MAX_FILE_JOINTS}")
    return movable, limits, mimic


def _inertias(root: ET.Element) -> list[tuple[str, float, NDArray[np.float64]]]:
    out = []
    for link in root.iter("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        lname = link.get("name", "?")
        mass_el = inertial.find("mass")
        mass = _float(mass_el, "value", "0", f"link {lname!r} mass") if mass_el is not None else 0.0
        if not math.isfinite(mass) or mass < 0:
            raise ValueError(f"urdf: link {lname!r} mass must be a finite value >= 0 kg")
        I_el = inertial.find("inertia")
        if I_el is None:
            continue
        g = {
            k: _float(I_el, k, "0", f"link {lname!r} inertia")
            for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
        }
        inertia = np.array(
            [
                [g["ixx"], g["ixy"], g["ixz"]],
                [g["ixy"], g["iyy"], g["iyz"]],
                [g["ixz"], g["iyz"], g["izz"]],
            ]
        )
        if not np.all(np.isfinite(inertia)):
            raise ValueError(f"urdf: link {lname!r} inertia has non-finite values")
        out.append((lname, mass, inertia))
    return out


def _root_box(root: ET.Element) -> tuple[float, float, float] | None:
    """Size (m) of the largest ``<box>`` collision (else visual) geometry of the root link and
    the links fixed to it (the body of a legged robot), if the file gives one."""
    children = {c.get("link") for j in root.iter("joint") for c in j.iter("child")}
    roots = [link.get("name") for link in root.iter("link") if link.get("name") not in children]
    if len(roots) != 1:
        return None
    body = {roots[0]}
    fixed = [
        (p.get("link"), c.get("link"))
        for j in root.iter("joint")
        if j.get("type") == "fixed"
        for p in j.iter("parent")
        for c in j.iter("child")
    ]
    grown = True
    while grown:
        grown = False
        for parent, child in fixed:
            if parent in body and child not in body:
                body.add(child)
                grown = True
    for tag in ("collision", "visual"):
        sizes = []
        for link in root.iter("link"):
            if link.get("name") not in body:
                continue
            for el in link.iter(tag):
                box = el.find("geometry/box")
                if box is None:
                    continue
                try:
                    size = tuple(float(v) for v in box.get("size", "").split())
                except ValueError:
                    continue
                if len(size) == 3 and all(math.isfinite(v) and v > 0 for v in size):
                    sizes.append((size[0], size[1], size[2]))
        if sizes:
            return max(sizes, key=lambda v: v[0] * v[1] * v[2])
    return None


def parse_urdf(text: str) -> ParsedURDF:
    """Check URDF ``text`` (no declarations, well-formed, ``<robot>`` root, 1-DOF joints with
    limits, finite non-negative masses and finite inertias) and return it prepared for
    Pinocchio. Raises ``ValueError("urdf: …")`` naming the joint or link at fault."""
    reject_declarations(text)
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ValueError(f"urdf: not well-formed XML ({exc})") from None
    if root.tag != "robot":
        raise ValueError(f"urdf: root element must be <robot>, got <{root.tag}>")
    movable, limits, mimic = _joints(root)
    inertias = _inertias(root)
    return ParsedURDF(
        xml=ET.tostring(root, encoding="unicode"),
        movable=tuple(movable),
        limits=limits,
        mimic=mimic,
        inertias=tuple(inertias),
        root_box=_root_box(root),
    )


def _vector(el: ET.Element | None, attr: str, default: str) -> NDArray[np.float64]:
    text = el.get(attr, default) if el is not None else default
    try:
        v = np.array([float(x) for x in text.split()], dtype=float)
    except ValueError:
        v = np.zeros(0)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"urdf: {attr}={text!r} must be three finite numbers")
    return v


def _rpy_matrix(rpy: NDArray[np.float64]) -> NDArray[np.float64]:
    """URDF ``rpy``: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def _matrix_rpy(R: NDArray[np.float64]) -> NDArray[np.float64]:
    """Inverse of :func:`_rpy_matrix` (pitch in [-π/2, π/2])."""
    pitch = float(np.arctan2(-R[2, 0], np.hypot(R[0, 0], R[1, 0])))
    if np.hypot(R[0, 0], R[1, 0]) < 1e-12:  # gimbal lock: put the whole turn in the yaw
        return np.array([0.0, pitch, float(np.arctan2(-R[0, 1], R[1, 1]))])
    return np.array(
        [float(np.arctan2(R[2, 1], R[2, 2])), pitch, float(np.arctan2(R[1, 0], R[0, 0]))]
    )


def _axis_rotation(axis: NDArray[np.float64], angle: float) -> NDArray[np.float64]:
    """Rotation matrix of ``angle`` (rad) about the unit ``axis`` (Rodrigues)."""
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * (K @ K)


def lock_xml(xml: str, values: dict[str, float]) -> str:
    """``xml`` (a :class:`ParsedURDF`'s) with the named joints made ``fixed`` at ``values``
    (rad or m): each one's origin becomes ``origin · motion(value)`` about or along its axis."""
    if not values:
        return xml
    root = ET.fromstring(xml)
    for joint in root.iter("joint"):
        name = joint.get("name", "")
        if name not in values:
            continue
        origin = joint.find("origin")
        xyz = _vector(origin, "xyz", "0 0 0")
        R = _rpy_matrix(_vector(origin, "rpy", "0 0 0"))
        axis = _vector(joint.find("axis"), "xyz", "1 0 0")
        norm = float(np.linalg.norm(axis))
        if norm < 1e-12:
            raise ValueError(f"urdf: joint {name!r} has a zero axis")
        axis = axis / norm
        if joint.get("type") == "prismatic":
            xyz = xyz + R @ axis * values[name]
        else:
            R = R @ _axis_rotation(axis, values[name])
        for tag in ("origin", "axis", "limit", "mimic", "dynamics", "safety_controller"):
            for el in joint.findall(tag):
                joint.remove(el)
        joint.set("type", "fixed")
        rpy = _matrix_rpy(R)
        ET.SubElement(
            joint,
            "origin",
            xyz=" ".join(repr(float(v)) for v in xyz),
            rpy=" ".join(repr(float(v)) for v in rpy),
        )
    return ET.tostring(root, encoding="unicode")
