"""Block-wise, vectorisable sine and cosine for the numba kernels (forward kinematics, RNEA,
chain points): :func:`_sincos` fills the cosines and sines of a slice of joint angles."""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

# sin/cos of the joint angles, block-wise and vectorisable (libm's scalar sin+cos took ~70 % of
# the kernel): Cody–Waite reduction by π/2 in three parts (fdlibm constants; exact k·P1 for
# |k| < 2^20) and fdlibm's minimax kernels on [-π/4, π/4]; agrees with libm to ~1e-16 absolute.
# Angles beyond |q| > 1e5 rad (and non-finite ones) fall back to math.sin/math.cos.
_TWO_OVER_PI = 6.36619772367581382433e-01
_PIO2_1 = 1.57079632673412561417e00
_PIO2_2 = 6.07710050630396597660e-11
_PIO2_3 = 2.02226624871116645580e-21
_S1 = -1.66666666666666324348e-01
_S2 = 8.33333333332248946124e-03
_S3 = -1.98412698298579493134e-04
_S4 = 2.75573137070700676789e-06
_S5 = -2.50507602534068634195e-08
_S6 = 1.58969099521155010221e-10
_C1 = 4.16666666666666019037e-02
_C2 = -1.38888888888741095749e-03
_C3 = 2.48015872894767294178e-05
_C4 = -2.75573143513906633035e-07
_C5 = 2.08757232129817482790e-09
_C6 = -1.13596475577881948265e-11
_TRIG_BIG = 1.0e5
_BLOCK = 64  # samples per trig block


@numba.njit(cache=True, nogil=True)
def _sincos(x: FloatArray, lo: int, hi: int, c: FloatArray, s: FloatArray) -> None:
    """``c[j-lo], s[j-lo] = cos(x[j]), sin(x[j])`` for j in lo..hi-1 (x 1-D)."""
    for j in range(lo, hi):
        xj = x[j]
        k = np.rint(xj * _TWO_OVER_PI)
        r = ((xj - k * _PIO2_1) - k * _PIO2_2) - k * _PIO2_3
        z = r * r
        sr = r + r * z * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
        hz = 0.5 * z
        w = 1.0 - hz
        cr = w + (
            ((1.0 - w) - hz)
            + z * z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
        )
        quad = np.int64(k) & 3
        odd = (quad & 1) == 1
        a = cr if odd else sr
        b = sr if odd else cr
        s[j - lo] = -a if (quad & 2) == 2 else a
        c[j - lo] = -b if ((quad + 1) & 2) == 2 else b
    for j in range(lo, hi):
        if not abs(x[j]) <= _TRIG_BIG:  # also catches NaN / inf
            c[j - lo] = math.cos(x[j])
            s[j - lo] = math.sin(x[j])
