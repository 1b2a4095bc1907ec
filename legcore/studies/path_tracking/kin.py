"""Path geometry by arc length, joint motion through a time law, and exact arm5 joint rates.

:class:`ArcLengthPath` evaluates a composite planar path (lines and arcs of
:mod:`legcore.trajectories.paths`, placed in 3D by a ``Plane``) at arc lengths σ (m) of any
shape: position and its first three σ-derivatives, so that a time law σ(t) gives the tool
trajectory by the chain rule (``trajectories.sampling.compose_time_law``).

:func:`compose_ppoly` is the study's hot path: the joints' piecewise polynomial q(σ) composed with
a whole population's time laws σ(t) → q, q̇, q̈, q⃛ in one numba pass (one interval search and
one Horner pass with derivatives per sample instead of ``PPoly.__call__`` for 4 derivatives and
:func:`~legcore.trajectories.sampling.compose_time_law`; equal to them to ~1e-15 relative);
:func:`peak_abs` is ``max_k |a|`` over the time axis in one pass.

:func:`arm5_down_rates` differentiates seed 004's closed-form IK (``legcore.ik.arm5``) exactly:
given the joint angles on the path and the tool's velocity, acceleration and jerk, it returns
q̇, q̈, q⃛ — the exact reference that the generic joint path of the study (any arm,
:mod:`legcore.studies.path_tracking.joints`) is tested against on the seed's arm. With the
tool pointing straight down the wrist centre w is the tool point raised by d5, so ẇ = ṗ (the
tool only turns about the vertical). Writing the wrist in the base's cylindrical frame,
e_r = (c1, s1, 0), e_t = (−s1, c1, 0), R = a1 + X the signed radial distance of the wrist,
X = a2 c2 + a3 c23, Y = a2 s2 + a3 s23 = w_z − d1 (θ = q + offset)::

    Ẋ = ẇ·e_r                θ̇1 = ẇ·e_t / R
    Ẍ = ẅ·e_r + R θ̇1²        θ̈1 = (ẅ·e_t − 2 Ẋ θ̇1) / R
    X⃛ = w⃛·e_r + 3 Ẋ θ̇1² + 3 R θ̇1 θ̈1
    θ⃛1 = (w⃛·e_t − 3 Ẍ θ̇1 + R θ̇1³ − 3 Ẋ θ̈1) / R

and for the planar 2R (u = (X, Y), J2 its Jacobian, det J2 = a2 a3 sin θ3, e(θ) = (cos θ,
sin θ), e⊥ = (−sin θ, cos θ), θ23 = θ2 + θ3)::

    θ̇ = J2⁻¹ u̇
    θ̈ = J2⁻¹ (ü + a2 e2 θ̇2² + a3 e23 θ̇23²)
    θ⃛ = J2⁻¹ (u⃛ + 3 a2 e2 θ̇2 θ̈2 + 3 a3 e23 θ̇23 θ̈23 + a2 e2⊥ θ̇2³ + a3 e23⊥ θ̇23³)

θ4 = −θ2 − θ3 keeps the tool vertical; θ5 is constant (q5 = 0, the paper's setting) or follows
θ1 when the tool's heading is held fixed in the world.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PPoly

from legcore.ik.arm5 import Arm5Geometry
from legcore.trajectories.paths import Arc, Line, Plane

__all__ = ["ArcLengthPath", "arm5_down_rates", "compose_ppoly", "peak_abs"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class ArcLengthPath:
    """Consecutive planar ``curves`` (Line/Arc, plane coordinates m) placed by ``plane``."""

    curves: tuple[Line | Arc, ...]
    plane: Plane

    @property
    def lengths(self) -> FloatArray:
        """Segment lengths D_k (n,) m."""
        return np.array([c.length for c in self.curves])

    @property
    def length(self) -> float:
        """Total length L (m)."""
        return float(self.lengths.sum())

    @property
    def joins(self) -> FloatArray:
        """Start of every segment and the end of the last, (n + 1, 3) world points (m)."""
        w = [c.start for c in self.curves] + [self.curves[-1].end]
        return self.plane.to_world(np.array(w))

    def derivatives(self, sigma: FloatArray) -> FloatArray:
        """p, dp/dσ, d²p/dσ², d³p/dσ³ at arc lengths ``sigma`` (any shape S) → (4, *S, 3)."""
        sigma = np.asarray(sigma, dtype=float)
        flat = sigma.reshape(-1)
        D = self.lengths
        start = np.concatenate([[0.0], np.cumsum(D)[:-1]])
        seg = np.clip(np.searchsorted(start, flat, side="right") - 1, 0, len(self.curves) - 1)
        out = np.empty((4, flat.size, 3))
        scale = np.array([1.0, 1.0, 1.0, 1.0])
        for k, curve in enumerate(self.curves):
            mask = seg == k
            if not mask.any():
                continue
            s = np.clip((flat[mask] - start[k]) / D[k], 0.0, 1.0)
            g = curve.derivatives(s)  # (4, m, 2) w.r.t. s
            scale[:] = D[k] ** -np.arange(4.0)  # d/dσ = (1/D) d/ds
            g = g * scale[:, None, None]
            out[0, mask] = self.plane.to_world(g[0])
            out[1:, mask] = self.plane.to_world_vectors(g[1:])
        return out.reshape(4, *sigma.shape, 3)

    def polyline(self, points_per_segment: int = 100) -> FloatArray:
        """Dense points along the path, (n · points_per_segment + 1, 3) world m (for drawing)."""
        edges = np.concatenate([[0.0], np.cumsum(self.lengths)])
        sig = [np.linspace(a, b, points_per_segment, endpoint=False) for a, b in
               zip(edges[:-1], edges[1:], strict=True)]
        sig.append(np.array([edges[-1]]))
        return self.derivatives(np.concatenate(sig))[0]


def arm5_down_rates(
    geometry: Arm5Geometry,
    q: FloatArray,
    pd: FloatArray,
    pdd: FloatArray,
    pddd: FloatArray,
    heading_fixed: bool = False,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """q̇, q̈, q⃛ (…, 5) (rad/s, rad/s², rad/s³) of the arm following a tool-down trajectory.

    ``q`` (…, 5) rad: the IK solution on the path; ``pd``, ``pdd``, ``pddd`` (…, 3): the tool
    point's velocity (m/s), acceleration (m/s²) and jerk (m/s³) in the world. ``heading_fixed``:
    the tool keeps a fixed heading in the world (joint 5 turns with the base); otherwise
    q5 is constant. Where the wrist is on the base axis (R = 0) or the elbow is straight
    (sin θ3 = 0) the result is inf/NaN: the problem rejects such paths when it is built.
    """
    g = geometry
    th = np.asarray(q, dtype=float) + g.offset
    cb, sb = math.cos(g.base_yaw), math.sin(g.base_yaw)

    def to_base(v: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        v = np.asarray(v, dtype=float)
        return cb * v[..., 0] + sb * v[..., 1], -sb * v[..., 0] + cb * v[..., 1], v[..., 2]

    (vx, vy, vz), (ax, ay, az), (jx, jy, jz) = to_base(pd), to_base(pdd), to_base(pddd)
    c1, s1 = np.cos(th[..., 0]), np.sin(th[..., 0])
    th2, th23 = th[..., 1], th[..., 1] + th[..., 2]
    c2, s2, c23, s23 = np.cos(th2), np.sin(th2), np.cos(th23), np.sin(th23)
    X = g.a2 * c2 + g.a3 * c23
    R = g.a1 + X
    # base yaw (polar coordinates of the wrist)
    v_r, v_t = c1 * vx + s1 * vy, -s1 * vx + c1 * vy
    a_r, a_t = c1 * ax + s1 * ay, -s1 * ax + c1 * ay
    j_r, j_t = c1 * jx + s1 * jy, -s1 * jx + c1 * jy
    Xd = v_r
    w1 = v_t / R
    Xdd = a_r + R * w1**2
    a1 = (a_t - 2.0 * Xd * w1) / R
    Xddd = j_r + 3.0 * Xd * w1**2 + 3.0 * R * w1 * a1
    j1 = (j_t - 3.0 * Xdd * w1 + R * w1**3 - 3.0 * Xd * a1) / R
    # planar 2R: inverse of J2 = [[-a2 s2 - a3 s23, -a3 s23], [a2 c2 + a3 c23, a3 c23]]
    det = g.a2 * g.a3 * np.sin(th[..., 2])

    def solve(bx: FloatArray, by: FloatArray) -> tuple[FloatArray, FloatArray]:
        d2 = (g.a3 * c23 * bx + g.a3 * s23 * by) / det
        d3 = (-(g.a2 * c2 + g.a3 * c23) * bx - (g.a2 * s2 + g.a3 * s23) * by) / det
        return d2, d2 + d3  # θ2 and θ23 rates

    w2, w23 = solve(Xd, vz)
    a2_, a23 = solve(
        Xdd + g.a2 * c2 * w2**2 + g.a3 * c23 * w23**2,
        az + g.a2 * s2 * w2**2 + g.a3 * s23 * w23**2,
    )
    j2_, j23 = solve(
        Xddd + 3.0 * (g.a2 * c2 * w2 * a2_ + g.a3 * c23 * w23 * a23)
        - g.a2 * s2 * w2**3 - g.a3 * s23 * w23**3,
        jz + 3.0 * (g.a2 * s2 * w2 * a2_ + g.a3 * s23 * w23 * a23)
        + g.a2 * c2 * w2**3 + g.a3 * c23 * w23**3,
    )
    zero = np.zeros_like(w1)

    def stack(r1: FloatArray, r2: FloatArray, r23: FloatArray) -> FloatArray:
        r5 = r1 if heading_fixed else zero
        return np.stack([r1, r2, r23 - r2, -r23, r5], axis=-1)

    return stack(w1, w2, w23), stack(a1, a2_, a23), stack(j1, j2_, j23)



@numba.njit(cache=True, nogil=True)
def _compose_kernel(x: FloatArray, c: FloatArray, sig: FloatArray,
                    out: FloatArray) -> None:  # pragma: no cover - compiled
    """out (4, N, n): q, q̇, q̈, q⃛ of the PPoly (x, c) composed with sig (4, N)."""
    deg = c.shape[0] - 1
    m = c.shape[1]
    n = c.shape[2]
    N = sig.shape[1]
    i = 0
    for s in range(N):
        xv = sig[0, s]
        # interval: x[i] <= xv < x[i+1] (the last one closed; extrapolated outside), as scipy's
        if not x[i] <= xv < x[i + 1]:  # else: the previous sample's interval (σ rises)
            lo = 0
            hi = m + 1  # x[lo] <= xv < x[hi] with x[m + 1] = +inf
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if xv < x[mid]:
                    hi = mid
                else:
                    lo = mid
            i = min(lo, m - 1)  # below x[0]: 0; at or beyond x[m]: the last interval
        h = xv - x[i]
        s1 = sig[1, s]
        s2 = sig[2, s]
        s3 = sig[3, s]
        for j in range(n):
            # Horner for Q(h) and, differentiating each step, its first three derivatives
            g0 = c[0, i, j]
            g1 = 0.0
            g2 = 0.0
            g3 = 0.0
            for k in range(1, deg + 1):
                g3 = g3 * h + 3.0 * g2
                g2 = g2 * h + 2.0 * g1
                g1 = g1 * h + g0
                g0 = g0 * h + c[k, i, j]
            # chain rule (compose_time_law)
            out[0, s, j] = g0
            out[1, s, j] = g1 * s1
            out[2, s, j] = g2 * s1 * s1 + g1 * s2
            out[3, s, j] = g3 * s1 * s1 * s1 + 3.0 * g2 * s1 * s2 + g1 * s3


def compose_ppoly(poly: PPoly, sig: FloatArray) -> FloatArray:
    """q, q̇, q̈, q⃛ (4, N, n) of x(t) = poly(σ(t)) from ``sig`` (4, N) = σ, σ̇, σ̈, σ⃛.

    ``poly``: a PPoly (breaks in σ, values (n,)); at a break the interval after it is used and
    outside the breaks the end polynomials are extrapolated, as ``poly(σ, nu)`` does. Equals
    ``compose_time_law(np.stack([poly(σ, nu) for nu in range(4)]), sig)`` to rounding (~1e-15
    relative: Horner's scheme in place of scipy's power sums).
    """
    x = np.ascontiguousarray(poly.x, dtype=np.float64)
    c = np.ascontiguousarray(poly.c, dtype=np.float64)
    if poly.extrapolate is not True or x.size < 2 or np.any(np.diff(x) < 0.0):
        raise ValueError("poly: needs increasing breaks and extrapolate=True")
    if c.ndim != 3:
        raise ValueError(f"poly: expected vector values (coefficients (k, m, n)), got {c.shape}")
    sig = np.ascontiguousarray(sig, dtype=np.float64)
    if sig.ndim != 2 or sig.shape[0] != 4:
        raise ValueError(f"sig: expected shape (4, N), got {sig.shape}")
    out = np.empty((4, sig.shape[1], c.shape[2]))
    _compose_kernel(x, c, sig, out)
    return out


@numba.njit(cache=True, nogil=True)
def _peak_kernel(a: FloatArray, out: FloatArray) -> None:  # pragma: no cover - compiled
    B, K, n = a.shape
    for b in range(B):
        for j in range(n):
            out[b, j] = abs(a[b, 0, j])
        for k in range(1, K):
            for j in range(n):
                v = abs(a[b, k, j])
                if v > out[b, j] or v != v:  # NaN propagates, as in np.max
                    out[b, j] = v


def peak_abs(a: FloatArray) -> FloatArray:
    """``np.abs(a).max(axis=1)`` (B, n) of ``a`` (B, K ≥ 1, n) in one pass (no |a| temporary)."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    if a.ndim != 3 or a.shape[1] < 1:
        raise ValueError(f"a: expected shape (B, K >= 1, n), got {a.shape}")
    out = np.empty((a.shape[0], a.shape[2]))
    _peak_kernel(a, out)
    return out
