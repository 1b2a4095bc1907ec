"""Fixtures of the numerical-IK tests: the UR5 and the Panda as DH chains
(``ik_numeric_helpers``)."""

from __future__ import annotations

import pytest

from legcore.robots import Robot
from tests.legcore.ik_numeric.ik_numeric_helpers import panda_dh, ur5_dh


@pytest.fixture(scope="module")
def ur5() -> Robot:
    return ur5_dh()


@pytest.fixture(scope="module")
def panda() -> Robot:
    return panda_dh()
