"""One step of the damped Newton IK of :mod:`legcore.ik.newton`, compiled with numba: the damped
step ``Δq = Aᵀ (A Aᵀ + λ² I)⁻¹ e`` by Cholesky with joints at a limit frozen (:func:`_step`), and
the undamped step from one LU factorisation of ``A`` itself (:func:`_lu_step`), each with the
optional pull toward the rest posture along the self-motion manifold."""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _factor(
    Af: FloatArray, lam: float, M: FloatArray, dinv: FloatArray
) -> None:  # pragma: no cover - compiled
    """Lower Cholesky factor of ``Af Afᵀ + λ² I`` (m×m) into ``M``, its inverse diagonal into
    ``dinv`` (the Gram matrix formed row by row as the factorisation needs it)."""
    m, n = Af.shape
    lam2 = lam * lam
    for i in range(m):
        for k in range(i + 1):
            s = 0.0
            for j in range(n):
                s += Af[i, j] * Af[k, j]
            for t in range(k):
                s -= M[i, t] * M[k, t]
            if i == k:
                d = math.sqrt(max(s + lam2, 1e-300))
                M[i, i] = d
                dinv[i] = 1.0 / d
            else:
                M[i, k] = s * dinv[k]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _chol_solve(
    M: FloatArray, dinv: FloatArray, b: FloatArray, x: FloatArray
) -> None:  # pragma: no cover - compiled
    """Solve ``M Mᵀ x = b`` with the factor of :func:`_factor`."""
    m = b.shape[0]
    for i in range(m):
        s = b[i]
        for k in range(i):
            s -= M[i, k] * x[k]
        x[i] = s * dinv[i]
    for i in range(m - 1, -1, -1):
        s = x[i]
        for k in range(i + 1, m):
            s -= M[k, i] * x[k]
        x[i] = s * dinv[i]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _step(
    q: FloatArray,
    A: FloatArray,
    e: FloatArray,
    lam: float,
    lo: FloatArray,
    hi: FloatArray,
    rest: FloatArray,
    gain: float,
    use_null: bool,
    dq: FloatArray,
    M: FloatArray,
    free: BoolArray,
    r: FloatArray,
    y: FloatArray,
    b: FloatArray,
    Af: FloatArray,
    dinv: FloatArray,
) -> float:  # pragma: no cover - compiled
    """Damped step into ``dq`` with limit freezing; returns max |null-space pull| (0 if unused).

    ``Af`` is ``A`` with the frozen joints' columns zeroed; on return ``M``/``dinv`` hold the
    factor of ``Af Afᵀ + λ² I`` (reused by :func:`track` when no joint was frozen).
    """
    m, n = A.shape
    for a in range(m):
        for j in range(n):
            Af[a, j] = A[a, j]
    for j in range(n):
        free[j] = True
    null_size = 0.0
    for _ in range(n + 1):
        _factor(Af, lam, M, dinv)
        _chol_solve(M, dinv, e, y)
        for j in range(n):
            s = 0.0
            for a in range(m):
                s += Af[a, j] * y[a]
            dq[j] = s
        null_size = 0.0
        if use_null:
            for j in range(n):
                r[j] = gain * (rest[j] - q[j]) if free[j] else 0.0
            for a in range(m):
                s = 0.0
                for j in range(n):
                    s += Af[a, j] * r[j]
                b[a] = s
            _chol_solve(M, dinv, b, y)
            for j in range(n):  # frozen joints: r = 0 and a zero column, so s = 0
                s = r[j]
                for a in range(m):
                    s -= Af[a, j] * y[a]
                dq[j] += s
                null_size = max(null_size, abs(s))
        changed = False
        for j in range(n):
            if free[j] and (
                (q[j] <= lo[j] and dq[j] < 0.0) or (q[j] >= hi[j] and dq[j] > 0.0)
            ):
                free[j] = False
                changed = True
                for a in range(m):
                    Af[a, j] = 0.0
        if not changed:
            break
    return null_size


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _lu_step(
    A: FloatArray,
    e: FloatArray,
    q: FloatArray,
    rest: FloatArray,
    gain: float,
    use_null: bool,
    dq: FloatArray,
    U: FloatArray,
    c: FloatArray,
    piv: NDArray[np.int64],
    x: FloatArray,
    z: FloatArray,
) -> float:  # pragma: no cover - compiled
    """The undamped step of :func:`_step` (no joint frozen) for n = m or n = m + 1 joints, from
    one LU factorisation of ``A`` itself (complete pivoting) instead of ``A Aᵀ``.

    n = m: ``dq = A⁻¹ e``. n = m + 1: the null space of ``A`` is the line of ``z`` (from the
    same factorisation), ``N = z zᵀ / |z|²``; ``dq = A⁺ e`` (a particular solution minus its
    component along ``z``) plus, with ``use_null``, ``g N (q_rest − q)``. Returns the max
    |null-space pull| (0 without ``use_null``), or −1 when ``A`` is (numerically) rank-deficient.
    ``U`` (m, n), ``c`` (m), ``piv`` (n) int, ``x`` (n), ``z`` (n) are scratch.
    """
    m, n = A.shape
    for a in range(m):
        c[a] = e[a]
        for j in range(n):
            U[a, j] = A[a, j]
    for j in range(n):
        piv[j] = j
    for k in range(m):
        big, bi, bj = -1.0, k, k
        for a in range(k, m):
            for j in range(k, n):
                t = abs(U[a, j])
                if t > big:
                    big, bi, bj = t, a, j
        if not (big > 1e-300 and math.isfinite(big)):
            return -1.0
        if bi != k:
            for j in range(k, n):
                U[k, j], U[bi, j] = U[bi, j], U[k, j]
            c[k], c[bi] = c[bi], c[k]
        if bj != k:
            for a in range(m):
                U[a, k], U[a, bj] = U[a, bj], U[a, k]
            piv[k], piv[bj] = piv[bj], piv[k]
        inv = 1.0 / U[k, k]
        for a in range(k + 1, m):
            f = U[a, k] * inv
            for j in range(k + 1, n):
                U[a, j] -= f * U[k, j]
            c[a] -= f * c[k]
    # in pivoted order: U1 x = c (x_m = 0), and z = [−U1⁻¹ u_m; 1] spans the null space
    for a in range(m - 1, -1, -1):
        s = c[a]
        t = U[a, m] if n > m else 0.0
        for j in range(a + 1, m):
            s -= U[a, j] * x[j]
            t -= U[a, j] * z[j]
        inv = 1.0 / U[a, a]
        x[a] = s * inv
        z[a] = t * inv
    if n == m:
        for j in range(n):
            dq[piv[j]] = x[j]
        return 0.0
    x[m] = 0.0
    z2 = 1.0
    zx = 0.0
    zr = 0.0
    zmax = 1.0
    for j in range(m):
        z[j] = -z[j]
        z2 += z[j] * z[j]
        zx += z[j] * x[j]
        zmax = max(zmax, abs(z[j]))
    z[m] = 1.0
    if use_null:
        for j in range(n):
            zr += z[j] * gain * (rest[piv[j]] - q[piv[j]])
    coef = (zr - zx) / z2  # remove the null part of x, add the projected rest pull
    for j in range(n):
        dq[piv[j]] = x[j] + coef * z[j]
    return abs(zr) / z2 * zmax
