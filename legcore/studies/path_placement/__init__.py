"""The ``path_placement`` study: placing a tool path in an arm's workspace for energy and
manipulability (seed 001, Ramírez Henao & Duque Muñoz 2015).

``STUDY`` is its descriptor (registered by :mod:`legcore.studies.registry`); ``Params`` its
parameters; ``PathPlacementProblem`` the vectorised problem (:mod:`.problem`).
"""

from legcore.studies.path_placement.params import Params
from legcore.studies.path_placement.problem import PathPlacementProblem
from legcore.studies.path_placement.study import STUDY

__all__ = ["STUDY", "Params", "PathPlacementProblem"]
