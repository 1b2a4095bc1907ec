"""The ``swing_energy`` study: the swing of one leg through joint via points, for energy (seed 000,
Calderón et al. 2015).

``STUDY`` is its descriptor (registered by :mod:`legcore.studies.registry`); ``Params`` its
parameters; ``SwingEnergyProblem`` the vectorised problem (:mod:`.problem`).
"""

from legcore.studies.swing_energy.params import Params
from legcore.studies.swing_energy.problem import SwingEnergyProblem
from legcore.studies.swing_energy.study import STUDY

__all__ = ["STUDY", "Params", "SwingEnergyProblem"]
