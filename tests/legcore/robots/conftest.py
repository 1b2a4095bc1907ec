"""The ``erd_urdf`` fixture: real robots' URDF text from example-robot-data (see
:mod:`tests.robot_files`); tests using it skip, saying why, when the wheel is absent."""

from __future__ import annotations

from collections.abc import Callable
from functools import cache

import pytest

from tests.robot_files import ERD_URDF, erd_robots_dir, require_erd


@cache
def _read(name: str) -> str:
    root = erd_robots_dir()
    assert root is not None
    return (root / ERD_URDF[name]).read_text()


@pytest.fixture(scope="session")
def erd_urdf() -> Callable[[str], str]:
    """``erd_urdf("go1")`` → the URDF text of that robot (skips without the wheel)."""
    require_erd()
    return _read
