"""The ``quadruped_gait`` study: the four-beat walk of a quadruped, for energy under a stability
margin (seed 003).

``STUDY`` is its descriptor (registered by :mod:`legcore.studies.registry`); ``Params`` its
parameters; ``QuadrupedGaitProblem`` the vectorised problem (:mod:`.problem`).
"""

from legcore.studies.quadruped_gait.params import Params
from legcore.studies.quadruped_gait.problem import STUDY, QuadrupedGaitProblem

__all__ = ["STUDY", "Params", "QuadrupedGaitProblem"]
