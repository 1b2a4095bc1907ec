"""The ``path_tracking`` study: the time law of an arm running a line/arc path (seed 004).

``STUDY`` is its descriptor (registered by :mod:`legcore.studies.registry`); ``Params`` its
parameters; ``PathTrackingProblem`` the vectorised problem (:mod:`.problem`).
"""

from legcore.studies.path_tracking.params import Params
from legcore.studies.path_tracking.problem import PathTrackingProblem
from legcore.studies.path_tracking.study import STUDY

__all__ = ["STUDY", "Params", "PathTrackingProblem"]
