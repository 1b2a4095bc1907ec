"""Via-point joint splines: interpolation, clamped ends, continuity, batch independence."""

from __future__ import annotations

import numpy as np
import pytest

from legcore.trajectories import ViaPointSpline

# seed 000 setting: T = 3 s, K = 10 intermediate via points (+ start and end), 3 joints
T = 3.0
K_VIA = 12
N = 3
B = 6


@pytest.fixture(scope="module")
def via() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(7)
    t_via = np.linspace(0.0, T, K_VIA)
    q_via = rng.uniform(-1.0, 1.0, size=(B, K_VIA, N))
    return t_via, q_via


@pytest.mark.parametrize("kind", ["cubic", "quintic"])
def test_passes_through_via_points_with_rest_ends(via, kind):
    t_via, q_via = via
    sp = ViaPointSpline(t_via, q_via, kind)
    s = sp.evaluate(t_via)
    assert s.q.shape == (B, K_VIA, N)
    np.testing.assert_allclose(s.q, q_via, atol=1e-12)
    np.testing.assert_allclose(s.qd[:, [0, -1]], 0.0, atol=1e-10)
    if kind == "quintic":
        np.testing.assert_allclose(s.qdd[:, [0, -1]], 0.0, atol=1e-9)


@pytest.mark.parametrize(("kind", "order"), [("cubic", 2), ("quintic", 4)])
def test_continuity_at_interior_via_points(via, kind, order):
    # cubic spline is C², quintic C⁴: the highest continuous derivative matches both sides
    t_via, q_via = via
    sp = ViaPointSpline(t_via, q_via, kind)
    eps = 1e-7
    inner = t_via[1:-1]
    left, right = sp.evaluate(inner - eps), sp.evaluate(inner + eps)
    name = "qdd" if order == 2 else "qddd"
    scale = np.abs(getattr(left, name)).max()
    np.testing.assert_allclose(getattr(left, name), getattr(right, name), atol=1e-4 * scale)
    if kind == "cubic":  # the jerk of a cubic spline jumps at the knots
        assert np.abs(left.qddd - right.qddd).max() > 1e-2


def test_two_via_points_give_the_rest_to_rest_polynomials():
    q0 = np.array([[[0.1, -0.2]], [[0.5, 0.0]]])  # (B=2, 1, n=2)
    q1 = np.array([[[0.7, 0.3]], [[-0.5, 1.0]]])
    q_via = np.concatenate([q0, q1], axis=1)
    t = np.linspace(1.0, 3.0, 21)
    tau = ((t - 1.0) / 2.0)[None, :, None]
    cubic = ViaPointSpline(np.array([1.0, 3.0]), q_via, "cubic").evaluate(t)
    np.testing.assert_allclose(cubic.q, q0 + (q1 - q0) * (3 * tau**2 - 2 * tau**3), atol=1e-14)
    quintic = ViaPointSpline(np.array([1.0, 3.0]), q_via, "quintic").evaluate(t)
    expected = q0 + (q1 - q0) * (10 * tau**3 - 15 * tau**4 + 6 * tau**5)
    np.testing.assert_allclose(quintic.q, expected, atol=1e-13)
    # velocity of the quintic: 30 τ²(1 − τ)² Δq / T
    np.testing.assert_allclose(
        quintic.qd, (q1 - q0) * 30 * tau**2 * (1 - tau) ** 2 / 2.0, atol=1e-13
    )


@pytest.mark.parametrize("kind", ["cubic", "quintic"])
def test_derivatives_match_finite_differences(via, kind):
    t_via, q_via = via
    sp = ViaPointSpline(t_via, q_via, kind)
    h = 1e-5
    t = np.linspace(0.01, T - 0.01, 173)
    t = t[np.min(np.abs(t[:, None] - t_via[None, :]), axis=1) > 10 * h]
    s0, sp_, sm = sp.evaluate(t), sp.evaluate(t + h), sp.evaluate(t - h)
    for lo, hi in (("q", "qd"), ("qd", "qdd"), ("qdd", "qddd")):
        fd = (getattr(sp_, lo) - getattr(sm, lo)) / (2 * h)
        ref = getattr(s0, hi)
        np.testing.assert_allclose(fd, ref, atol=1e-5 * max(1.0, np.abs(ref).max()))


def test_batch_members_are_independent(via):
    t_via, q_via = via
    base = ViaPointSpline(t_via, q_via).sample(0.01)
    q2 = q_via.copy()
    q2[0] += 0.3 * np.sin(np.arange(K_VIA))[:, None]
    other = ViaPointSpline(t_via, q2).sample(0.01)
    np.testing.assert_array_equal(other.q[1:], base.q[1:])
    assert np.abs(other.q[0] - base.q[0]).max() > 0.1
    # member 3 alone gives the same trajectory as inside the batch
    alone = ViaPointSpline(t_via, q_via[3:4]).sample(0.01)
    np.testing.assert_allclose(alone.qdd[0], base.qdd[3], atol=1e-12)


def test_sample_shapes_and_offset_start():
    t_via = np.array([0.5, 1.5, 3.5])
    q_via = np.zeros((4, 3, 5))
    q_via[:, 1] = 1.0
    s = ViaPointSpline(t_via, q_via).sample(0.01)
    assert s.t.shape == (301,) and s.t[0] == 0.5 and s.t[-1] == pytest.approx(3.5)
    assert s.q.shape == s.qd.shape == s.qdd.shape == s.qddd.shape == (4, 301, 5)


def test_invalid_inputs_raise():
    t = np.linspace(0.0, 1.0, 4)
    with pytest.raises(ValueError, match="q_via must have shape"):
        ViaPointSpline(t, np.zeros((4, 3)))
    with pytest.raises(ValueError, match="strictly increasing"):
        ViaPointSpline(np.array([0.0, 1.0, 1.0, 2.0]), np.zeros((1, 4, 2)))
    with pytest.raises(ValueError, match="kind"):
        ViaPointSpline(t, np.zeros((1, 4, 2)), "linear")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="t must lie"):
        ViaPointSpline(t, np.zeros((1, 4, 2))).evaluate([1.5])
