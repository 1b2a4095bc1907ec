"""URDF files of real robots from the ``example-robot-data`` wheel (a dev dependency).

The wheel (6.0.0) ships the files only — its Python loaders are another package — under its
cmeel prefix, ``cmeel.prefix/share/example-robot-data/robots/<robot>_description/…``, found
through the installed distribution::

    from tests.robot_files import erd_robots_dir
    root = erd_robots_dir()            # None when the wheel is not installed
    text = (root / ERD_URDF["ur5"]).read_text()
"""

from __future__ import annotations

import importlib.metadata
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

__all__ = ["ERD_URDF", "erd_arm_spec", "erd_robots_dir"]

#: name -> path of the URDF under the wheel's robots directory.
ERD_URDF = {
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "kinova": "kinova_description/robots/kinova.urdf",
    "z1": "z1_description/urdf/z1.urdf",
    "so100": "so_arm_description/urdf/so100.urdf",
    "solo12": "solo_description/robots/solo12.urdf",
    "anymal": "anymal_b_simple_description/robots/anymal.urdf",
    "anymal_kinova": "anymal_b_simple_description/robots/anymal-kinova.urdf",
    "anymal_c": "anymal_c_simple_description/urdf/anymal.urdf",
    "go1": "go1_description/urdf/go1.urdf",
}


def erd_robots_dir() -> Path | None:
    """The wheel's robots directory, or None when example-robot-data is not installed."""
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    path = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
    return path if path.is_dir() else None


def require_erd() -> Path:
    """The wheel's robots directory; skips the test without it — or fails, where
    ``LEGOPT_REQUIRE_ROBOT_DATA=1`` (``.ci/run``: a real-robot test must not silently skip)."""
    import pytest

    root = erd_robots_dir()
    if root is None:
        why = "example-robot-data is not installed (dev dependency, see pyproject.toml)"
        if os.environ.get("LEGOPT_REQUIRE_ROBOT_DATA") == "1":
            pytest.fail(why)
        pytest.skip(why)
    return root


def erd_arm_spec(text: str, name: str, tool_frame: str | None = None) -> dict[str, Any]:
    """The robot spec of an arm's URDF ``text`` with its gripper's finger joints locked (the
    arm's own chain is what IK and the studies use)."""
    fingers = [j.get("name", "") for j in ET.fromstring(text).iter("joint")
               if "finger" in j.get("name", "") and j.get("type") != "fixed"]  # fmt: skip
    spec: dict[str, Any] = {"kind": "urdf", "name": name, "urdf": text,
                            "locked_joints": dict.fromkeys(fingers)}  # fmt: skip
    if tool_frame:
        spec["tool_frame"] = tool_frame
    return spec
