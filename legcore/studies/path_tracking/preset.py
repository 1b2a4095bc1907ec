"""Seed 004's own settings on its own arm (``articulated_5dof``): the capsule on the plane
z = 0.50 m, the tool pointing down, the paper's law V = 0.10 m/s with t_a = t_d = 3 s, the speed
box of the seed example and its evaluation on the samples only.

On that catalog robot's kinematics (whatever its name, masses or motors) these fill the fields
the user left unset, before the robot-relative rules of
:mod:`legcore.studies.path_tracking.defaults`; every number of ``examples/004_*.yaml`` and of
docs/studies.md (seed 004) comes from them."""

from __future__ import annotations

from legcore.studies.path_tracking.params import CAPSULE, SEED_T_A, SEED_T_D, SEED_V
from legcore.studies.task import Preset

__all__ = ["PRESET"]

PRESET = Preset(
    robot="articulated_5dof",
    params={
        "segments": tuple(s.model_dump() for s in CAPSULE),
        "plane_origin": (0.0, 0.0, 0.50),  # "a una altura de 50cm sobre el eje Z"
        "plane_e1": (1.0, 0.0, 0.0),
        "plane_e2": (0.0, 1.0, 0.0),
        "orientation": "down",
        "rest": None,  # the arm's home: elbow up, facing the path
        "V": SEED_V,
        "t_a": SEED_T_A,
        "t_d": SEED_T_D,
        "V_bounds": (0.01, 1.0),
        "ramp_bounds": (0.005, 5.0),
        "limit_check": 1,
    },
    source="seed 004 (Sandoval Rodríguez et al.), §V–VI: the capsule at z = 50 cm, V = 10 cm/s, "
           "t_a = t_d = 3 s, on its 5-DOF arm (fig. 18)",
)
