"""Fixtures of the ``path_placement`` tests (seed 001): the catalog's PUMA 560 and the study's
problem on its "pan" path."""

from __future__ import annotations

from typing import Any

import pytest

from legcore.robots import catalog
from legcore.studies.path_placement.problem import Params
from legcore.studies.path_placement.study import build


@pytest.fixture(scope="module")
def robot() -> Any:
    return catalog.get("puma560")


@pytest.fixture(scope="module")
def pan(robot: Any) -> Any:
    return build(robot, Params(path="pan"))
