"""What a study adds on top of a plain `Problem`: parameters, decoded solutions, baselines.

A study package (``legcore/studies/<kind>/``) defines

- ``Params`` — a :class:`StudyParams` subclass with ``kind: Literal["<kind>"]`` and the study's
  parameters; a robot-relative one defaults to None, filled from the robot by the study's
  ``derive`` (``defaults.py``) or, on the paper's own robot, by its ``Preset`` (``preset.py``);
- a :class:`StudyProblem` subclass — vectorised ``_evaluate``, plus ``solution(x)`` (the full
  decoded trajectory with metrics) and ``baseline_solutions()`` (the paper's reference
  trajectories, decoded the same way);
- ``STUDY`` — a :class:`Study` descriptor: default robot, the seed's optimiser and budget, and
  ``build(robot, params) -> StudyProblem``.

:class:`Motion` is the one time-series format every study decodes to; `legcore.recording` turns
it into what the worker logs to Rerun, and the CLI/API summarise it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, ValidationError

from legcore.problems.base import Problem
from legcore.robots.capabilities import Needs, capabilities, refusal
from legcore.studies.task import Fit, Preset, Task, Violation, fill, validation_message

__all__ = ["Box", "Fit", "Motion", "Solution", "Study", "StudyParams", "StudyProblem", "Task",
           "Violation"]

FloatArray = NDArray[np.float64]


class StudyParams(BaseModel):
    """Base of every study's parameter model: strict (unknown keys rejected) and frozen."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    kind: str


@dataclass(frozen=True)
class Box:
    """An axis-aligned box obstacle: ``center`` (3,) and ``half_size`` (3,), m, world frame."""

    center: tuple[float, float, float]
    half_size: tuple[float, float, float]

    def contains(self, p: FloatArray, margin: float = 0.0) -> NDArray[np.bool_]:
        """(…,) True where points ``p`` (…, 3) are inside the box grown by ``margin`` (m)."""
        d = np.abs(np.asarray(p, dtype=float) - np.asarray(self.center))
        return np.all(d <= np.asarray(self.half_size) + margin, axis=-1)


@dataclass(frozen=True, eq=False)
class Motion:
    """Time series of one decoded solution (SI units; K samples, n joints).

    ``t`` (K,) s; ``q``, ``qd``, ``qdd``, ``jerk`` (K, n) rad, rad/s, rad/s², rad/s³; ``tau``
    (K, n) N·m; ``power`` (K, n) W (signed τ·ω, or electrical power when ``power_kind`` says
    so); ``energy`` (K,) cumulative J. ``tool`` (K, 3) m: the foot/tool path in the world (or
    body) frame. ``robot``: catalog name or robot name; ``legs``: for a multi-legged robot, the
    leg names, and then ``q`` holds the legs' joints side by side (leg-major, ``joint_names``
    tells which is which). ``scene``: targets (M, 3), obstacles (list of :class:`Box`),
    support polygon (P, 3) etc., keyed by name.
    """

    t: FloatArray
    q: FloatArray
    joint_names: tuple[str, ...]
    qd: FloatArray | None = None
    qdd: FloatArray | None = None
    jerk: FloatArray | None = None
    tau: FloatArray | None = None
    power: FloatArray | None = None
    energy: FloatArray | None = None
    tool: FloatArray | None = None
    robot: str = ""
    legs: tuple[str, ...] = ()
    power_kind: str = "mechanical"
    scene: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        K = self.t.shape[0]
        if self.q.ndim != 2 or self.q.shape[0] != K:
            raise ValueError(f"q: expected shape ({K}, n), got {self.q.shape}")
        if len(self.joint_names) != self.q.shape[1]:
            raise ValueError("joint_names: one name per column of q")
        for name in ("qd", "qdd", "jerk", "tau", "power"):
            a = getattr(self, name)
            if a is not None and a.shape != self.q.shape:
                raise ValueError(f"{name}: expected shape {self.q.shape}, got {a.shape}")
        if self.energy is not None and self.energy.shape != (K,):
            raise ValueError(f"energy: expected shape ({K},), got {self.energy.shape}")
        if self.tool is not None and self.tool.shape != (K, 3):
            raise ValueError(f"tool: expected shape ({K}, 3), got {self.tool.shape}")

    @property
    def n_samples(self) -> int:
        return int(self.t.shape[0])


@dataclass(frozen=True, eq=False)
class Solution:
    """A decision vector decoded into everything a report, a table or a recording needs.

    ``objectives``: named objective values (as the paper states them, e.g. the seed 000 score
    to maximise); ``metrics``: named scalars (energy J, θ_T rad, path length m, feasibility…);
    ``table``: per-joint rows like seed 000 Table 2 (``{"metric", "unit", "values": [...]}``);
    ``motion``: the time series (None when the study has none); ``extra``: study-specific
    JSON-able outputs (servo table, workspace, …). ``violations``: the constraints the solution
    violates, with their size (``()``: feasible; None: not checked — ``legcore.runner.finalize``
    checks the optimum and every baseline with :meth:`StudyProblem.violations`).
    """

    x: FloatArray | None
    objectives: dict[str, float]
    metrics: dict[str, float]
    table: list[dict[str, Any]] = field(default_factory=list)
    motion: Motion | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    violations: tuple[Violation, ...] | None = None

    @property
    def feasible(self) -> bool | None:
        """True when no constraint is violated, None when not checked."""
        return None if self.violations is None else not self.violations

    def summary(self) -> dict[str, Any]:
        """JSON-able summary (no time series): x, objectives, metrics, table, extra, and when
        checked ``feasible`` and ``violations``."""
        out: dict[str, Any] = {
            "x": None if self.x is None else [float(v) for v in self.x],
            "objectives": {k: float(v) for k, v in self.objectives.items()},
            "metrics": {k: float(v) for k, v in self.metrics.items()},
            "table": self.table,
            "extra": self.extra,
        }
        if self.violations is not None:
            out["feasible"] = not self.violations
            out["violations"] = [v.as_dict() for v in self.violations]
        return out


class StudyProblem(Problem):
    """A `Problem` that decodes to full solutions and carries its paper's baselines.

    Subclasses set ``objective_names`` (one per objective, in F's column order; minimised),
    ``constraint_names`` (one per column of G) and ``n_samples`` (time samples per evaluated
    trajectory, used for the job-size limit), and implement ``solution`` and
    ``baseline_solutions``. ``extras`` may add study-level outputs computed from the final front
    (e.g. the hexapod's stable/unstable split); ``violations`` says what an infeasible solution
    violates. ``task``: the robot-relative parameters the problem was built with (set by
    :meth:`Study.build`).
    """

    objective_names: tuple[str, ...] = ()
    constraint_names: tuple[str, ...] = ()
    n_samples: int = 1
    task: Task | None = None

    def solution(self, x: FloatArray) -> Solution:  # pragma: no cover - abstract in spirit
        raise NotImplementedError

    def baseline_solutions(self) -> dict[str, Solution]:
        return {}

    def extras(self, front_X: FloatArray, front_F: FloatArray) -> dict[str, Any]:
        return {}

    def free_start(self) -> tuple[str, FloatArray] | None:
        """The solution the problem's encoding or initialisation gives without any search,
        as ``(what it is, x)`` — e.g. the coordinated motion that all-zero genes decode to, or
        the original placement the population is seeded with — or None. A result reports it
        beside the optimum so that nobody credits the optimiser with what the coding gave."""
        return None

    def reference_optimum(self) -> dict[str, Any] | None:
        """For a single objective, the best value any answer can reach, from an exact
        solution of the same problem: ``{"objective", "value", "kind", "method"[, "sense"]}``
        (:func:`legcore.optimality_gap.optimality_gap`), or None (the default: none known)."""
        return None

    def violations(self, x: FloatArray) -> tuple[Violation, ...]:
        """The constraints ``x`` violates (``G > 0``), each with its size: the columns of G
        named by ``constraint_names`` (``g1``, ``g2``, … when unnamed), in G's units. A study
        overrides this to say more (units, which joint) or to count what its G does not."""
        _, G = self.evaluate(np.asarray(x, dtype=float)[None, :])
        names = self.constraint_names or tuple(f"g{j + 1}" for j in range(self.n_constr))
        return tuple(Violation(str(n), float(g)) for n, g in zip(names, G[0], strict=True)
                     if g > 0.0)

    def companions(self) -> list[tuple[Problem, int]]:
        """Other problems a job of this one evaluates, each with its population (e.g. the
        baseline GAs a swing_energy job runs after the search): :mod:`legcore.memory` sizes
        a job by the largest of them. Default: none."""
        return []

    def decode(self, x: np.ndarray) -> dict[str, Any]:
        return self.solution(np.asarray(x, dtype=float)).summary()


@dataclass(frozen=True)
class Study:
    """Descriptor of a study kind: its parameter model, defaults and problem builder.

    ``default_optimizer`` is ``{"kind": ..., "params": {...}}`` with the seed's settings;
    ``default_generations`` the seed's budget; ``robot_kinds`` which robots it accepts
    ("serial" and/or "legged").

    ``needs``: what the study needs from a robot, as alternatives (a robot is accepted when it
    meets one of them; empty: any robot of ``robot_kinds``) — checked by :meth:`refusal`
    before ``build`` (``legcore.studies.registry`` wraps ``build`` with that check).
    ``description``: a paragraph for listings (``GET /studies``, ``legopt studies``);
    ``plugin``: the distribution that registered the kind (None for a built-in kind).

    ``derive(robot, params) -> Task``: the robot-relative defaults and the pre-flight check
    (:mod:`legcore.studies.task`); ``preset``: the paper's settings on its own robot, applied
    before ``derive``; ``robot_relative``: the parameters ``derive`` fills from the robot when
    left out (listings show them as "from the robot"). :meth:`task` runs both. ``build`` is
    wrapped on creation so that it refuses a robot :meth:`refusal` rejects with
    ``ValueError("robot: <kind> needs …")``, then builds the study's problem from
    :meth:`task`'s parameters (``problem.task`` keeps them).
    """

    kind: str
    title: str
    seed_paper: str
    params: type[StudyParams]
    default_robot: str
    default_optimizer: dict[str, Any]
    default_generations: int
    build: Callable[[Any, Any], StudyProblem]
    robot_kinds: tuple[str, ...] = ("serial",)
    needs: tuple[Needs, ...] = ()
    description: str = ""
    plugin: str | None = None
    derive: Callable[[Any, Any], Task] | None = None
    preset: Preset | None = None
    robot_relative: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        inner = getattr(self.build, "_unchecked", self.build)

        def build(robot: Any, params: Any) -> StudyProblem:
            verdict = self.fit(robot, params)
            if verdict.task is None:
                raise ValueError(verdict.message)
            problem = inner(robot, verdict.task.params)
            problem.task = verdict.task
            return problem

        build._unchecked = inner  # type: ignore[attr-defined]
        build.__doc__ = inner.__doc__
        object.__setattr__(self, "build", build)

    def fit(self, robot: Any, params: Any = None) -> Fit:
        """Whether this study fits ``robot`` with ``params`` (None: the defaults) — the one
        answer of the submission (``build`` uses it) and of every listing
        (:func:`legcore.studies.fit.fit`): the robot's capabilities (:meth:`refusal`, field
        ``robot``), then :meth:`task` (the preset and robot-relative defaults and the
        pre-flight check; its ``ValueError("<field>: …")`` names the field)."""
        reason = self.refusal(robot)
        if reason is not None:
            return Fit(self.kind, False, reason, "robot")
        if params is None:
            params = self.params(kind=self.kind)
        try:
            task = self.task(robot, params)
        except ValueError as exc:
            field, _, why = str(exc).partition(": ")
            if not why or " " in field:
                field, why = "problem", str(exc)
            return Fit(self.kind, False, why, field)
        return Fit(self.kind, True, task=task)

    def task(self, robot: Any, params: Any) -> Task:
        """``params`` made concrete for ``robot`` (the robot must not be refused): the paper's
        preset on its own robot fills the unset fields first, then ``derive`` the
        robot-relative rest and runs the pre-flight check (``ValueError`` naming the field)."""
        preset = None
        if self.preset is not None and self.preset.applies(robot):
            params = fill(params, self.preset.values(params))
            preset = self.preset.source
        if self.derive is None:
            return Task(params, {}, preset)
        try:
            task = self.derive(robot, params)
        except ValidationError as exc:  # a derived value the params model refuses
            raise ValueError(validation_message(exc)) from None
        return Task(task.params, task.rules, preset) if preset is not None else task

    def refusal(self, robot: Any) -> str | None:
        """Why this study cannot run on ``robot`` (naming the missing capability), or None.

        The first unmet need of the alternative that matches the robot's kind (serial or
        legged) is reported; a robot meeting any alternative is accepted.
        """
        kind = "legged" if capabilities(robot).kind == "legged" else "serial"
        if kind not in self.robot_kinds:
            return (f"{self.kind} needs a {' or '.join(self.robot_kinds)} robot; robot "
                    f"{getattr(robot, 'name', '?')} is {kind}")
        if not self.needs:
            return None
        reasons = [refusal(self.kind, n, robot) for n in self.needs]
        if any(r is None for r in reasons):
            return None
        same = [r for n, r in zip(self.needs, reasons, strict=True)
                if (n.legged and kind == "legged") or (n.serial and kind == "serial")]
        return (same or reasons)[0]
