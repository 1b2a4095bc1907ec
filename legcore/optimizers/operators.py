"""Vectorised real-coded variation operators shared by MOEA/D and NSGA-II.

- ``sbx``: simulated binary crossover, bounded form (Deb & Agrawal 1995; as in Deb's NSGA-II
  code and pymoo's ``SBX``): per pair with probability ``prob``, per variable with probability
  ``prob_var``; children swapped per variable with probability 1/2.
- ``polynomial_mutation``: Deb's bounded polynomial mutation (pymoo's ``PM``): each row with
  probability ``prob`` (pymoo's NSGA-II: 0.9; default 1), then each of its variables with
  probability ``prob_var`` (default ``1 / n_var``).

All operators draw a fixed number of random numbers per call (independent of the data), which
keeps runs reproducible and checkpoints exact. The per-variable work is one compiled pass
(numba) over the drawn numbers; ``tests/legcore/optimizers/test_operators.py`` checks it
against the vectorised numpy formulation it replaced (equal to an ulp: libm's ``pow`` here,
numpy's SIMD ``power`` there).
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["sbx", "polynomial_mutation"]

_EPS = 1.0e-14


@numba.njit(cache=True, nogil=True)
def _betaq(beta: float, rand: float, eta: float) -> float:  # pragma: no cover - compiled
    alpha = 2.0 - beta ** -(eta + 1.0)
    if rand <= 1.0 / alpha:
        return (rand * alpha) ** (1.0 / (eta + 1.0))
    return (1.0 / (2.0 - rand * alpha)) ** (1.0 / (eta + 1.0))


@numba.njit(cache=True, nogil=True)
def _clip(v: float, lo: float, hi: float) -> float:  # pragma: no cover - compiled
    """``np.clip`` of one value (NaN stays NaN)."""
    if v < lo:
        return lo
    if v > hi:
        return hi
    return v


@numba.njit(cache=True, nogil=True)
def _sbx_kernel(
    P1: np.ndarray, P2: np.ndarray, xl: np.ndarray, xu: np.ndarray, r_pair: np.ndarray,
    r_var: np.ndarray, r_beta: np.ndarray, r_swap: np.ndarray, eta: float, prob: float,
    prob_var: float, C1: np.ndarray, C2: np.ndarray,
) -> None:  # pragma: no cover - compiled
    n, d = P1.shape
    for i in range(n):
        pair = r_pair[i] < prob
        for j in range(d):
            p1 = P1[i, j]
            p2 = P2[i, j]
            if not (pair and r_var[i, j] < prob_var and abs(p1 - p2) > _EPS and xu[j] > xl[j]):
                C1[i, j] = p1
                C2[i, j] = p2
                continue
            y1 = min(p1, p2)
            y2 = max(p1, p2)
            delta = y2 - y1
            beta1 = 1.0 + 2.0 * (y1 - xl[j]) / delta
            beta2 = 1.0 + 2.0 * (xu[j] - y2) / delta
            c1 = _clip(0.5 * ((y1 + y2) - _betaq(beta1, r_beta[i, j], eta) * delta), xl[j], xu[j])
            c2 = _clip(0.5 * ((y1 + y2) + _betaq(beta2, r_beta[i, j], eta) * delta), xl[j], xu[j])
            if r_swap[i, j] < 0.5:
                C1[i, j] = c2
                C2[i, j] = c1
            else:
                C1[i, j] = c1
                C2[i, j] = c2


def sbx(
    P1: np.ndarray,
    P2: np.ndarray,
    xl: np.ndarray,
    xu: np.ndarray,
    rng: np.random.Generator,
    *,
    eta: float = 15.0,
    prob: float = 0.9,
    prob_var: float = 0.5,
) -> tuple[np.ndarray, np.ndarray]:
    """Cross rows of ``P1`` with rows of ``P2``; returns two ``(n, n_var)`` children arrays."""
    n, d = int(P1.shape[0]), int(P1.shape[1])
    r_pair = rng.random(n)
    r_var = rng.random((n, d))
    r_beta = rng.random((n, d))
    r_swap = rng.random((n, d))
    P1 = np.ascontiguousarray(P1, dtype=float)
    P2 = np.ascontiguousarray(P2, dtype=float)
    C1 = np.empty((n, d))
    C2 = np.empty((n, d))
    _sbx_kernel(P1, P2, _row(xl, d), _row(xu, d), r_pair, r_var, r_beta, r_swap,
                float(eta), float(prob), float(prob_var), C1, C2)  # fmt: skip
    return C1, C2


@numba.njit(cache=True, nogil=True)
def _pm_kernel(
    X: np.ndarray, xl: np.ndarray, xu: np.ndarray, rows: np.ndarray, r_mut: np.ndarray,
    r: np.ndarray, eta: float, p: float, Y: np.ndarray,
) -> None:  # pragma: no cover - compiled
    n, d = X.shape
    pw = 1.0 / (eta + 1.0)
    for i in range(n):
        for j in range(d):
            x = X[i, j]
            span = xu[j] - xl[j]
            if not (rows[i] and r_mut[i, j] < p and span > 0):
                Y[i, j] = x
                continue
            ri = r[i, j]
            if ri <= 0.5:
                d1 = (x - xl[j]) / span
                v = 2.0 * ri + (1.0 - 2.0 * ri) * (1.0 - d1) ** (eta + 1.0)
                dq = v**pw - 1.0
            else:
                d2 = (xu[j] - x) / span
                v = 2.0 * (1.0 - ri) + 2.0 * (ri - 0.5) * (1.0 - d2) ** (eta + 1.0)
                dq = 1.0 - v**pw
            Y[i, j] = _clip(x + dq * span, xl[j], xu[j])


def polynomial_mutation(
    X: np.ndarray,
    xl: np.ndarray,
    xu: np.ndarray,
    rng: np.random.Generator,
    *,
    eta: float = 20.0,
    prob_var: float | None = None,
    prob: float = 1.0,
) -> np.ndarray:
    """Mutate each row with probability ``prob``, and in it each variable with probability
    ``prob_var`` (default ``1 / n_var``). ``prob < 1`` draws ``n`` more numbers (after the
    others); ``prob = 1`` draws none."""
    n, d = X.shape
    p = 1.0 / d if prob_var is None else prob_var
    r_mut = rng.random((n, d))
    r = rng.random((n, d))
    rows = np.asarray(rng.random(n) < prob) if prob < 1.0 else np.ones(n, dtype=np.bool_)
    Y = np.empty((n, d))
    _pm_kernel(np.ascontiguousarray(X, dtype=float), _row(xl, d), _row(xu, d), rows, r_mut, r,
               float(eta), float(p), Y)  # fmt: skip
    return Y


def _row(v: np.ndarray, d: int) -> np.ndarray:
    """Bounds as a contiguous float (d,) array (a scalar bound is broadcast)."""
    if isinstance(v, np.ndarray) and v.shape == (d,) and v.dtype == np.float64:
        return v if v.flags.c_contiguous else np.ascontiguousarray(v)
    return np.ascontiguousarray(np.broadcast_to(np.asarray(v, dtype=float), (d,)))
