"""A study's task made concrete for one robot: robot-relative defaults, the paper's preset, the
pre-flight check, and what an infeasible answer violates (DESIGN §5).

Every parameter of a study kind that depends on the robot (a leg's start and end postures, a
gait's speed, an arm's path and where it lies) is *derived from the robot it is given*, by a
documented rule, whenever the user leaves it out; a value the user gives is always used as
given. A study kind states that rule as its ``derive`` function
(``legcore/studies/<kind>/defaults.py``):

    derive(robot, params) -> Task

which returns the parameters with every unset robot-relative field filled in, the rule that
gave each (``Task.rules``, in words with the numbers), and raises
``ValueError("<field>: <why>; <what to change>")`` when the task — given or derived — cannot
work on this robot (the cheap pre-flight check: a path out of reach, no standing posture, a
step longer than the leg can make). A refusal is found before the job is queued.

A paper's own settings are data, not a branch: a :class:`Preset` names the paper's robot (a
catalog name) and the parameter values the paper used; on a robot with that robot's kinematics
(whatever its name or masses: :meth:`Preset.applies`) the preset fills the unset fields first, so
every seed number is reproduced with the defaults, and ``derive`` sees them as given.

A run's answer states whether it is feasible: :class:`Violation` is one violated constraint of a
solution with its size (``StudyProblem.violations``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from pydantic import ValidationError

__all__ = ["Fit", "Preset", "Task", "Violation", "fill", "validation_message"]


@dataclass(frozen=True)
class Task:
    """The parameters of a job on one robot: ``params`` (the study's ``Params`` with every
    robot-relative default filled in) and ``rules`` (field → the rule that gave its value, with
    the numbers, e.g. ``"0.6 × leg length (0.32 m) = 0.192 m below the hip"``; empty for the
    values the user gave). ``preset``: the paper whose settings filled the unset fields (its
    source text), or None."""

    params: Any
    rules: Mapping[str, str] = field(default_factory=dict)
    preset: str | None = None

    def as_dict(self) -> dict[str, Any]:
        """JSON-able: ``{"params": {...}, "rules": {...}, "preset": ...}``."""
        return {"params": self.params.model_dump(mode="json"), "rules": dict(self.rules),
                "preset": self.preset}


@dataclass(frozen=True)
class Preset:
    """A paper's settings on its own robot.

    ``robot``: the catalog name of the paper's robot; ``params``: the study parameters the
    paper used (JSON-able values, validated by the study's ``Params``); ``source``: the paper
    and table. It applies to a robot with the catalog robot's kinematics (:meth:`applies`; a
    robot of other geometry gets robot-relative defaults instead). ``cases``:
    the paper's values that depend on what the user gave (``cases(params) -> {field: value}``,
    e.g. a second case's end posture when there is an obstacle, or a value left out when the
    user gave another field that excludes it); :meth:`values` merges them over ``params``.
    """

    robot: str
    params: Mapping[str, Any]
    source: str
    cases: Callable[[Any], Mapping[str, Any]] | None = None

    def values(self, params: Any) -> Mapping[str, Any]:
        """The values this preset fills into ``params`` (its unset fields only, :func:`fill`)."""
        if self.cases is None:
            return self.params
        return {**self.params, **self.cases(params)}

    def applies(self, robot: Any) -> bool:
        """True when ``robot`` is this preset's catalog robot as far as the task goes: the same
        kinematics (joints, their geometry and position limits, base, tool, home), whatever its
        name, masses, inertias, motors and speed or torque limits — so a sweep of the paper's
        robot's masses keeps the paper's task at every point. A legged catalog robot (no
        spec): the catalog robot itself, or one of its name built without a spec."""
        from legcore.robots import catalog

        try:
            paper_robot = catalog.get(self.robot)
        except KeyError:
            return False
        if robot is paper_robot:
            return True
        mine, paper = getattr(robot, "spec", None), paper_robot.spec
        if paper is None or mine is None:
            return mine is None and paper is None and getattr(robot, "name", None) == self.robot
        return type(mine) is type(paper) and _geometry(mine) == _geometry(paper)


#: Spec fields that do not change a task's geometry (dynamics, names): ignored by
#: :meth:`Preset.applies`.
_NOT_GEOMETRY = frozenset({"name", "description", "mass", "com", "inertia", "motor", "tau_max",
                           "qd_max", "qdd_max"})


def _geometry(spec: Any) -> Any:
    """A robot spec's kinematic content: its JSON without :data:`_NOT_GEOMETRY` keys."""

    def strip(v: Any) -> Any:
        if isinstance(v, dict):
            return {k: strip(x) for k, x in v.items() if k not in _NOT_GEOMETRY}
        if isinstance(v, list):
            return [strip(x) for x in v]
        return v

    return strip(spec.model_dump(mode="json"))


def fill(params: Any, values: Mapping[str, Any]) -> Any:
    """``params`` with the fields the user left unset taken from ``values`` (validated by the
    params model; the filled fields then count as set). A combination the model refuses (a
    preset's value beside a given one) is ``ValueError("<field>: …")``."""
    given = params.model_dump(exclude_unset=True)
    missing = {k: v for k, v in values.items() if k not in params.model_fields_set}
    if not missing:
        return params
    try:
        return type(params).model_validate({**missing, **given})
    except ValidationError as exc:
        raise ValueError(validation_message(exc)) from None


def validation_message(exc: ValidationError) -> str:
    """``"<field>: <why>"`` of a pydantic error of a study's ``Params`` (the first one)."""
    err = exc.errors()[0]
    msg = str(err.get("msg", exc)).removeprefix("Value error, ")
    head = msg.split(" ", 1)[0]
    if head.endswith(":") and len(head) > 1:  # already "<field>: …"
        return msg
    loc = ".".join(str(p) for p in err.get("loc", ()))
    return f"{loc}: {msg}" if loc else msg


@dataclass(frozen=True)
class Violation:
    """One constraint a solution violates: ``constraint`` (its name, a column of ``G``),
    ``amount`` (how far past its limit, > 0, in ``unit``; for a ratio constraint such as
    ``max|q̇|/q̇_max − 1`` the fraction over, unit ``""``) and ``text`` (in words, e.g.
    ``"peak joint speed 12 % over its limit"``)."""

    constraint: str
    amount: float
    unit: str = ""
    text: str = ""

    def as_dict(self) -> dict[str, Any]:
        """JSON-able; ``text`` empty when the study gave no words (a reader words the
        constraint and amount itself)."""
        return {"constraint": self.constraint, "amount": float(self.amount), "unit": self.unit,
                "text": self.text}


@dataclass(frozen=True)
class Fit:
    """Does a study fit a robot — the one answer every listing and the submission give.

    ``accepted``: the robot has what the study needs and the task (the defaults, or the given
    parameters) passes the pre-flight check; then ``task`` is it. Otherwise ``field`` names
    what to change (``robot`` for a missing capability, else the parameter) and ``reason``
    says why and what to do.
    """

    kind: str
    accepted: bool
    reason: str | None = None
    field: str | None = None
    task: Task | None = None

    @property
    def message(self) -> str | None:
        """``"<field>: <reason>"`` (the ValueError text a submission is refused with)."""
        return None if self.accepted else f"{self.field}: {self.reason}"

    def as_dict(self) -> dict[str, Any]:
        """JSON-able: kind, accepted, field, reason, and the task's rules when accepted."""
        return {"kind": self.kind, "accepted": self.accepted, "field": self.field,
                "reason": self.reason,
                "task": None if self.task is None else self.task.as_dict()}
