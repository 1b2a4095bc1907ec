"""Seed 001's own settings on its own arm (``puma560``): the paper's paths at their size and
duration, where they are drawn (the ORIGINAL placement), the simplified spherical workspace of
eqs 1–5 as the region, the closed-form IK from the arm's home, and the nominal power of eq 15
(0.4 kW, assumed for the PUMA 560 — the paper does not print it).

On that catalog robot's kinematics (whatever its name, masses or motors) these fill the fields
the user left unset, before the robot-relative rules of
:mod:`legcore.studies.path_placement.defaults`; every number of ``examples/001_*.yaml`` and of
docs/studies.md (seed 001) comes from them."""

from __future__ import annotations

from legcore.studies.path_placement.params import PUMA560_NOMINAL_POWER_KW
from legcore.studies.task import Preset

__all__ = ["PRESET"]

PRESET = Preset(
    robot="puma560",
    params={
        "path_scale": 1.0,  # the paper's pan (r = 0.08 m) and jar (r = 0.06 m, h = 0.15 m)
        "path_axis": None,  # as drawn
        "spin": 0.0,  # the tool x axis along the world x projected
        "duration": None,  # the paper's: 1.01205355 s (pan), 1.66888271 s (jar)
        "region": None,  # the simplified spherical workspace, eqs 1–5
        "original": None,  # where the path is drawn (pan centre (0.25, 0, 0.80) m)
        "postures": None,  # the closed form's 8 branches (home for a numerical IK)
        "nominal_power_kw": PUMA560_NOMINAL_POWER_KW,
    },
    source="seed 001 (Ramírez Henao & Duque Muñoz 2015), Tables 2–3: the pan and jar paths "
           "on the PUMA 560, its simplified workspace (eqs 1–5), P_n assumed 0.4 kW",
)
