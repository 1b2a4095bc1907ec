"""Sample containers, fixed-step time grids and the chain rule through a time law."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["JointSample", "PathSample", "compose_time_law", "time_grid"]


def time_grid(T: float, dt: float, t0: float = 0.0) -> NDArray[np.float64]:
    """Uniform times ``t0 + k dt`` for k = 0 .. floor(T/dt), shape (K,), in s.

    The step is exactly dt; the end ``t0 + T`` is included only when T is a multiple
    of dt (to 1e-9 relative). For samples that must hit both ends, evaluate at
    ``np.linspace(t0, t0 + T, K)`` instead.
    """
    T = float(T)
    dt = float(dt)
    if not math.isfinite(T) or T <= 0.0:
        raise ValueError(f"T must be a finite duration > 0 s, got {T!r}")
    if not math.isfinite(dt) or dt <= 0.0:
        raise ValueError(f"dt must be a finite step > 0 s, got {dt!r}")
    K = int(math.floor(T / dt * (1.0 + 1e-9))) + 1
    return t0 + dt * np.arange(K, dtype=np.float64)


def compose_time_law(g: NDArray[np.float64], sdot: NDArray[np.float64]) -> NDArray[np.float64]:
    """Time derivatives of x(t) = g(s(t)) by the chain rule.

    ``g``: (4, K, d) — g, g', g'', g''' with respect to s at s(t_k).
    ``sdot``: (4, K) — s, ṡ, s̈, s⃛ at t_k.
    Returns (4, K, d): x, ẋ = g' ṡ, ẍ = g'' ṡ² + g' s̈, x⃛ = g''' ṡ³ + 3 g'' ṡ s̈ + g' s⃛.
    """
    s1 = sdot[1][:, None]
    s2 = sdot[2][:, None]
    s3 = sdot[3][:, None]
    return np.stack(
        [
            g[0],
            g[1] * s1,
            g[2] * s1**2 + g[1] * s2,
            g[3] * s1**3 + 3.0 * g[2] * s1 * s2 + g[1] * s3,
        ]
    )


@dataclass(frozen=True, eq=False)
class PathSample:
    """A Cartesian trajectory sampled at times t.

    t (K,) s; p (K, 3) m; pd (K, 3) m/s; pdd (K, 3) m/s²; pddd (K, 3) m/s³ (jerk).
    """

    t: NDArray[np.float64]
    p: NDArray[np.float64]
    pd: NDArray[np.float64]
    pdd: NDArray[np.float64]
    pddd: NDArray[np.float64]

    @property
    def speed(self) -> NDArray[np.float64]:
        """Tool speed |ṗ| (m/s), shape (K,)."""
        return np.linalg.norm(self.pd, axis=-1)


@dataclass(frozen=True, eq=False)
class JointSample:
    """A batch of joint trajectories sampled at times t.

    t (K,) s; q (B, K, n) rad (or m for prismatic joints); qd (B, K, n) rad/s;
    qdd (B, K, n) rad/s²; qddd (B, K, n) rad/s³ (jerk).
    """

    t: NDArray[np.float64]
    q: NDArray[np.float64]
    qd: NDArray[np.float64]
    qdd: NDArray[np.float64]
    qddd: NDArray[np.float64]
