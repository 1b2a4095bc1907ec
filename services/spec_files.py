"""Robot files named in a spec on the user's machine, read by the CLI before submission.

A job spec (or a sweep's ``base``) given to ``legopt run/submit/sweep`` may name its robot's
URDF file instead of pasting it::

    robot: {urdf_file: arm.urdf, locked_joints: {finger: null}}

The CLI reads the file (relative to the spec file's folder) and sends the robot inline:
``{kind: urdf, name: arm, urdf: "<robot …>", …}`` (``name`` defaults to the file's stem). The
API never reads a path: a ``urdf_file`` reaching it is an unknown field (422).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

__all__ = ["MAX_URDF_BYTES", "inline_robot_files", "read_urdf_file", "robot_name_from"]

#: The largest URDF a robot spec holds (``URDFRobotSpec.urdf``: 2,000,000 characters).
MAX_URDF_BYTES = 2_000_000


def robot_name_from(path: Path) -> str:
    """A robot name from a file name: its stem, characters other than letters, digits, ``_``,
    ``-`` and ``.`` replaced by ``_``, at most 64 characters."""
    return re.sub(r"[^A-Za-z0-9_.\-]", "_", path.stem)[:64] or "robot"


def read_urdf_file(path: Path, field: str = "urdf_file") -> str:
    """The text of the URDF file ``path``; ``ValueError("<field>: …")`` when it cannot be read,
    is not UTF-8 text or is larger than a robot spec allows."""
    try:
        with path.open("rb") as f:
            data = f.read(MAX_URDF_BYTES + 1)
    except OSError as exc:
        raise ValueError(f"{field}: cannot read {path}: {exc.strerror or exc}") from None
    if len(data) > MAX_URDF_BYTES:
        raise ValueError(f"{field}: {path} is larger than {MAX_URDF_BYTES / 1e6:g} MB")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{field}: {path} is not UTF-8 text") from None


def _inline(robot: dict[str, Any], base_dir: Path, loc: str) -> dict[str, Any]:
    name = robot["urdf_file"]
    if not isinstance(name, str) or not name:
        raise ValueError(f"{loc}.urdf_file: must be a file name (relative to the spec file)")
    if "urdf" in robot:
        raise ValueError(f"{loc}: give either 'urdf' (the text) or 'urdf_file', not both")
    path = Path(name).expanduser()
    if not path.is_absolute():
        path = base_dir / path
    out = {k: v for k, v in robot.items() if k != "urdf_file"}
    out.setdefault("kind", "urdf")
    out.setdefault("name", robot_name_from(path))
    out["urdf"] = read_urdf_file(path, f"{loc}.urdf_file")
    return out


def inline_robot_files(data: dict[str, Any], base_dir: Path) -> dict[str, Any]:
    """``data`` (a job spec or a sweep document) with ``robot.urdf_file`` and
    ``base.robot.urdf_file`` replaced by the file's text (see the module docstring); relative
    names are taken from ``base_dir``. ``ValueError("robot.urdf_file: …")`` on a bad file."""
    out = dict(data)
    robot = out.get("robot")
    if isinstance(robot, dict) and "urdf_file" in robot:
        out["robot"] = _inline(robot, base_dir, "robot")
    base = out.get("base")
    if isinstance(base, dict):
        robot = base.get("robot")
        if isinstance(robot, dict) and "urdf_file" in robot:
            out["base"] = {**base, "robot": _inline(robot, base_dir, "base.robot")}
    return out
