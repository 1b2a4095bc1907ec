"""Fixtures of the ``hexapod_workspace`` tests (seed 002): the study's problem on seed 002's
robot with the seed's parameters."""

from __future__ import annotations

import pytest

from legcore.robots import catalog
from legcore.studies.hexapod_workspace.problem import HexapodWorkspaceProblem, Params
from legcore.studies.hexapod_workspace.study import build


@pytest.fixture(scope="module")
def problem() -> HexapodWorkspaceProblem:
    return build(catalog.get("citedi_hexapod"), Params())
