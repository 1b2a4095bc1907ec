"""Closed-form IK as a fast path of :func:`legcore.ik.solve`: all branches, then branch tracking.

:func:`closed_form_candidates` returns every closed-form branch of the targets when the robot's
``ik_family`` solves the task exactly:

- ``"puma560"``: task ``"pose"`` (8 branches, :mod:`legcore.ik.puma560`);
- ``"arm5_down"``: task ``"axis"`` with every target axis pointing straight down (4 branches,
  :mod:`legcore.ik.arm5`, joint 5 at 0: the spin about the axis is free);
- ``"leg3"`` / ``"leg2"``: task ``"position"`` (2 knee branches each, preferring per branch the
  yaw family inside the limits, as :func:`legcore.ik.dispatch.ik`).

:func:`track_branches` then picks one candidate per sample inside the joint limits — nearest
``q0`` for independent targets, nearest the previous sample's choice along a path (so a path
stays on its branch while it can) — after shifting revolute angles by 2π toward that reference
when the shifted angle stays inside the limits.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from legcore.ik.dispatch import ik
from legcore.robots.model import Robot

__all__ = ["closed_form_candidates", "track_branches"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

_DOWN_TOL = 1e-12  # |axis − (0, 0, −1)| below which an axis target "points down"


def closed_form_candidates(
    robot: Robot, task: str, p: FloatArray, Rt: FloatArray
) -> tuple[FloatArray, BoolArray, tuple[str, ...]] | None:
    """Every closed-form branch for targets (p (N, 3) m, Rt (N, 3, 3)) of ``task``, or None.

    Returns ``(q (N, B, n), ok (N, B), branch names)`` with ``ok`` = reachable and inside the
    joint limits, or None when the robot's ``ik_family`` does not solve this task exactly.
    """
    family = robot.ik_family
    if family == "puma560" and task == "pose":
        from legcore.ik.puma560 import BRANCH_NAMES, puma560_geometry, puma560_ik

        T = np.broadcast_to(np.eye(4), (p.shape[0], 4, 4)).copy()
        T[:, :3, :3], T[:, :3, 3] = Rt, p
        sol = puma560_ik(T, puma560_geometry(robot.spec), robot.q_min, robot.q_max)
        return sol.q, sol.within_limits & sol.reachable, BRANCH_NAMES
    if family == "arm5_down" and task == "axis":
        down = np.abs(Rt[:, :, 2] - np.array([0.0, 0.0, -1.0])).max(initial=0.0) <= _DOWN_TOL
        if not down:
            return None
        from legcore.ik.arm5 import BRANCH_NAMES as ARM5_NAMES
        from legcore.ik.arm5 import arm5_geometry, arm5_ik_down

        sol5 = arm5_ik_down(p, arm5_geometry(robot.spec), None, robot.q_min, robot.q_max)
        return sol5.q, sol5.within_limits & sol5.reachable, ARM5_NAMES
    if family in ("leg3", "leg2") and task == "position":
        names = ("knee-up", "knee-down") if family == "leg3" else ("elbow-back", "knee-forward")
        qs, oks = [], []
        for b in range(len(names)):
            res = ik(robot, p, branch=b)
            qs.append(res.q)
            oks.append(res.reachable & res.within_limits)
        return np.stack(qs, axis=1), np.stack(oks, axis=1), names
    return None


@numba.njit(cache=True, nogil=True)
def _track_kernel(
    cand: FloatArray,
    ok: BoolArray,
    q_init: FloatArray,
    warm: bool,
    lo: FloatArray,
    hi: FloatArray,
    revolute: BoolArray,
    q_out: FloatArray,
    idx: NDArray[np.int64],
) -> None:  # pragma: no cover - compiled
    """Per path b and sample k, the ok candidate nearest the reference (L1), 2π-shifted."""
    P, K, B, n = cand.shape
    two_pi = 2.0 * math.pi
    ref = np.empty(n)
    c = np.empty(n)
    best_q = np.empty(n)
    for b in range(P):
        for j in range(n):
            ref[j] = q_init[b, j]
        for k in range(K):
            best = math.inf
            best_i = -1
            for i in range(B):
                if not ok[b, k, i]:
                    continue
                d = 0.0
                for j in range(n):
                    v = cand[b, k, i, j]
                    if revolute[j]:
                        s = v + two_pi * math.floor((ref[j] - v) / two_pi + 0.5)
                        if s < lo[j] or s > hi[j]:
                            s = s + two_pi if s < lo[j] else s - two_pi
                            if s < lo[j] or s > hi[j]:
                                s = v
                        v = s
                    c[j] = v
                    d += abs(v - ref[j])
                if d < best:
                    best = d
                    best_i = i
                    for j in range(n):
                        best_q[j] = c[j]
            idx[b, k] = best_i
            for j in range(n):
                q_out[b, k, j] = best_q[j] if best_i >= 0 else np.nan
            if warm and best_i >= 0:
                for j in range(n):
                    ref[j] = best_q[j]


def track_branches(
    robot: Robot, cand: FloatArray, ok: BoolArray, q_init: FloatArray, path: bool
) -> tuple[FloatArray, NDArray[np.int64]]:
    """Choose one candidate per sample: ``cand`` (P, K, B, n), ``ok`` (P, K, B), ``q_init`` (P, n).

    Returns ``(q (P, K, n), branch index (P, K), −1 and NaN where no candidate is ok)``.
    """
    P, K, _, n = cand.shape
    q_out = np.empty((P, K, n))
    idx = np.empty((P, K), dtype=np.int64)
    _track_kernel(
        np.ascontiguousarray(np.nan_to_num(cand)),
        np.ascontiguousarray(ok),
        np.ascontiguousarray(q_init),
        bool(path),
        robot.q_min,
        robot.q_max,
        ~robot.chain.prismatic,
        q_out,
        idx,
    )
    return q_out, idx
