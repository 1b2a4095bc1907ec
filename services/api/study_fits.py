"""Whether each study kind fits a robot, as every API view shows it.

One answer for ``GET /studies``, ``GET /robots/{id}`` (and so ``legopt robots show``), the
dashboard's robot page and ``POST /jobs``: :func:`legcore.studies.fit.fit`, the function the
submission's ``Study.build`` runs — the robot's capabilities, then the study's task with its
defaults derived from the robot and the pre-flight check. A study the robot does not fit says
which field to change (``robot`` for a missing capability) and why; one it fits gives the rules
its default task was derived by.
"""

from __future__ import annotations

import logging
from typing import Any

from pydantic import BaseModel, Field

from legcore.studies.fit import fit
from legcore.studies.registry import studies
from legcore.studies.task import Fit

__all__ = ["StudyFitOut", "fit_of", "robot_fits"]

log = logging.getLogger("legopt.api")


class StudyFitOut(BaseModel):
    """Whether a study kind accepts a robot with its default task, and why not."""

    kind: str
    title: str
    accepted: bool
    field: str | None = Field(
        default=None, description="What to change when refused: `robot` (a capability the robot "
        "lacks) or the study parameter the pre-flight check names."
    )
    reason: str | None = Field(default=None, description="Why it is refused, and what to do.")
    rules: dict[str, str] = Field(
        default_factory=dict,
        description="When accepted: each parameter derived from the robot and the rule with its "
        "numbers (empty on the paper's own robot, where the paper's settings apply).",
    )
    preset: str | None = Field(
        default=None, description="The paper whose settings the default task takes (on its own "
        "robot), else null."
    )


def fit_of(robot: Any, kind: str) -> Fit:
    """:func:`legcore.studies.fit.fit`, with a study whose check itself fails (a plug-in's bug)
    reported as a refusal instead of failing the listing."""
    try:
        return fit(robot, kind)
    except Exception as exc:  # noqa: BLE001 - a plug-in's check failing must not fail a listing
        log.warning("fit check of %s failed: %r", kind, exc)
        return Fit(kind, False, f"{kind} could not check this robot: {type(exc).__name__}: {exc}",
                   "robot")


def robot_fits(robot: Any) -> list[StudyFitOut]:
    """Every study kind's verdict on ``robot``, sorted by kind."""
    out = []
    for kind, study in sorted(studies().items()):
        v = fit_of(robot, kind)
        task = v.task
        out.append(StudyFitOut(
            kind=kind, title=study.title, accepted=v.accepted, field=v.field, reason=v.reason,
            rules=dict(task.rules) if task is not None else {},
            preset=task.preset if task is not None else None,
        ))
    return out
