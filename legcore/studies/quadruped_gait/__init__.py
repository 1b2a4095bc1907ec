"""The ``quadruped_gait`` study: the four-beat walk of a quadruped, for energy under a stability
margin (seed 003).

``STUDY`` is its descriptor (registered by :mod:`legcore.studies.registry`); ``Params`` its
parameters; ``QuadrupedGaitProblem`` the vectorised problem (:mod:`.problem`). The walk is the
robot's: :mod:`.defaults` derives depth, standing posture, stroke centre, step, speed and margin
from its leg length and checks the task before a job is queued; :mod:`.preset` holds seed 003's
values for its own robot; :mod:`.feasibility` says what a step violates.
"""

from legcore.studies.quadruped_gait.params import Params
from legcore.studies.quadruped_gait.problem import QuadrupedGaitProblem
from legcore.studies.quadruped_gait.study import STUDY

__all__ = ["STUDY", "Params", "QuadrupedGaitProblem"]
