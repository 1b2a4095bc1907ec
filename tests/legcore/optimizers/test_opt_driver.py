"""The ask/tell protocol, minimize/Run, terminations, reproducibility and exact checkpoints."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pytest

from legcore.optimizers import (
    ALGORITHMS,
    AllOf,
    MaxEvaluations,
    MaxGenerations,
    MaxTime,
    Progress,
    Result,
    Run,
    Tolerance,
    algorithm_params,
    from_jsonable,
    get_algorithm,
    minimize,
    termination_from_budget,
    to_jsonable,
)
from legcore.problems import Problem
from legcore.problems.benchmarks import ZDT1, Rastrigin, Sphere


class ConstrainedSphere(Problem):
    """Sphere with the constraint x0 >= 0.5 (exercises G in every algorithm state)."""

    def __init__(self, n_obj: int = 1) -> None:
        super().__init__(4, n_obj, 1, xl=-2.0, xu=2.0, resolution=0.01)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        f = np.sum(X ** 2, axis=1)
        F = f[:, None] if self.n_obj == 1 else np.column_stack([f, np.sum((X - 1) ** 2, axis=1)])
        return F, 0.5 - X[:, :1]


CASES: list[tuple[str, dict[str, Any], Any]] = [
    ("ga", {"pop_size": 30}, lambda: Rastrigin(5, resolution=0.01)),
    ("ga", {"pop_size": 20, "fitness": "window", "penalty": None}, ConstrainedSphere),
    ("hka", {"n_samples": 30, "n_best": 5}, lambda: Rastrigin(5)),
    ("hka", {"init": "survey", "survey_size": 200}, ConstrainedSphere),
    ("moead", {"n_subproblems": 30, "n_neighbors": 6}, lambda: ZDT1(8)),
    ("moead", {"n_subproblems": 20, "n_neighbors": 5, "archive_size": 0},
     lambda: ConstrainedSphere(2)),
    ("nsga2", {"pop_size": 24}, lambda: ZDT1(8)),
    ("nsga2", {"pop_size": 20}, lambda: ConstrainedSphere(2)),
]
IDS = [f"{kind}-{i}" for i, (kind, _, _) in enumerate(CASES)]


def _same_result(a: Result, b: Result) -> None:
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.F, b.F)
    np.testing.assert_array_equal(a.front_X, b.front_X)
    np.testing.assert_array_equal(a.front_F, b.front_F)
    assert a.n_gen == b.n_gen and a.n_evals == b.n_evals and a.cv == b.cv
    assert [r.best_f for r in a.history] == [r.best_f for r in b.history]
    assert [r.n_evals for r in a.history] == [r.n_evals for r in b.history]


@pytest.mark.slow
@pytest.mark.parametrize(("kind", "params", "make"), CASES, ids=IDS)
def test_checkpoint_resume_is_bit_identical(kind: str, params: dict, make: Any) -> None:
    problem = make()
    term = MaxGenerations(12)
    full = minimize(problem, get_algorithm(kind, **params), term, seed=7)

    saved: list[dict[str, Any]] = []
    run = Run(problem, get_algorithm(kind, **params), term, seed=7)
    for _ in range(5):
        run.step()
    saved.append(json.loads(json.dumps(to_jsonable(run.state_dict()), allow_nan=False)))
    del run  # the worker died

    resumed = minimize(make(), get_algorithm(kind, **params), term, seed=7, state=saved[0])
    _same_result(full, resumed)
    assert resumed.history[4].generation == 5 and len(resumed.history) == 12


@pytest.mark.parametrize(("kind", "params", "make"), CASES[::2], ids=IDS[::2])
def test_checkpoint_between_ask_and_tell(kind: str, params: dict, make: Any) -> None:
    problem = make()
    a = get_algorithm(kind, **params).setup(problem, seed=3)
    b = get_algorithm(kind, **params).setup(problem, seed=3)
    for step in range(8):
        X = a.ask()
        if step == 4:  # checkpoint with a pending batch, restore in a fresh object
            state = json.loads(json.dumps(to_jsonable(a.state_dict())))
            a = get_algorithm(kind, **params).setup(problem, seed=999)
            a.load_state_dict(state)
            np.testing.assert_array_equal(a.ask(), X)
        Y = b.ask()
        np.testing.assert_array_equal(X, Y)
        a.tell(X, *problem.evaluate(X))
        b.tell(Y, *problem.evaluate(Y))
    np.testing.assert_array_equal(a.best()[0], b.best()[0])


@pytest.mark.parametrize(("kind", "params", "make"), CASES[::2], ids=IDS[::2])
def test_same_seed_same_result_other_seed_other_result(kind: str, params: dict,
                                                       make: Any) -> None:
    r1 = minimize(make(), get_algorithm(kind, **params), MaxGenerations(6), seed=11)
    r2 = minimize(make(), get_algorithm(kind, **params), MaxGenerations(6), seed=11)
    r3 = minimize(make(), get_algorithm(kind, **params), MaxGenerations(6), seed=12)
    _same_result(r1, r2)
    assert not np.array_equal(r1.front_X, r3.front_X) or not np.array_equal(r1.x, r3.x)


def test_state_is_plain_data_and_round_trips() -> None:
    algo = get_algorithm("moead", n_subproblems=20, n_neighbors=4).setup(ZDT1(5), seed=1)
    X = algo.ask()
    algo.tell(X, *ZDT1(5).evaluate(X))
    state = algo.state_dict()
    assert state["kind"] == "moead" and state["generation"] == 1 and state["n_evals"] == 20
    assert state["rng"]["bit_generator"] == "PCG64"
    assert isinstance(state["data"]["X"], np.ndarray)
    text = json.dumps(to_jsonable(state), allow_nan=False)  # strict JSON
    back = from_jsonable(json.loads(text))
    np.testing.assert_array_equal(back["data"]["F"], state["data"]["F"])
    assert back["data"]["F"].dtype == np.float64
    # non-finite floats survive too (e.g. HKA's initial spread)
    assert from_jsonable(json.loads(json.dumps(to_jsonable({"a": float("inf")}))))["a"] == np.inf


def test_restore_refuses_other_kind_params_or_problem() -> None:
    problem = Sphere(3)
    algo = get_algorithm("ga", pop_size=10).setup(problem, seed=0)
    X = algo.ask()
    algo.tell(X, *problem.evaluate(X))
    state = algo.state_dict()
    with pytest.raises(ValueError, match="belongs to 'ga'"):
        get_algorithm("hka").setup(problem).load_state_dict(state)
    with pytest.raises(ValueError, match="pop_size"):
        get_algorithm("ga", pop_size=12).setup(problem).load_state_dict(state)
    with pytest.raises(ValueError, match="n_var"):
        get_algorithm("ga", pop_size=10).setup(Sphere(4)).load_state_dict(state)
    with pytest.raises(ValueError, match="seed"):
        Run(problem, get_algorithm("ga", pop_size=10), seed=1,
            state={**Run(problem, get_algorithm("ga", pop_size=10), seed=0).state_dict()})


def test_ask_tell_protocol_errors() -> None:
    problem = Sphere(3)
    algo = get_algorithm("ga", pop_size=10)
    with pytest.raises(RuntimeError, match="setup"):
        algo.ask()
    algo.setup(problem, seed=0)
    with pytest.raises(RuntimeError, match="ask"):
        algo.tell(np.zeros((10, 3)), np.zeros((10, 1)))
    X = algo.ask()
    np.testing.assert_array_equal(algo.ask(), X)  # idempotent until told
    with pytest.raises(ValueError, match="X: must be the batch"):
        algo.tell(X + 1, *problem.evaluate(X + 1))
    with pytest.raises(ValueError, match="F:"):
        algo.tell(X, np.zeros((10, 2)))
    algo.tell(X, *problem.evaluate(X))
    assert algo.generation == 1 and algo.n_evals == 10


def test_minimize_result_history_callback_and_checkpoints() -> None:
    seen: list[Progress] = []
    states: list[dict[str, Any]] = []
    r = minimize(Sphere(4), get_algorithm("ga", pop_size=20), MaxGenerations(10), seed=0,
                 callback=seen.append, checkpoint=states.append, checkpoint_every=4)
    assert [p.generation for p in seen] == list(range(1, 11))
    assert [p.n_evals for p in seen] == [20 + 18 * k for k in range(10)]  # 2 elites kept
    assert [s["algorithm"]["generation"] for s in states] == [4, 8, 10]
    assert len(r.history) == 10 and r.n_gen == 10 and r.reason == "reached 10 generations"
    assert r.algorithm == "ga" and r.seed == 0 and r.params["pop_size"] == 20
    best = [rec.best_f[0] for rec in r.history]
    assert all(b2 <= b1 for b1, b2 in zip(best, best[1:], strict=False))
    assert r.F[0] == best[-1] and r.front_F.shape == (1, 1) and r.feasible
    with pytest.raises(ValueError):
        r.x[0] = 1.0  # frozen


def test_callback_can_stop_the_run() -> None:
    r = minimize(Sphere(4), get_algorithm("ga", pop_size=20), MaxGenerations(50), seed=0,
                 callback=lambda p: p.generation >= 3)
    assert r.n_gen == 3 and "callback" in r.reason


def test_multi_objective_progress_reports_front_and_knee() -> None:
    seen: list[Progress] = []
    r = minimize(ZDT1(6), get_algorithm("nsga2", pop_size=20), MaxGenerations(5), seed=0,
                 callback=seen.append)
    p = seen[-1]
    assert p.front_F.shape[1] == 2 and p.front_X.shape == (len(p.front_F), 6)
    assert any(np.array_equal(p.best_f, f) for f in p.front_F)  # the knee is on the front
    rec = r.history[-1]
    assert rec.front_size == len(r.front_F)
    np.testing.assert_allclose(rec.ideal, r.front_F.min(axis=0))


def test_terminations() -> None:
    r = minimize(Sphere(3), get_algorithm("ga", pop_size=10), MaxEvaluations(50), seed=0)
    assert r.n_evals == 50 and "50 evaluations" in r.reason  # 10 + 8 * 5
    r = minimize(Sphere(3), get_algorithm("hka", spread_tol=0.0),
                 Tolerance(ftol=1e-9, window=5) | MaxGenerations(500), seed=0)
    assert "changed by at most" in r.reason and r.n_gen < 500
    last = [rec.best_f[0] for rec in r.history[-6:]]
    assert max(last) - min(last) <= 1e-9 * 5
    r = minimize(Sphere(3), get_algorithm("ga", pop_size=10), MaxTime(1e-9), seed=0)
    assert r.n_gen == 1 and "time" in r.reason
    both = AllOf(MaxGenerations(3), MaxEvaluations(10))
    r = minimize(Sphere(3), get_algorithm("ga", pop_size=10), both, seed=0)
    assert r.n_gen == 3
    t = termination_from_budget(n_gen=5, seconds=60.0)
    assert "MaxGenerations(5)" in repr(t)
    with pytest.raises(ValueError, match="budget"):
        termination_from_budget()
    with pytest.raises(ValueError, match="n_gen"):
        MaxGenerations(0)


def test_resuming_a_finished_run_returns_its_result() -> None:
    run = Run(Sphere(3), get_algorithm("ga", pop_size=10), MaxGenerations(3), seed=0)
    while not run.done:
        run.step()
    state = to_jsonable(run.state_dict())
    r = minimize(Sphere(3), get_algorithm("ga", pop_size=10), MaxGenerations(3), state=state)
    np.testing.assert_array_equal(r.x, run.result().x)
    assert r.seed == 0 and r.n_gen == 3


def test_registry() -> None:
    assert set(ALGORITHMS) == {"ga", "hka", "moead", "nsga2"}
    assert algorithm_params("moead")["n_subproblems"] == 300
    assert algorithm_params("moead")["n_neighbors"] == 20
    with pytest.raises(ValueError, match="kind: unknown algorithm 'pso'"):
        get_algorithm("pso")
    with pytest.raises(ValueError, match="popsize: unknown parameter"):
        get_algorithm("ga", popsize=10)
    with pytest.raises(ValueError, match="seed"):
        minimize(Sphere(2), get_algorithm("ga"), seed=-1)
    with pytest.raises(ValueError, match="checkpoint_every"):
        minimize(Sphere(2), get_algorithm("ga"), checkpoint_every=0)
