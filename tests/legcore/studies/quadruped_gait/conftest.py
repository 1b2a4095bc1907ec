"""Fixtures of the ``quadruped_gait`` tests (seed 003): the study's problem on seed 003's robot
and the solution of its default step."""

from __future__ import annotations

from typing import Any

import pytest

from legcore.studies.quadruped_gait.problem import Params
from legcore.studies.quadruped_gait.study import build
from tests.legcore.studies.quadruped_gait.quadruped_gait_helpers import DEFAULT_X, ROBOT


@pytest.fixture(scope="module")
def problem() -> Any:
    return build(ROBOT, Params())


@pytest.fixture(scope="module")
def default_solution(problem: Any) -> Any:
    return problem.solution(DEFAULT_X)
