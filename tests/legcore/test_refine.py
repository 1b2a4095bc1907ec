"""`legcore.optimizers.refine`: SLSQP refinement on the continuous relaxation, and
``optimizer.refine`` of a job."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from pydantic import ValidationError

from legcore.jobspec import parse_job_spec, spec_error_locations
from legcore.optimizers.refine import Relaxation, fd_gradients, refine, relaxation_of
from legcore.problems.base import Problem
from legcore.runner import prepare, run

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


class Disc(Problem):
    """min (x0 − 1)² + (x1 − 2)² s.t. x0 + x1 ≤ 2 on [−5, 5]²: optimum (0.5, 1.5), F = 0.5."""

    def __init__(self, n_obj: int = 1) -> None:
        super().__init__(2, n_obj, 1, xl=-5.0, xu=5.0)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        f = (X[:, 0] - 1.0) ** 2 + (X[:, 1] - 2.0) ** 2
        F = np.stack([f] * self.n_obj, axis=1)
        return F, (X[:, 0] + X[:, 1] - 2.0)[:, None]


def _example(name: str, **budget: int) -> dict:
    spec = yaml.safe_load((EXAMPLES / name).read_text())
    spec["record"] = False
    if budget:
        spec["budget"] = budget
    return spec


def test_refine_reaches_the_known_optimum() -> None:
    r = refine(Disc(), np.array([-4.0, 4.0]))  # infeasible start
    assert r.cv == 0.0 and r.improved and not r.skipped
    np.testing.assert_allclose(r.x, [0.5, 1.5], atol=1e-5)
    assert r.f == pytest.approx(0.5, abs=1e-8)
    assert r.before > r.after == r.f


def test_refine_never_returns_a_worse_point() -> None:
    problem = Disc()
    start = np.array([0.5, 1.5])  # already optimal
    r = refine(problem, start)
    assert r.f <= r.before and r.cv == 0.0
    # a relaxation whose way back lands on an infeasible point: the start is kept
    base = relaxation_of(problem)
    bad = Relaxation(base.xl, base.xu, base.evaluate, base.lift, lambda z: np.array([5.0, 5.0]))
    r = refine(problem, np.array([0.0, 0.0]), relax=bad)
    assert not r.improved and r.f == r.before == 5.0 and r.cv == 0.0
    np.testing.assert_array_equal(r.x, [0.0, 0.0])


class Staircase(Problem):
    """Integer-coded (0.1) and flat between grid points: min Σ (x_j − c_j)², grid optimum
    (0.3, −0.3, 0.7); finite differences see no slope, only the grid climb moves."""

    def __init__(self) -> None:
        super().__init__(3, 1, 0, xl=-3.0, xu=3.0, resolution=0.1)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, None]:
        Xg = np.rint(X / 0.1) * 0.1
        return ((Xg - [0.26, -0.33, 0.71]) ** 2).sum(axis=1)[:, None], None


def test_refine_climbs_the_grid_of_an_integer_problem() -> None:
    problem = Staircase()
    r = refine(problem, np.array([-2.0, 2.0, -2.0]), max_iter=200)
    np.testing.assert_allclose(r.x, [0.3, -0.3, 0.7], atol=1e-12)
    np.testing.assert_array_equal(problem.snap(r.x[None])[0], r.x)  # on the grid


def test_refine_skips_several_objectives() -> None:
    r = refine(Disc(n_obj=2), np.array([0.0, 0.0]))
    assert r.skipped and not r.improved and "objectives" in r.message


def test_fd_gradient_matches_the_analytic_one() -> None:
    def evaluate(U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        f = np.sin(3.0 * U[:, 0]) + U[:, 1] ** 3
        G = np.stack([U[:, 0] * U[:, 1], np.exp(U[:, 1])], axis=1)
        return f[:, None], G

    for u in (np.array([0.3, 0.7]), np.array([0.0, 1.0])):  # inside, and at both bounds
        f, g, df, dG = fd_gradients(evaluate, u, h=1e-6)
        assert f == pytest.approx(np.sin(3 * u[0]) + u[1] ** 3)
        np.testing.assert_allclose(g, [u[0] * u[1], np.exp(u[1])])
        np.testing.assert_allclose(df, [3 * np.cos(3 * u[0]), 3 * u[1] ** 2], atol=1e-5)
        np.testing.assert_allclose(dG, [[u[1], u[0]], [0.0, np.exp(u[1])]], atol=1e-5)


def test_swing_energy_continuous_decode_equals_the_integer_decode() -> None:
    problem = prepare(_example("000_swing_energy_obstacle.yaml")).problem
    rng = np.random.default_rng(3)
    X = problem.snap(rng.uniform(problem.xl, problem.xu, (20, problem.n_var)))
    X[0] = problem.coordinated_x()
    relax = relaxation_of(problem)
    Z = np.stack([relax.lift(x) for x in X])
    assert np.all(Z >= relax.xl) and np.all(Z <= relax.xu)
    F, G = problem.evaluate(X)
    Fz, Gz = relax.evaluate(Z)
    np.testing.assert_array_equal(Fz, F)
    np.testing.assert_array_equal(Gz, G)
    Xb = np.stack([relax.lower(z) for z in Z])  # back onto the grid: the same trajectories
    np.testing.assert_array_equal(problem.via_points(Xb), problem.via_points(X))
    # off the grid the decode is continuous (it moves with z)
    Fz2, _ = relax.evaluate(Z[:1] + 0.3 * problem.res * (relax.xu - Z[:1] > problem.res))
    assert Fz2[0, 0] != F[0, 0]


def test_job_with_refine_is_no_worse_and_records_it() -> None:
    spec = _example("000_swing_energy_flat.yaml", generations=3)
    prepared = prepare(spec)
    r = prepared.new_run()  # the same job without refine, not decoded
    while not r.done:
        r.step()
    plain = r.result()
    spec["optimizer"]["refine"] = True
    spec["optimizer"]["refine_max_iter"] = 20
    refined = run(spec)
    assert -refined.best.objectives["score"] <= plain.F[0]
    rec = refined.optimizer["refine"]
    assert {"before", "after", "n_evals", "elapsed_s", "success", "message"} <= set(rec)
    assert rec["before"] == pytest.approx(plain.F[0])
    assert rec["after"] == pytest.approx(-refined.best.objectives["score"])
    assert refined.best.metrics["on_grid"] == 1.0 and refined.best.metrics["feasible"] == 1.0
    assert refined.optimizer["feasible"] is True


def test_refine_spec_errors_name_the_field() -> None:
    spec = _example("000_swing_energy_flat.yaml")
    spec["optimizer"]["refine_max_iter"] = 0
    with pytest.raises(ValidationError) as exc:
        parse_job_spec(spec)
    locs = [".".join(map(str, loc)) for loc, _ in spec_error_locations(exc.value, spec)]
    assert locs == ["optimizer.refine_max_iter"]
    spec["optimizer"]["refine_max_iter"] = 5
    spec["optimizer"]["refine"] = "sometimes"
    with pytest.raises(ValidationError) as exc:
        parse_job_spec(spec)
    locs = [".".join(map(str, loc)) for loc, _ in spec_error_locations(exc.value, spec)]
    assert locs == ["optimizer.refine"]
