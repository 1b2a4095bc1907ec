"""Vectorised real-coded variation operators shared by MOEA/D and NSGA-II.

- ``sbx``: simulated binary crossover, bounded form (Deb & Agrawal 1995; as in Deb's NSGA-II
  code and pymoo's ``SBX``): per pair with probability ``prob``, per variable with probability
  ``prob_var``; children swapped per variable with probability 1/2.
- ``polynomial_mutation``: Deb's bounded polynomial mutation (pymoo's ``PM``), each variable with
  probability ``prob_var`` (default ``1 / n_var``).

All operators draw a fixed number of random numbers per call (independent of the data), which
keeps runs reproducible and checkpoints exact.
"""

from __future__ import annotations

import numpy as np

__all__ = ["sbx", "polynomial_mutation"]

_EPS = 1.0e-14


def _betaq(beta: np.ndarray, rand: np.ndarray, eta: float) -> np.ndarray:
    alpha = 2.0 - np.power(beta, -(eta + 1.0))
    low = rand <= 1.0 / alpha
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        bq_low = np.power(rand * alpha, 1.0 / (eta + 1.0))
        bq_high = np.power(1.0 / (2.0 - rand * alpha), 1.0 / (eta + 1.0))
    return np.where(low, bq_low, bq_high)


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
    cross = (r_pair < prob)[:, None] & (r_var < prob_var)
    cross &= np.abs(P1 - P2) > _EPS
    cross &= (xu > xl)[None, :]

    y1, y2 = np.minimum(P1, P2), np.maximum(P1, P2)
    delta = np.where(cross, y2 - y1, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        beta1 = 1.0 + 2.0 * (y1 - xl) / delta
        beta2 = 1.0 + 2.0 * (xu - y2) / delta
    c1 = 0.5 * ((y1 + y2) - _betaq(beta1, r_beta, eta) * delta)
    c2 = 0.5 * ((y1 + y2) + _betaq(beta2, r_beta, eta) * delta)
    c1 = np.clip(c1, xl, xu)
    c2 = np.clip(c2, xl, xu)
    swap = r_swap < 0.5
    C1 = np.where(cross, np.where(swap, c2, c1), P1)
    C2 = np.where(cross, np.where(swap, c1, c2), P2)
    return C1, C2


def polynomial_mutation(
    X: np.ndarray,
    xl: np.ndarray,
    xu: np.ndarray,
    rng: np.random.Generator,
    *,
    eta: float = 20.0,
    prob_var: float | None = None,
) -> np.ndarray:
    """Mutate each variable with probability ``prob_var`` (default ``1 / n_var``)."""
    n, d = X.shape
    p = 1.0 / d if prob_var is None else prob_var
    r_mut = rng.random((n, d))
    r = rng.random((n, d))
    span = xu - xl
    mut = (r_mut < p) & (span > 0)[None, :]
    safe = np.where(span > 0, span, 1.0)
    d1 = (X - xl) / safe
    d2 = (xu - X) / safe
    pw = 1.0 / (eta + 1.0)
    with np.errstate(invalid="ignore"):
        v_low = 2.0 * r + (1.0 - 2.0 * r) * np.power(1.0 - d1, eta + 1.0)
        v_high = 2.0 * (1.0 - r) + 2.0 * (r - 0.5) * np.power(1.0 - d2, eta + 1.0)
        dq = np.where(r <= 0.5, np.power(v_low, pw) - 1.0, 1.0 - np.power(v_high, pw))
    Y = np.clip(X + dq * span, xl, xu)
    return np.where(mut, Y, X)
