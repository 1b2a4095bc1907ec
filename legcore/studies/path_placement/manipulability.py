"""w_M of ``path_placement``'s cost (eq 15): the largest manipulability of an arm over its joint
limits — seed 001's analytic form (eqs 6–8 on a 361² grid, then refined) for a PUMA-type arm,
Yoshikawa's measure sampled and refined for any other arm."""

from __future__ import annotations

import math
import weakref

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize as scipy_minimize

from legcore.ik.numeric import halton_seeds
from legcore.manipulability import manipulability, manipulability_split
from legcore.robots.model import Robot
from legcore.studies.path_placement.region import is_puma_type

__all__ = ["max_manipulability"]

FloatArray = NDArray[np.float64]

_SAMPLES = 4096

_WM_CACHE: weakref.WeakKeyDictionary[Robot, tuple[float, FloatArray]] = weakref.WeakKeyDictionary()


def _puma_max_manipulability(robot: Robot) -> tuple[float, FloatArray]:
    """Seed 001: the largest w = w_A |sin θ5| (eqs 6–8) — a 361 × 361 grid over (θ2, θ3)
    within their limits (w depends on neither θ1, θ4 nor θ6; θ5 = ±90° when inside its limits,
    else the limit nearest it), refined by L-BFGS-B."""
    lo, hi = robot.q_min, robot.q_max
    off = np.array([j.offset for j in robot.spec.joints])  # type: ignore[union-attr]
    cand5 = np.array([math.pi / 2, -math.pi / 2, lo[4] + off[4], hi[4] + off[4]]) - off[4]
    cand5 = cand5[(cand5 >= lo[4]) & (cand5 <= hi[4])]
    q5 = float(cand5[np.argmax(np.abs(np.sin(cand5 + off[4])))])
    g2, g3 = np.meshgrid(np.linspace(lo[1], hi[1], 361), np.linspace(lo[2], hi[2], 361),
                         indexing="ij")
    q = np.zeros(g2.shape + (6,))
    q[..., 1], q[..., 2], q[..., 4] = g2, g3, q5
    w = manipulability_split(robot, q)[0]
    i = np.unravel_index(int(np.argmax(w)), w.shape)
    q_best = q[i].copy()

    def neg_w(z: FloatArray) -> float:
        qq = q_best.copy()
        qq[1:3] = z
        return -float(manipulability_split(robot, qq)[0])

    res = scipy_minimize(neg_w, q_best[1:3], method="L-BFGS-B",
                         bounds=[(lo[1], hi[1]), (lo[2], hi[2])])
    if -res.fun > w[i]:
        q_best[1:3] = res.x
    return float(manipulability_split(robot, q_best)[0]), q_best


def _sampled_max_manipulability(robot: Robot) -> tuple[float, FloatArray]:
    """Yoshikawa's manipulability maximised over joints 2..n (joint 1 turns the whole arm
    and leaves it unchanged): 4096 Halton samples, the best 4 refined by L-BFGS-B."""
    lo, hi = robot.q_min, robot.q_max
    qs = halton_seeds(_SAMPLES, lo, hi, robot.home)
    qs[:, 0] = robot.home[0]
    w = manipulability(robot, qs)
    best_w, best_q = -1.0, qs[int(np.argmax(w))].copy()
    bounds = list(zip(lo[1:], hi[1:], strict=True))
    for k in np.argsort(w)[-4:]:
        q0 = qs[k].copy()

        def neg_w(z: FloatArray, q0: FloatArray = q0) -> float:
            qq = q0.copy()
            qq[1:] = z
            return -float(manipulability(robot, qq))

        res = scipy_minimize(neg_w, q0[1:], method="L-BFGS-B", bounds=bounds)
        if -res.fun > best_w:
            best_w = float(-res.fun)
            best_q = q0.copy()
            best_q[1:] = res.x
    return float(manipulability(robot, best_q)), best_q


def max_manipulability(robot: Robot) -> tuple[float, FloatArray]:
    """``(w_M, q)``: the largest manipulability (m³ for a 6R arm) over the joint limits and
    where — seed 001's analytic form on a grid for a PUMA-type arm, Yoshikawa's measure
    sampled and refined for any other arm. Computed once per robot."""
    cached = _WM_CACHE.get(robot)
    if cached is None:
        cached = (_puma_max_manipulability(robot) if is_puma_type(robot)
                  else _sampled_max_manipulability(robot))
        _WM_CACHE[robot] = cached
    return cached
