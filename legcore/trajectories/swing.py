"""Swing (transfer-phase) curves of a foot in its sagittal plane (seed 000 baselines).

The foot moves from ``p0`` to ``p0 + step`` while lifting by ``height`` along
``up``; the plane spanned by step and up is the sagittal plane. With the path
parameter s = s(t) from any profile:

- parabolic: p(s) = p0 + step·s + up·h·4 s (1 − s)
- elliptic (half ellipse): p(s) = p0 + step·(1 − cos πs)/2 + up·h·sin πs

Both reach the full height h at s = 1/2 (mid-stride for a symmetric time law). The
elliptic curve leaves and touches the ground vertically; the parabolic one at an
angle atan(4h/|step|).

Seed 000's baseline (Calderón 2008): parabolic swing over 0.156 m with maximum
height 0.065 m in T = 3 s (``SEED000_STEP``, ``SEED000_HEIGHT``, ``SEED000_T``).
The seed does not state the time law; a rest-to-rest ``QuinticProfile`` is the
natural choice.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.trajectories.profiles import Profile
from legcore.trajectories.sampling import PathSample, compose_time_law, time_grid

__all__ = ["SEED000_HEIGHT", "SEED000_STEP", "SEED000_T", "SwingCurve"]

#: Seed 000 baseline step length (m), maximum foot height (m) and swing time (s).
SEED000_STEP = 0.156
SEED000_HEIGHT = 0.065
SEED000_T = 3.0


@dataclass(frozen=True, eq=False)
class SwingCurve:
    """Foot swing from ``p0`` (3,) m by ``step`` (3,) m, lifting ``height`` (m) along ``up``.

    ``shape`` is "parabolic" or "elliptic"; ``profile`` is the time law s(t), its T
    is the swing duration (s). ``up`` (3,) is normalised on construction.
    """

    p0: NDArray[np.float64]
    step: NDArray[np.float64]
    height: float
    profile: Profile
    shape: Literal["parabolic", "elliptic"] = "parabolic"
    up: NDArray[np.float64] = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))

    def __post_init__(self) -> None:
        for name in ("p0", "step", "up"):
            arr = np.array(getattr(self, name), dtype=float)
            if arr.shape != (3,) or not np.all(np.isfinite(arr)):
                raise ValueError(f"{name} must be 3 finite numbers, got {getattr(self, name)!r}")
            if name == "up":
                norm = float(np.linalg.norm(arr))
                if norm == 0.0:
                    raise ValueError("up must be a non-zero vector")
                arr = arr / norm
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        height = float(self.height)
        if not math.isfinite(height) or height < 0.0:
            raise ValueError(f"height must be a finite number >= 0 m, got {self.height!r}")
        object.__setattr__(self, "height", height)
        if self.shape not in ("parabolic", "elliptic"):
            raise ValueError(f"shape must be 'parabolic' or 'elliptic', got {self.shape!r}")
        if not isinstance(self.profile, Profile):
            raise ValueError(f"profile must be a Profile, got {type(self.profile).__name__}")

    @property
    def T(self) -> float:
        """Swing duration (s) = profile.T."""
        return self.profile.T

    def _shape_derivatives(self, s: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
        """Along-step fraction a(s) and lift fraction b(s) with 3 derivatives, each (4, K)."""
        if self.shape == "parabolic":
            a = np.stack([s, np.ones_like(s), np.zeros_like(s), np.zeros_like(s)])
            b = np.stack(
                [4.0 * s * (1.0 - s), 4.0 - 8.0 * s, np.full_like(s, -8.0), np.zeros_like(s)]
            )
        else:
            x = math.pi * s
            c, n = np.cos(x), np.sin(x)
            pi = math.pi
            a = np.stack([(1.0 - c) / 2.0, pi / 2.0 * n, pi**2 / 2.0 * c, -(pi**3) / 2.0 * n])
            b = np.stack([n, pi * c, -(pi**2) * n, -(pi**3) * c])
        return a, b

    def evaluate(self, t: ArrayLike) -> PathSample:
        """Foot position and analytic derivatives at times t (K,) in [0, T] (s)."""
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        if tt.ndim != 1:
            raise ValueError(f"t must be a 1-D array of times, got shape {tt.shape}")
        sdot = self.profile.derivatives(tt)  # validates t in [0, T]
        a, b = self._shape_derivatives(sdot[0])
        g = a[..., None] * self.step + (self.height * b)[..., None] * self.up  # (4, K, 3)
        g[0] += self.p0
        out = compose_time_law(g, sdot)
        return PathSample(t=np.clip(tt, 0.0, self.T), p=out[0], pd=out[1], pdd=out[2], pddd=out[3])

    def sample(self, dt: float) -> PathSample:
        """Samples on the uniform grid ``time_grid(T, dt)`` (the end only if T/dt is whole)."""
        return self.evaluate(time_grid(self.T, dt))
