"""SBX and polynomial mutation: the compiled operators equal the vectorised numpy formulation
they replaced (kept here as the reference), for the same random draws, to the last bits —
numpy's ``power`` may use SIMD (SVML) code on AVX-512 machines, the compiled code calls libm's
correctly rounded ``pow``: they can differ by an ulp."""

from __future__ import annotations

import numpy as np
import pytest

from legcore.optimizers.operators import polynomial_mutation, sbx

_EPS = 1.0e-14


def _betaq(beta: np.ndarray, rand: np.ndarray, eta: float) -> np.ndarray:
    alpha = 2.0 - np.power(beta, -(eta + 1.0))
    low = rand <= 1.0 / alpha
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        bq_low = np.power(rand * alpha, 1.0 / (eta + 1.0))
        bq_high = np.power(1.0 / (2.0 - rand * alpha), 1.0 / (eta + 1.0))
    return np.where(low, bq_low, bq_high)


def sbx_reference(P1, P2, xl, xu, rng, *, eta=15.0, prob=0.9, prob_var=0.5):
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
    c1 = np.clip(0.5 * ((y1 + y2) - _betaq(beta1, r_beta, eta) * delta), xl, xu)
    c2 = np.clip(0.5 * ((y1 + y2) + _betaq(beta2, r_beta, eta) * delta), xl, xu)
    swap = r_swap < 0.5
    return (np.where(cross, np.where(swap, c2, c1), P1),
            np.where(cross, np.where(swap, c1, c2), P2))  # fmt: skip


def pm_reference(X, xl, xu, rng, *, eta=20.0, prob_var=None, prob=1.0):
    n, d = X.shape
    p = 1.0 / d if prob_var is None else prob_var
    r_mut = rng.random((n, d))
    r = rng.random((n, d))
    rows = rng.random(n) < prob if prob < 1.0 else np.ones(n, dtype=bool)
    span = xu - xl
    mut = (r_mut < p) & (span > 0)[None, :] & rows[:, None]
    safe = np.where(span > 0, span, 1.0)
    d1 = (X - xl) / safe
    d2 = (xu - X) / safe
    pw = 1.0 / (eta + 1.0)
    with np.errstate(invalid="ignore"):
        v_low = 2.0 * r + (1.0 - 2.0 * r) * np.power(1.0 - d1, eta + 1.0)
        v_high = 2.0 * (1.0 - r) + 2.0 * (r - 0.5) * np.power(1.0 - d2, eta + 1.0)
        dq = np.where(r <= 0.5, np.power(v_low, pw) - 1.0, 1.0 - np.power(v_high, pw))
    return np.where(mut, np.clip(X + dq * span, xl, xu), X)


@pytest.mark.parametrize("seed", range(5))
def test_compiled_operators_equal_the_numpy_formulation(seed: int) -> None:
    rng = np.random.default_rng(seed)
    d = 13
    xl = np.r_[-5.0 * np.ones(d - 1), 2.0]
    xu = np.r_[5.0 * np.ones(d - 1), 2.0]  # one fixed variable (xl == xu)
    P1 = rng.uniform(xl, xu, (40, d))
    P2 = rng.uniform(xl, xu, (40, d))
    P2[:5] = P1[:5]  # identical parents: nothing to cross
    P1[5:8, 0] = xl[0]  # on the bound
    for eta, prob, prob_var in ((15.0, 0.9, 0.5), (2.0, 1.0, 1.0), (40.0, 0.5, 0.2)):
        a, b = np.random.default_rng(seed + 100), np.random.default_rng(seed + 100)
        got = sbx(P1, P2, xl, xu, a, eta=eta, prob=prob, prob_var=prob_var)
        want = sbx_reference(P1, P2, xl, xu, b, eta=eta, prob=prob, prob_var=prob_var)
        np.testing.assert_allclose(got[0], want[0], rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(got[1], want[1], rtol=1e-14, atol=1e-15)
        np.testing.assert_array_equal(got[0] == P1, want[0] == P1)  # the same genes crossed
        assert a.random() == b.random()  # the same draws were taken
        for pv, pr in ((None, 1.0), (0.5, 0.9), (1.0, 0.3)):
            got_m = polynomial_mutation(P1, xl, xu, a, eta=eta, prob_var=pv, prob=pr)
            want_m = pm_reference(P1, xl, xu, b, eta=eta, prob_var=pv, prob=pr)
            np.testing.assert_allclose(got_m, want_m, rtol=1e-14, atol=1e-15)
            np.testing.assert_array_equal(got_m == P1, want_m == P1)  # the same genes mutated
            assert np.all((got_m >= xl) & (got_m <= xu))
