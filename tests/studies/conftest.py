"""Shared scaffolding of the study × robot matrix (issue 9, "Must show"): real robots from
example-robot-data (a dev dependency, :mod:`tests.robot_files`), the presets of ``examples/``
with their URDF files read from that wheel, short runs through ``legcore.run``, refusals, and
independent physical checks (:mod:`tests.studies.physics`).

A matrix row is a robot × a study kind: either a short run with physical checks, or the
refusal naming the missing capability. The robots (``MATRIX_ROBOTS``) are shared by the legged
and the arm kinds; add rows in your own test module.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any

import pytest
import yaml

from legcore.robots import LeggedRobot, Robot, build_any_robot
from services.spec_files import inline_robot_files
from tests.robot_files import ERD_URDF, erd_robots_dir, require_erd

ROOT = Path(__file__).resolve().parents[2]
PRESETS = ROOT / "examples" / "presets"

#: Matrix robots: name -> (example-robot-data file, extra robot-spec fields).
MATRIX_ROBOTS: dict[str, tuple[str, dict[str, Any]]] = {
    "ur5": ("ur5", {}),
    "panda": ("panda", {"locked_joints": {"panda_finger_joint1": 0.02}}),
    "kinova": ("kinova", {}),
    "z1": ("z1", {"locked_joints": {"jointGripper": None}}),
    "so100": ("so100", {"locked_joints": {"gripper": None}}),
    "solo12_leg": ("solo12", {"legs": "auto", "leg": "FL"}),  # one leg, a serial chain
    "solo12": ("solo12", {"legs": "auto"}),
    "anymal": ("anymal", {"legs": "auto"}),
    "go1": ("go1", {"legs": "auto"}),
}


@cache
def _urdf(file_key: str) -> str:
    root = erd_robots_dir()
    assert root is not None
    return (root / ERD_URDF[file_key]).read_text()


@pytest.fixture(scope="session")
def robot_spec() -> Callable[[str], dict[str, Any]]:
    """``robot_spec("go1")`` → the inline URDF robot spec of a matrix robot (a new dict)."""
    require_erd()

    def make(name: str) -> dict[str, Any]:
        file_key, extra = MATRIX_ROBOTS[name]
        return {"kind": "urdf", "name": name, "urdf": _urdf(file_key), **copy.deepcopy(extra)}

    return make


@cache
def _built(name: str) -> Robot | LeggedRobot:
    file_key, extra = MATRIX_ROBOTS[name]
    return build_any_robot({"kind": "urdf", "name": name, "urdf": _urdf(file_key), **extra})


@pytest.fixture(scope="session")
def built_robot() -> Callable[[str], Robot | LeggedRobot]:
    """``built_robot("solo12")`` → the built model of a matrix robot (cached)."""
    require_erd()
    return _built


@pytest.fixture(scope="session")
def preset() -> Callable[[str], dict[str, Any]]:
    """``preset("quadruped_gait_go1")`` → ``examples/presets/<name>.yaml`` as a job spec, its
    ``robot.urdf_file`` read from example-robot-data (as ``legopt run`` would from a copy)."""
    root = require_erd()

    def load(name: str) -> dict[str, Any]:
        data = yaml.safe_load((PRESETS / f"{name}.yaml").read_text())
        return inline_robot_files(data, root)

    return load


def refusal_message(spec: dict[str, Any]) -> str:
    """The ValueError message ``legcore.runner.prepare`` raises for ``spec`` (fails if none)."""
    from legcore.runner import prepare

    with pytest.raises(ValueError) as exc:
        prepare(spec)
    return str(exc.value)
