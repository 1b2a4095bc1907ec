"""Heuristic Kalman Algorithm (Toscano & Lyonnet 2009/2010) as used by seed 001.

A Gaussian generator ``N(m, diag(sigma^2))`` is moved towards the optimum by a Kalman estimator
that treats the mean of the best samples as a noisy measurement of the optimum. Per iteration
(= one generation):

1. draw ``N`` points ``q ~ N(m, diag sigma^2)``, clipped to the box (and rounded to the grid of an
   integer-coded problem), and evaluate them as one batch;
2. measurement: keep the ``N_xi`` lowest costs; ``xi`` = their mean, ``v`` = their variance
   (per variable, population variance);
3. Kalman update: ``L = sigma^2 / (sigma^2 + v)``, ``m+ = m + L (xi - m)``,
   ``p+ = (1 - L) sigma^2``;
4. slowed-down variance update: ``c = min(1, mean(sqrt(v)))``,
   ``a = alpha c^2 / (c^2 + max(p+))``, ``sigma <- sigma + a (sqrt(p+) - sigma)``, ``m <- m+``;
5. stop by itself when the spread of the ``N_xi`` best, ``max_j sqrt(v_j) / (xu_j - xl_j)``,
   falls below ``spread_tol`` (any `Termination` can stop it earlier).

Initialisation: ``init="center"`` is the original ``m0 = (xl + xu) / 2``,
``sigma0 = (xu - xl) / 6`` (seed 001 eq. 16). ``init="survey"`` is seed 001's modified
initialisation: the first generation evaluates a coarse grid of cell centres over the box (a
constant step per variable, ``k = floor(survey_size^(1/n))`` levels, at least 2; when ``2^n``
exceeds ``survey_size`` the grid cells are sampled at random); the ``survey_best`` best cells
define a new box (their bounding box grown by half a cell, within the bounds) from which
``m0``/``sigma0`` follow by eq. 16. Samples are still drawn in the original bounds.

Constraints: penalty as in seed 001 eq. 15, ``cost = f + penalty * sum(max(g_i, 0))``; with
``penalty=None`` Deb's parameterless feasibility rule is used instead (see `scalar_cost`).

Defaults: seed 001 does not publish ``N``, ``N_xi``, ``alpha`` ("found experimentally following
[17]"), nor its penalty weight; the defaults ``N = 100``, ``N_xi = 10``, ``alpha = 0.9`` were
chosen on the 10-variable sphere / Rosenbrock / Rastrigin benchmarks (docs/optimizers.md), and
``penalty = 1e3`` assumes objectives of order 1 (seed 001's cost is a weighted sum of ratios).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from legcore.optimizers.base import Algorithm
from legcore.optimizers.ga import scalar_cost
from legcore.optimizers.params import check_choice, check_float, check_int, check_optional_float

__all__ = ["HKA", "kalman_update"]


def kalman_update(
    m: np.ndarray, sigma: np.ndarray, best: np.ndarray, alpha: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One HKA update of the generator from the ``N_xi`` best samples ``best (N_xi, n)``.

    Returns ``(m_new, sigma_new, v)``: ``xi = mean(best)``, ``v = var(best)``,
    ``L = sigma^2 / (sigma^2 + v)``, ``m_new = m + L (xi - m)``, ``p = (1 - L) sigma^2``,
    ``c = min(1, mean(sqrt(v)))``, ``a = alpha c^2 / (c^2 + max(p))``,
    ``sigma_new = sigma + a (sqrt(p) - sigma)``. Where ``sigma^2 + v = 0`` the gain is 0.
    """
    xi = best.mean(axis=0)
    v = best.var(axis=0)
    s2 = sigma ** 2
    denom = s2 + v
    L = np.divide(s2, denom, out=np.zeros_like(s2), where=denom > 0)
    m_new = m + L * (xi - m)
    p = (1.0 - L) * s2
    c = min(1.0, float(np.mean(np.sqrt(v))))
    den = c * c + float(p.max())
    a = alpha * c * c / den if den > 0 else 0.0
    sigma_new = sigma + a * (np.sqrt(p) - sigma)
    return m_new, sigma_new, v


class HKA(Algorithm):
    """Heuristic Kalman Algorithm (single objective).

    Args:
        n_samples: ``N``, points drawn per iteration (>= 2). Default 100.
        n_best: ``N_xi``, best points forming the measurement (2 <= N_xi <= N). Default 10.
        alpha: slowdown coefficient in (0, 1]. Default 0.9.
        spread_tol: stop when the relative spread of the ``N_xi`` best is below this (>= 0;
            0 disables the rule). Default 1e-8.
        init: ``"center"`` (eq. 16) or ``"survey"`` (seed 001's coarse survey first).
        survey_size: maximum number of grid points of the survey. Default 1000.
        survey_best: best survey cells that define the initial box. Default 5.
        penalty: constraint penalty weight ``>= 0``, or ``None`` for Deb's rule. Default 1e3.
    """

    kind: ClassVar[str] = "hka"

    def __init__(
        self,
        n_samples: int = 100,
        n_best: int = 10,
        alpha: float = 0.9,
        spread_tol: float = 1e-8,
        init: str = "center",
        survey_size: int = 1000,
        survey_best: int = 5,
        penalty: float | None = 1e3,
    ) -> None:
        super().__init__()
        n_samples = check_int("n_samples", n_samples, 2)
        survey_size = check_int("survey_size", survey_size, 2)
        self._params = {
            "n_samples": n_samples,
            "n_best": check_int("n_best", n_best, 2, n_samples),
            "alpha": check_float("alpha", alpha, 0.0, 1.0, low_open=True),
            "spread_tol": check_float("spread_tol", spread_tol, 0.0),
            "init": check_choice("init", init, ("center", "survey")),
            "survey_size": survey_size,
            "survey_best": check_int("survey_best", survey_best, 1, survey_size),
            "penalty": check_optional_float("penalty", penalty, 0.0),
        }
        self._m = np.zeros(0)
        self._sigma = np.zeros(0)
        self._surveyed = True
        self._spread = float("inf")

    # ------------------------------------------------------------------ state accessors
    @property
    def mean(self) -> np.ndarray:
        """Current mean ``m`` of the Gaussian generator."""
        return self._m.copy()

    @property
    def sigma(self) -> np.ndarray:
        """Current standard deviations ``sigma`` of the generator."""
        return self._sigma.copy()

    @property
    def spread(self) -> float:
        """Relative spread of the last ``N_xi`` best (``inf`` before the first update)."""
        return self._spread

    # ------------------------------------------------------------------ survey
    def _survey_levels(self) -> int:
        n = self.problem.n_var
        k = int(np.floor(self._params["survey_size"] ** (1.0 / n) + 1e-9))
        return max(2, k)

    def _survey_points(self) -> np.ndarray:
        p = self.problem
        k = self._survey_levels()
        size = self._params["survey_size"]
        if k ** p.n_var <= size:
            cells = np.indices((k,) * p.n_var).reshape(p.n_var, -1).T
        else:
            cells = self._rng.integers(0, k, size=(size, p.n_var))
        X = p.xl + (cells + 0.5) * (p.xu - p.xl) / k
        return p.snap(X)

    def _init_from_survey(self, X: np.ndarray, cost: np.ndarray) -> None:
        p = self.problem
        k = self._survey_levels()
        best = X[np.argsort(cost, kind="stable")[: self._params["survey_best"]]]
        half = 0.5 * (p.xu - p.xl) / k
        lo = np.maximum(p.xl, best.min(axis=0) - half)
        hi = np.minimum(p.xu, best.max(axis=0) + half)
        self._m = 0.5 * (lo + hi)
        self._sigma = (hi - lo) / 6.0

    # ------------------------------------------------------------------ hooks
    def _setup(self) -> None:
        p = self.problem
        self._m = 0.5 * (p.xl + p.xu)
        self._sigma = (p.xu - p.xl) / 6.0
        self._surveyed = self._params["init"] != "survey"
        self._spread = float("inf")

    def _ask(self) -> np.ndarray:
        p = self.problem
        if not self._surveyed:
            return self._survey_points()
        Z = self._rng.standard_normal((self._params["n_samples"], p.n_var))
        return p.snap(self._m + self._sigma * Z)

    def _tell(self, X: np.ndarray, F: np.ndarray, cv: np.ndarray) -> None:
        cost = scalar_cost(F[:, 0], cv, self._params["penalty"])
        if not self._surveyed:
            self._init_from_survey(X, cost)
            self._surveyed = True
            return
        p = self.problem
        best = X[np.argsort(cost, kind="stable")[: self._params["n_best"]]]
        self._m, self._sigma, v = kalman_update(self._m, self._sigma, best,
                                                self._params["alpha"])
        width = p.xu - p.xl
        rel = np.sqrt(v)[width > 0] / width[width > 0]
        self._spread = float(rel.max()) if rel.size else 0.0
        tol = self._params["spread_tol"]
        if self._spread < tol or (tol > 0 and self._spread == 0.0):
            self._stop_reason = f"spread of the {self._params['n_best']} best below {tol:g}"

    def _get_state(self) -> dict[str, Any]:
        return {"m": self._m, "sigma": self._sigma, "surveyed": self._surveyed,
                "spread": self._spread}

    def _set_state(self, data: dict[str, Any]) -> None:
        self._m = np.asarray(data["m"], dtype=float).copy()
        self._sigma = np.asarray(data["sigma"], dtype=float).copy()
        self._surveyed = bool(data["surveyed"])
        self._spread = float(data["spread"])
