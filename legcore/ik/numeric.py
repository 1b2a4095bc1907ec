"""Batched numerical inverse kinematics of any serial chain, warm-started along paths.

:func:`solve_numeric` solves every target of a batch in one compiled (numba) pass over the
chain arrays of the robot's Pinocchio model, sample by sample with the damped Newton step of
:mod:`legcore.ik.newton` (position, position + tool axis, or full pose; joint limits enforced;
redundancy resolved toward a rest posture).

Along a path (``path=True``) sample k starts from the solution of sample k−1 (continuation), so
the branch is tracked: the solver stays on the branch it started on. When the warm start fails
or its solution jumps by more than ``flip_tol`` in some joint, the step from the previous
reachable target is subdivided (2, 4, … ``max_substeps`` intermediate targets: positions
interpolated linearly, axes and rotations along the geodesic) and solved by continuation;
only if that fails too is the sample restarted from ``restarts`` seed configurations (the rest
posture, then a Halton sequence inside the limits). A sample whose solution still jumps is
reported in ``flip`` (a forced change of branch). Independent targets (``path=False``) all start
from ``q0`` and are restarted the same way when they fail.

The path axis is sequential by nature; the compiled loop makes one sample cost a few
FK + Jacobian evaluations (≈ µs), far below a Python loop's per-sample overhead — see
``benchmarks/bench_ik.py``.
"""

from __future__ import annotations

import functools
import math
import weakref

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.ik.newton import (
    PRM_LAM0,
    PRM_LAM_MAX,
    PRM_MAX_STEP,
    PRM_NEAR,
    PRM_NULL_GAIN,
    PRM_NULL_TOL,
    PRM_SIZE,
    PRM_TOL_P,
    PRM_TOL_R,
    PRM_W,
    newton,
    workspace,
)
from legcore.ik.sample_kinematics import interp_target, z_chain
from legcore.ik.targets import TASK_ROWS, IKSolution, parse_targets
from legcore.ik.track import track
from legcore.robots.model import Chain, Robot

__all__ = ["halton_seeds", "solve_numeric", "solve_parsed"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _max_jump(a: FloatArray, b: FloatArray) -> float:  # pragma: no cover - compiled
    d = 0.0
    for j in range(a.shape[0]):
        d = max(d, abs(a[j] - b[j]))
    return d


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _paths_kernel(
    tp: FloatArray,
    tR: FloatArray,
    task: int,
    q_init: FloatArray,
    warm: bool,
    lo: FloatArray,
    hi: FloatArray,
    rest: FloatArray,
    use_rest: bool,
    R: FloatArray,
    p: FloatArray,
    prismatic: BoolArray,
    tool_R: FloatArray,
    tool_p: FloatArray,
    prm: FloatArray,
    max_iter: int,
    seeds: FloatArray,
    flip_tol: float,
    max_sub: int,
    q_out: FloatArray,
    ok: BoolArray,
    iters: NDArray[np.int64],
    flip: BoolArray,
    err_p: FloatArray,
    err_r: FloatArray,
) -> None:  # pragma: no cover - compiled
    """Solve targets (P, K) — P paths of K samples (or P independent targets, K = 1)."""
    P, K = ok.shape
    n = q_init.shape[1]
    q = np.empty(n)
    q_prev = np.empty(n)
    q_prev2 = np.empty(n)
    q_prev3 = np.empty(n)
    q_sub = np.empty(n)
    p_prev = np.empty(3)
    R_prev = np.empty((3, 3))
    p_i = np.empty(3)
    R_i = np.empty((3, 3))
    ws = workspace(n, task)
    for b in range(P):
        have_prev = False
        have_prev2 = False
        have_prev3 = False
        for k in range(K):
            tpk = tp[b, k]
            tRk = tR[b, k]
            for j in range(n):
                if warm and have_prev3:  # predictor: extrapolate the last three solutions
                    q[j] = 3.0 * (q_prev[j] - q_prev2[j]) + q_prev3[j]
                elif warm and have_prev2:
                    q[j] = 2.0 * q_prev[j] - q_prev2[j]
                elif warm and have_prev:
                    q[j] = q_prev[j]
                else:
                    q[j] = q_init[b, j]
            if warm and have_prev:  # a predictor: one Newton step, checked (newton if not)
                conv, it, ep, er = track(
                    q, tpk, tRk, task, lo, hi, rest, use_rest, R, p, prismatic, tool_R,
                    tool_p, prm, max_iter, ws,
                )
            else:
                conv, it, ep, er = newton(
                    q, tpk, tRk, task, lo, hi, rest, use_rest, R, p, prismatic, tool_R, tool_p,
                    prm, max_iter, ws,
                )
            total = it
            jumped = conv and have_prev and _max_jump(q, q_prev) > flip_tol
            if warm and have_prev and (not conv or jumped):
                n_sub = 2
                while n_sub <= max_sub:
                    for j in range(n):
                        q_sub[j] = q_prev[j]
                    good = True
                    for s in range(1, n_sub + 1):
                        interp_target(task, p_prev, R_prev, tpk, tRk, s / n_sub, p_i, R_i)
                        c2, it2, ep2, er2 = newton(
                            q_sub, p_i, R_i, task, lo, hi, rest, use_rest, R, p,
                            prismatic, tool_R, tool_p, prm, max_iter, ws,
                        )
                        total += it2
                        if not c2:
                            good = False
                            break
                    if good and _max_jump(q_sub, q_prev) <= flip_tol:
                        for j in range(n):
                            q[j] = q_sub[j]
                        conv = True
                        ep, er = ep2, er2
                        jumped = False
                        break
                    n_sub *= 2
            if not conv:
                for s in range(seeds.shape[0]):
                    for j in range(n):
                        q[j] = seeds[s, j]
                    conv, it, ep, er = newton(
                        q, tpk, tRk, task, lo, hi, rest, use_rest, R, p, prismatic,
                        tool_R, tool_p, prm, max_iter, ws,
                    )
                    total += it
                    if conv:
                        jumped = have_prev and _max_jump(q, q_prev) > flip_tol
                        break
            iters[b, k] = total
            if conv:
                have_prev3 = have_prev2 and not jumped
                have_prev2 = have_prev and not jumped
                for j in range(n):
                    q_out[b, k, j] = q[j]
                    q_prev3[j] = q_prev2[j]
                    q_prev2[j] = q_prev[j]
                    q_prev[j] = q[j]
                for a in range(3):
                    p_prev[a] = tpk[a]
                    for c in range(3):
                        R_prev[a, c] = tRk[a, c]
                ok[b, k] = True
                flip[b, k] = jumped and warm
                err_p[b, k] = ep
                err_r[b, k] = er
                have_prev = True
            else:
                have_prev2 = False
                have_prev3 = False
                for j in range(n):
                    q_out[b, k, j] = np.nan
                ok[b, k] = False
                flip[b, k] = False


def halton_seeds(count: int, lo: FloatArray, hi: FloatArray, center: FloatArray) -> FloatArray:
    """``count`` deterministic seed configurations (count, n) spread inside the limits.

    A Halton sequence (bases 2, 3, 5, …) over ``[lo, hi]`` narrowed to ``center ± π`` (one turn
    of a revolute joint is enough to reach every pose).
    """
    n = lo.shape[0]
    primes = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37]
    a = np.maximum(lo, center - math.pi)
    b = np.minimum(hi, center + math.pi)
    out = np.empty((count, n))
    for j in range(n):  # the radical inverse of 1..count in base primes[j], all i at once
        base = primes[j % len(primes)]
        k = np.arange(1, count + 1)
        f = np.ones(count)
        r = np.zeros(count)
        while k.any():  # digit by digit, the same float operations as one i at a time
            live = k > 0
            f = np.where(live, f / base, f)
            r = np.where(live, r + f * (k % base), r)
            k //= base
        out[:, j] = a[j] + r * (b[j] - a[j])
    return out


@functools.lru_cache(maxsize=64)
def _restart_seeds(restarts: int, lo: bytes, hi: bytes, rest: bytes) -> FloatArray:
    """The restart seeds (restarts, n): ``rest``, then :func:`halton_seeds` about it (limits and
    rest as bytes of float64 arrays; cached — read-only)."""
    lo_a, hi_a, rest_a = (np.frombuffer(v, dtype=np.float64) for v in (lo, hi, rest))
    seeds = np.concatenate(
        [rest_a[None], halton_seeds(max(restarts - 1, 0), lo_a, hi_a, rest_a)]
    )[:restarts]
    seeds = np.ascontiguousarray(seeds)
    seeds.flags.writeable = False
    return seeds


_Z_CHAINS: weakref.WeakKeyDictionary[Chain, tuple[FloatArray, ...]] = weakref.WeakKeyDictionary()


def _z_chain(robot: Robot) -> tuple[FloatArray, ...]:
    """:func:`~legcore.ik.sample_kinematics.z_chain` of the robot's chain (cached per chain)."""
    c = robot.chain
    z = _Z_CHAINS.get(c)
    if z is None:
        z = z_chain(c.R, c.p, c.axis, c.tool_R, c.tool_p)
        _Z_CHAINS[c] = z
    return z


def _config(robot: Robot, value: ArrayLike | None, default: FloatArray, name: str) -> FloatArray:
    a = default if value is None else np.asarray(value, dtype=float)
    if a.ndim == 0 or a.shape[-1] != robot.nq or not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: must be finite with last axis nq = {robot.nq}, got {a.shape}")
    return a


def _reach_scale(robot: Robot) -> float:
    """A length (m) of the order of the robot's reach: the sum of its link offsets."""
    c = robot.chain
    return max(float(np.linalg.norm(c.p, axis=-1).sum() + np.linalg.norm(c.tool_p)), 1e-3)


def solve_numeric(
    robot: Robot,
    targets: ArrayLike,
    task: str = "pose",
    *,
    q0: ArrayLike | None = None,
    rest: ArrayLike | None = None,
    path: bool = False,
    tol: float = 1e-9,
    tol_rot: float = 1e-9,
    max_iter: int = 100,
    restarts: int = 32,
    flip_tol: float = 0.5,
    max_substeps: int = 8,
    null_gain: float = 1.0,
    null_tol: float = 1e-7,
    max_step: float = 0.5,
    rot_weight: float | None = None,
) -> IKSolution:
    """Numerical IK of ``targets`` for ``task`` (see :mod:`legcore.ik.targets`).

    ``q0``: start configuration, broadcastable to (*S[:-1], n) along paths (the first sample of
    each path) or to (*S, n) without; default ``rest``. ``rest``: rest posture (n,) that
    redundant chains (n > task rows) are pulled to in the null space; default ``robot.home``.
    ``tol`` m / ``tol_rot`` rad: convergence of the position / orientation error. ``max_iter``
    per attempt; ``restarts`` seed configurations tried when an attempt fails; ``flip_tol``
    (rad or m) the joint jump reported as a flip; ``max_substeps`` the finest subdivision of a
    path step; ``null_gain`` the rest-posture pull (1 = full projected step) and ``null_tol``
    (rad) its convergence: the remaining first-order move toward the rest posture;
    ``max_step`` the largest joint move per iteration; ``rot_weight`` (m/rad) the weight of the
    orientation rows (default: the robot's reach). Returns :class:`IKSolution` (method
    ``"numeric"``, branch 0 where reachable).
    """
    p_t, R_t, batch = parse_targets(task, targets)
    return solve_parsed(
        robot, p_t, R_t, batch, task, q0=q0, rest=rest, path=path, tol=tol, tol_rot=tol_rot,
        max_iter=max_iter, restarts=restarts, flip_tol=flip_tol, max_substeps=max_substeps,
        null_gain=null_gain, null_tol=null_tol, max_step=max_step, rot_weight=rot_weight,
    )


def solve_parsed(
    robot: Robot,
    p_t: FloatArray,
    R_t: FloatArray,
    batch: tuple[int, ...],
    task: str,
    *,
    q0: ArrayLike | None,
    rest: ArrayLike | None,
    path: bool,
    tol: float,
    tol_rot: float,
    max_iter: int,
    restarts: int,
    flip_tol: float,
    max_substeps: int,
    null_gain: float,
    null_tol: float,
    max_step: float,
    rot_weight: float | None,
) -> IKSolution:
    """:func:`solve_numeric` on targets already parsed by :func:`parse_targets`."""
    n = robot.nq
    if path and len(batch) == 0:
        raise ValueError("targets: path=True needs a batch of samples (..., K, ...)")
    for name, v in (("tol", tol), ("tol_rot", tol_rot), ("flip_tol", flip_tol),
                    ("max_step", max_step), ("null_gain", null_gain), ("null_tol", null_tol)):
        if not (math.isfinite(v) and v > 0.0):
            raise ValueError(f"{name}: must be a finite value > 0, got {v!r}")
    if max_iter < 1 or restarts < 0 or max_substeps < 0:
        raise ValueError("max_iter must be >= 1, restarts and max_substeps >= 0")
    rest_a = _config(robot, rest, robot.home, "rest")
    if rest_a.shape != (n,):
        raise ValueError(f"rest: must have shape ({n},), got {rest_a.shape}")
    rest_a = np.clip(rest_a, robot.q_min, robot.q_max)
    q0_a = _config(robot, q0, rest_a, "q0")
    lead = batch[:-1] if path else batch
    try:
        q_init = np.array(np.broadcast_to(q0_a, (*lead, n)), dtype=float, order="C")
        q_init = q_init.reshape(-1, n)  # a writable C-order copy: one signature of _paths_kernel
    except ValueError:
        raise ValueError(f"q0: shape {q0_a.shape} does not broadcast to {(*lead, n)}") from None
    K = batch[-1] if path else 1
    P = q_init.shape[0]
    m = TASK_ROWS[task]
    w = _reach_scale(robot) if rot_weight is None else float(rot_weight)
    prm = np.zeros(PRM_SIZE)
    prm[PRM_TOL_P], prm[PRM_TOL_R], prm[PRM_W] = tol, tol_rot, w
    prm[PRM_LAM0], prm[PRM_LAM_MAX] = 1e-3 * w, 1e6 * w
    prm[PRM_NULL_GAIN], prm[PRM_NULL_TOL] = null_gain, null_tol
    prm[PRM_MAX_STEP], prm[PRM_NEAR] = max_step, 1e-3 * w
    seeds = _restart_seeds(
        int(restarts),
        *(np.asarray(v, dtype=np.float64).tobytes() for v in (robot.q_min, robot.q_max, rest_a)),
    )
    zR, zp, z_tool_R, z_tool_p = _z_chain(robot)
    q_out = np.empty((P, K, n))
    ok = np.zeros((P, K), dtype=bool)
    iters = np.zeros((P, K), dtype=np.int64)
    flip = np.zeros((P, K), dtype=bool)
    ep = np.full((P, K), np.nan)
    er = np.full((P, K), np.nan)
    _paths_kernel(
        np.ascontiguousarray(p_t.reshape(P, K, 3)),
        np.ascontiguousarray(R_t.reshape(P, K, 3, 3)),
        m,
        q_init,
        bool(path),
        robot.q_min,
        robot.q_max,
        rest_a,
        n > m,
        zR, zp, robot.chain.prismatic, z_tool_R, z_tool_p,
        prm,
        int(max_iter),
        seeds,
        float(flip_tol),
        int(max_substeps),
        q_out, ok, iters, flip, ep, er,
    )
    q_flat = q_out.reshape(-1, n)
    # what is returned is inside the limits and on target (guaranteed by the kernel; checked)
    good = ok.reshape(-1) & (ep.reshape(-1) <= tol) & (er.reshape(-1) <= tol_rot)
    good &= robot.within_limits(np.where(good[:, None], q_flat, robot.q_min), tol=0.0)
    q_flat = np.where(good[:, None], q_flat, np.nan)
    ep_f = np.where(good, ep.reshape(-1), np.nan)
    er_f = np.where(good, er.reshape(-1), np.nan)
    return IKSolution(
        q=q_flat.reshape(*batch, n),
        reachable=good.reshape(batch),
        within_limits=good.reshape(batch),
        branch=np.where(good, 0, -1).astype(np.int64).reshape(batch),
        error=np.hypot(ep_f, er_f).reshape(batch),
        iterations=iters.reshape(batch),
        branch_names=("numeric",),
        method="numeric",
        flip=(flip.reshape(-1) & good).reshape(batch),
        position_error=ep_f.reshape(batch),
        rotation_error=er_f.reshape(batch),
        task=task,
    )
