"""Seed 003's robot and the steps the ``quadruped_gait`` tests evaluate
(``test_quadruped_gait*.py``)."""

from __future__ import annotations

import numpy as np

from legcore.robots import catalog

ROBOT = catalog.get("animatronic_quadruped")
DEFAULT_X = np.array([0.119, 0.03, 0.8])
PAPER_WALK_X = np.array([0.119, 0.03, 0.75])
NEAR_OPT_X = np.array([0.055, 0.01, 0.856])
