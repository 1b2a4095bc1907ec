"""Analytic test problems, vectorised over the batch, for testing and benchmarking optimisers.

Single objective (any ``n_var``; optional integer coding through ``resolution``):
``Sphere``, ``Rosenbrock``, ``Rastrigin``. Multi-objective with known Pareto fronts: ``ZDT1``,
``ZDT2`` (2 objectives) and ``DTLZ2`` (any number of objectives). ``get_benchmark(name, **kw)``
builds one by name.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from legcore.problems.base import Problem

__all__ = [
    "Sphere",
    "Rosenbrock",
    "Rastrigin",
    "ZDT1",
    "ZDT2",
    "DTLZ2",
    "BENCHMARKS",
    "get_benchmark",
]


class _SingleObjective(Problem):
    """Unconstrained single-objective benchmark with a known optimum ``x_opt``."""

    default_bounds: tuple[float, float] = (-5.12, 5.12)

    def __init__(
        self,
        n_var: int = 10,
        *,
        xl: float | np.ndarray | None = None,
        xu: float | np.ndarray | None = None,
        resolution: float | np.ndarray | None = None,
    ) -> None:
        lo, hi = self.default_bounds
        super().__init__(n_var, 1, 0, xl=lo if xl is None else xl, xu=hi if xu is None else xu,
                         resolution=resolution)

    @property
    def x_opt(self) -> np.ndarray:
        """The global minimiser."""
        return np.zeros(self.n_var)

    @property
    def f_opt(self) -> float:
        """The global minimum."""
        return 0.0

    def baselines(self) -> dict[str, np.ndarray]:
        """The global optimum, under the name ``"optimum"``."""
        return {"optimum": self.x_opt}


class Sphere(_SingleObjective):
    """``f(x) = sum x_i^2`` on ``[-5.12, 5.12]^n``; minimum 0 at 0."""

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, None]:
        return np.sum(X * X, axis=1, keepdims=True), None


class Rosenbrock(_SingleObjective):
    """``f(x) = sum 100 (x_{i+1} - x_i^2)^2 + (1 - x_i)^2`` on ``[-2.048, 2.048]^n``; min 0 at 1."""

    default_bounds = (-2.048, 2.048)

    def __init__(self, n_var: int = 10, **kwargs: Any) -> None:
        if n_var < 2:
            raise ValueError(f"n_var: Rosenbrock needs at least 2 variables, got {n_var}")
        super().__init__(n_var, **kwargs)

    @property
    def x_opt(self) -> np.ndarray:
        return np.ones(self.n_var)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, None]:
        a, b = X[:, :-1], X[:, 1:]
        f = np.sum(100.0 * (b - a * a) ** 2 + (1.0 - a) ** 2, axis=1, keepdims=True)
        return f, None


class Rastrigin(_SingleObjective):
    """``f(x) = 10 n + sum (x_i^2 - 10 cos(2 pi x_i))`` on ``[-5.12, 5.12]^n``; min 0 at 0."""

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, None]:
        f = 10.0 * self.n_var + np.sum(X * X - 10.0 * np.cos(2.0 * np.pi * X), axis=1)
        return f[:, None], None


class _ZDT(Problem):
    """ZDT family on ``[0, 1]^n`` (Zitzler, Deb & Thiele 2000), 2 objectives."""

    def __init__(self, n_var: int = 30) -> None:
        if n_var < 2:
            raise ValueError(f"n_var: ZDT problems need at least 2 variables, got {n_var}")
        super().__init__(n_var, 2, 0, xl=0.0, xu=1.0)

    def _h(self, f1: np.ndarray, g: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, None]:
        f1 = X[:, 0]
        g = 1.0 + 9.0 / (self.n_var - 1) * np.sum(X[:, 1:], axis=1)
        f2 = g * self._h(f1, g)
        return np.column_stack([f1, f2]), None

    def pareto_front(self, n_points: int = 1000) -> np.ndarray:
        """``n_points`` points of the analytic Pareto front, ``(n_points, 2)``."""
        f1 = np.linspace(0.0, 1.0, n_points)
        return np.column_stack([f1, self._h(f1, np.ones_like(f1))])


class ZDT1(_ZDT):
    """ZDT1: convex front ``f2 = 1 - sqrt(f1)``."""

    def _h(self, f1: np.ndarray, g: np.ndarray) -> np.ndarray:
        return 1.0 - np.sqrt(f1 / g)


class ZDT2(_ZDT):
    """ZDT2: concave front ``f2 = 1 - f1^2``."""

    def _h(self, f1: np.ndarray, g: np.ndarray) -> np.ndarray:
        return 1.0 - (f1 / g) ** 2


class DTLZ2(Problem):
    """DTLZ2 (Deb et al. 2002) on ``[0, 1]^n``; front: the unit sphere in the positive orthant."""

    def __init__(self, n_var: int = 12, n_obj: int = 3) -> None:
        if n_obj < 2 or n_var < n_obj:
            raise ValueError(f"n_var/n_obj: DTLZ2 needs n_obj >= 2 and n_var >= n_obj, "
                             f"got n_var={n_var}, n_obj={n_obj}")
        super().__init__(n_var, n_obj, 0, xl=0.0, xu=1.0)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, None]:
        m = self.n_obj
        g = np.sum((X[:, m - 1:] - 0.5) ** 2, axis=1)
        theta = X[:, : m - 1] * (np.pi / 2.0)
        cos, sin = np.cos(theta), np.sin(theta)
        F = np.empty((X.shape[0], m))
        # f_i = (1+g) * prod_{j < m-1-i} cos(theta_j) * (sin(theta_{m-1-i}) if i > 0)
        cum = np.ones(X.shape[0])
        prods = [cum]
        for j in range(m - 1):
            cum = cum * cos[:, j]
            prods.append(cum)
        for i in range(m):
            f = prods[m - 1 - i].copy()
            if i > 0:
                f *= sin[:, m - 1 - i]
            F[:, i] = (1.0 + g) * f
        return F, None

    def pareto_front(self, n_points: int = 1000) -> np.ndarray:
        """About ``n_points`` points of the analytic front (normalised simplex lattice)."""
        from legcore.optimizers.moead import simplex_lattice  # local: problems must not need it

        W = simplex_lattice(self.n_obj, n_points)
        return W / np.linalg.norm(W, axis=1, keepdims=True)


BENCHMARKS: dict[str, type[Problem]] = {
    "sphere": Sphere,
    "rosenbrock": Rosenbrock,
    "rastrigin": Rastrigin,
    "zdt1": ZDT1,
    "zdt2": ZDT2,
    "dtlz2": DTLZ2,
}


def get_benchmark(name: str, **kwargs: Any) -> Problem:
    """Build a benchmark problem by name (``BENCHMARKS`` keys), forwarding ``kwargs``."""
    try:
        cls = BENCHMARKS[name.lower()]
    except KeyError:
        raise ValueError(f"name: unknown benchmark {name!r}; "
                         f"expected one of {sorted(BENCHMARKS)}") from None
    return cls(**kwargs)
