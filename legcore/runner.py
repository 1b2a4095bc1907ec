"""`legcore.run(spec) -> RunResult`: one job, start to finish, in-process.

The worker uses the same pieces step by step (``prepare`` → ``Run`` → ``finalize``) so that it can
write progress, checkpoint, cancel and resume between generations; ``run`` is that loop in one
call. Both produce the same :class:`RunResult` for the same spec and seed.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from legcore.earned import earned_summary
from legcore.jobspec import JobSpec, parse_job_spec
from legcore.optimality_gap import optimality_gap, refined_reference
from legcore.optimizers import Progress, Result, Run, get_algorithm, termination_from_budget
from legcore.optimizers.base import Algorithm
from legcore.optimizers.termination import Termination
from legcore.problems.base import constraint_violation
from legcore.robots import LeggedRobot, Robot, build_any_robot, catalog
from legcore.studies.registry import get_study
from legcore.studies.study import Solution, Study, StudyProblem, Task

__all__ = [
    "JobSize",
    "Prepared",
    "RunResult",
    "finalize",
    "job_shape",
    "job_size",
    "prepare",
    "resolve_robot",
    "run",
]


def resolve_robot(spec: JobSpec, study: Study) -> Robot | LeggedRobot:
    """The robot of a job: a catalog name, an inline spec, or the study's default robot."""
    robot_ref = spec.robot if spec.robot is not None else study.default_robot
    if isinstance(robot_ref, str):
        try:
            robot = catalog.get(robot_ref)
        except KeyError as exc:
            raise ValueError(f"robot: {exc.args[0]}") from None
    else:
        robot = build_any_robot(robot_ref)
    reason = study.refusal(robot)
    if reason is not None:
        raise ValueError(f"robot: {reason}")
    return robot


@dataclass(frozen=True, eq=False)
class Prepared:
    """Everything needed to run a job: the validated spec and the built objects."""

    spec: JobSpec
    study: Study
    robot: Robot | LeggedRobot
    problem: StudyProblem
    algorithm: Algorithm
    termination: Termination
    total_generations: int | None

    def new_run(self, state: dict[str, Any] | None = None) -> Run:
        """A fresh `Run` (or one resumed from a checkpoint ``state``)."""
        return Run(self.problem, self.algorithm, self.termination, seed=self.spec.seed, state=state)


def prepare(
    spec: JobSpec | dict[str, Any],
    *,
    robot: Robot | LeggedRobot | None = None,
    build_problem: Callable[[Study, Robot | LeggedRobot, Any], StudyProblem] | None = None,
) -> Prepared:
    """Validate ``spec`` and build robot, problem, algorithm and termination.

    Injection points, for a caller that builds many jobs (the API's validation reuses what one
    request built already): ``robot``, the job's robot built already (None: the spec's catalog
    name, inline robot or the study's default robot, built here; a given robot the study
    refuses is a ``ValueError`` at ``robot``), and ``build_problem(study, robot, problem_spec)``
    (default ``study.build(robot, problem_spec)``).

    Raises pydantic ``ValidationError`` or ``ValueError`` (message starting with the field) for
    a spec that cannot run.
    """
    spec = parse_job_spec(spec)
    study = get_study(spec.problem.kind)
    if robot is None:
        robot = resolve_robot(spec, study)
    elif (reason := study.refusal(robot)) is not None:
        raise ValueError(f"robot: {reason}")
    if build_problem is None:
        problem = study.build(robot, spec.problem)
    else:
        problem = build_problem(study, robot, spec.problem)
    return assemble(spec, study, robot, problem)


def assemble(
    spec: JobSpec, study: Study, robot: Robot | LeggedRobot, problem: StudyProblem
) -> Prepared:
    """The :class:`Prepared` job of a parsed ``spec`` whose study, robot and built problem are
    given: the optimiser (the study's default unless the spec names one) and the termination
    from the budget (the study's default generations when only ``ftol`` is given)."""
    opt = spec.optimizer
    kind = opt.kind if opt is not None else study.default_optimizer["kind"]
    params = dict(opt.params) if opt is not None else dict(study.default_optimizer["params"])
    algorithm = get_algorithm(kind, **params)
    b = spec.budget
    generations = b.generations
    if generations is None and b.evaluations is None and b.wall_time_s is None:  # ftol alone
        generations = study.default_generations
    termination = termination_from_budget(
        n_gen=generations,
        n_evals=b.evaluations,
        seconds=b.wall_time_s,
        ftol=b.ftol,
        window=b.window,
    )
    return Prepared(spec, study, robot, problem, algorithm, termination, generations)


@dataclass(frozen=True)
class JobSize:
    """The work a job asks for: population per generation, generations, samples per evaluation."""

    population: int
    generations: int
    samples: int
    #: predicted peak resident memory of a process running the job, bytes (legcore.memory)
    peak_bytes: int = 0

    @property
    def work(self) -> int:
        return self.population * self.generations * self.samples


def job_shape(prepared: Prepared) -> tuple[int, int]:
    """(population per generation, generations) of a prepared job — what :func:`job_size`
    reports without measuring the memory."""
    params = prepared.algorithm.params
    population = next(
        (int(params[k]) for k in ("pop_size", "n_samples", "n_subproblems") if k in params), 1
    )
    generations = prepared.total_generations
    if generations is None:
        evals = prepared.spec.budget.evaluations
        generations = -(-evals // population) if evals else prepared.study.default_generations
    return population, int(generations)


def job_size(prepared: Prepared) -> JobSize:
    """Estimate the size of a prepared job (for the service's per-job limits), with its
    predicted peak memory (:func:`legcore.memory.predicted_peak_bytes`: measured on a few
    evaluations, milliseconds)."""
    from legcore.memory import predicted_peak_bytes

    population, generations = job_shape(prepared)
    return JobSize(population, generations, max(1, int(prepared.problem.n_samples)),
                   predicted_peak_bytes(prepared.problem, population))


@dataclass(frozen=True, eq=False)
class RunResult:
    """The outcome of a job (JSON via :meth:`to_dict`; time series in ``best.motion``).

    ``extras`` (the study's outputs computed from the final front: workspaces, masks, … —
    up to ~0.5 MB) are made the first time they are read (``study_extras``), so a caller that
    never reads them — the worker: the API makes them on demand, ``services.api.study_extras``
    — never pays for them."""

    spec: JobSpec
    status: str
    best: Solution
    pareto: list[dict[str, Any]]
    baselines: dict[str, Solution]
    history: list[dict[str, Any]]
    #: Makes the study's extras (``StudyProblem.extras`` of the final front), called at most
    #: once, by :attr:`extras`.
    study_extras: Callable[[], dict[str, Any]] = dataclasses.field(repr=False, compare=False)
    optimizer: dict[str, Any]
    objective_names: tuple[str, ...]
    start: dict[str, Any] | None = None
    task: Task | None = None
    gap: dict[str, Any] | None = None
    #: Position of the reported optimum on ``pareto`` (None when it is not on the front: a
    #: refined optimum, or an older result).
    best_index: int | None = None

    @functools.cached_property
    def extras(self) -> dict[str, Any]:
        """The study's extras of the final front (made on first use)."""
        return self.study_extras()

    @property
    def feasible(self) -> bool:
        """True when the optimum violates no constraint (``best.violations`` is empty)."""
        return not self.best.violations

    def to_dict(self, *, extras: bool = True) -> dict[str, Any]:
        """``result.json``: spec, status, feasible and the optimum's violations, the task (the
        robot-relative parameters and their rules), best, pareto, baselines, history, extras
        (left out with ``extras`` False: the worker's result, whose extras the API makes on
        demand), optimizer, start (what the optimiser earned: `legcore.earned`), gap (to the
        best the problem allows: `legcore.optimality_gap`), best_index (the optimum's place on
        the front, or None)."""
        doc = _jsonable(
            {
                "spec": self.spec.model_dump(mode="json"),
                "status": self.status,
                "feasible": self.feasible,
                "violations": [v.as_dict() for v in self.best.violations or ()],
                "task": None if self.task is None else self.task.as_dict(),
                "objective_names": list(self.objective_names),
                "best": self.best.summary(),
                "pareto": self.pareto,
                "best_index": self.best_index,
                "baselines": {k: v.summary() for k, v in self.baselines.items()},
                "history": self.history,
                "optimizer": self.optimizer,
                "start": self.start,
                "gap": self.gap,
            }
        )
        if extras:
            doc["extras"] = _jsonable(self.extras)
        return doc


def finalize(prepared: Prepared, result: Result) -> RunResult:
    """Decode the optimum, the front and the baselines of a finished `Run` (with
    ``optimizer.refine``, the optimum is polished first: ``refine.refine_result``)."""
    problem = prepared.problem
    refined = None
    if prepared.spec.optimizer is not None and prepared.spec.optimizer.refine:
        from legcore.optimizers.refine import refine_result

        result, refined = refine_result(problem, result, prepared.spec.optimizer.refine_max_iter)
    best = checked(problem, problem.solution(np.asarray(result.x)))
    on_front = np.flatnonzero(
        np.all(np.asarray(result.front_X) == np.asarray(result.x)[None, :], axis=1)
    ) if len(result.front_X) else np.empty(0, dtype=int)
    pareto = [
        {"x": [float(v) for v in x], "objectives": [float(v) for v in f]}
        for x, f in zip(result.front_X, result.front_F, strict=True)
    ]
    return RunResult(
        spec=prepared.spec,
        status="succeeded",
        best=best,
        pareto=pareto,
        best_index=int(on_front[0]) if on_front.size else None,
        baselines={k: checked(problem, v) for k, v in problem.baseline_solutions().items()},
        history=[r.to_dict() for r in result.history],
        study_extras=functools.partial(
            problem.extras, np.asarray(result.front_X), np.asarray(result.front_F)
        ),
        optimizer={
            "kind": result.algorithm,
            "params": result.params,
            "n_gen": result.n_gen,
            "n_evals": result.n_evals,
            "elapsed_s": result.elapsed,
            "reason": result.reason,
            "feasible": result.feasible,
            **({"refine": refined} if refined is not None else {}),
        },
        objective_names=problem.objective_names,
        start=start_summary(problem, result),
        task=problem.task,
        gap=optimality_gap(tuple(problem.objective_names), best.objectives,
                           problem.reference_optimum() or refined_reference(
                               tuple(problem.objective_names), refined)),
    )


def checked(problem: StudyProblem, sol: Solution) -> Solution:
    """``sol`` with its violated constraints (``problem.violations`` of its ``x``; a solution
    without a decision vector is left unchecked)."""
    if sol.x is None or sol.violations is not None:
        return sol
    return dataclasses.replace(sol, violations=problem.violations(np.asarray(sol.x, dtype=float)))


def start_summary(problem: StudyProblem, result: Result) -> dict[str, Any]:
    """Where the search started (initial population's best, the encoding's free solution) and
    what the optimiser earned over each: `legcore.earned.earned_summary`."""
    initial = None
    if result.initial_f is not None and result.initial_cv is not None:
        initial = (np.asarray(result.initial_f), float(result.initial_cv))
    free = None
    got = problem.free_start()
    if got is not None:
        what, x_free = got
        F, G = problem.evaluate(np.asarray(x_free, dtype=float)[None, :])
        free = (what, F[0], float(constraint_violation(G)[0]))
    return earned_summary(
        tuple(problem.objective_names) or tuple(f"f{j + 1}" for j in range(problem.n_obj)),
        np.asarray(result.F), float(result.cv), initial, free,
    )


def run(
    spec: JobSpec | dict[str, Any],
    *,
    callback: Any = None,
) -> RunResult:
    """Run a job in-process. ``callback(progress: Progress) -> bool | None`` is called after each
    generation; returning True stops the run early (its result is still decoded)."""
    prepared = prepare(spec)
    r = prepared.new_run()
    while not r.done:
        progress: Progress = r.step()
        if callback is not None and callback(progress) is True:
            r.stop("stopped by the callback")
    return finalize(prepared, r.result())


def _jsonable(obj: Any) -> Any:
    """Strict-JSON-safe copy: numpy → python, NaN/inf → None, tuples → lists."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        if all(type(v) is float and v - v == 0.0 for v in obj):  # finite floats: as they are
            return list(obj)
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "biu" or (obj.dtype.kind == "f" and np.isfinite(obj).all()):
            return obj.tolist()
        return _jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return _jsonable(obj.item())
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    return obj
