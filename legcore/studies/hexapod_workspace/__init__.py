"""The ``hexapod_workspace`` study: the body workspace of a hexapod in tripod stance (seed 002,
MOEA/D).

``STUDY`` is its descriptor (registered by :mod:`legcore.studies.registry`); ``Params`` its
parameters; ``HexapodWorkspaceProblem`` the vectorised problem (:mod:`.problem`).
"""

from legcore.studies.hexapod_workspace.params import Params
from legcore.studies.hexapod_workspace.problem import HexapodWorkspaceProblem
from legcore.studies.hexapod_workspace.study import STUDY

__all__ = ["STUDY", "Params", "HexapodWorkspaceProblem"]
