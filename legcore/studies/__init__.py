"""Study kinds: tasks defined relative to the robot they are given (DESIGN §5).

One package per kind, ``legcore/studies/<kind>/``: its problem, parameters, robot-relative
defaults, metric names and its paper preset side by side. Below them all sits the abstract
:class:`legcore.problems.base.Problem` (what every optimiser drives); :mod:`.study` adds what a
study has on top of it (decoded solutions, baselines, the descriptor), :mod:`.registry` finds
the kinds (built-in and plug-ins).

    from legcore.studies import get_study
    study = get_study("swing_energy")
"""

from legcore.studies.registry import get_study, studies
from legcore.studies.study import Motion, Solution, Study, StudyParams, StudyProblem

__all__ = ["Motion", "Solution", "Study", "StudyParams", "StudyProblem", "get_study", "studies"]
