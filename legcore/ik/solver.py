"""One entry point for inverse kinematics of any serial robot: :func:`solve`.

Closed forms are fast paths where the robot's ``ik_family`` solves the task exactly
(:mod:`legcore.ik.closed_form`); every other robot/task goes to the batched numerical solver
(:mod:`legcore.ik.numeric`). Both return :class:`~legcore.ik.targets.IKSolution` with the same
meaning: ``q`` inside the joint limits and on target to the tolerance, or NaN and
``reachable = False``; targets are never clipped.
"""

from __future__ import annotations

import inspect
import math
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from legcore.ik.closed_form import closed_form_candidates, track_branches
from legcore.ik.numeric import solve_numeric, solve_parsed
from legcore.ik.targets import IKSolution, parse_targets, task_errors
from legcore.kinematics import fk
from legcore.robots.model import Robot

__all__ = ["solve"]

Method = Literal["auto", "closed_form", "numeric"]

# the numerical solver's tuning options and their defaults, from its signature
_NUMERIC_DEFAULTS: dict[str, Any] = {
    k: v.default
    for k, v in inspect.signature(solve_numeric).parameters.items()
    if v.kind is inspect.Parameter.KEYWORD_ONLY
    and k not in ("q0", "rest", "path", "tol", "tol_rot", "flip_tol")
}


def solve(
    robot: Robot,
    targets: ArrayLike,
    task: str = "pose",
    *,
    q0: ArrayLike | None = None,
    rest: ArrayLike | None = None,
    path: bool = False,
    method: Method = "auto",
    tol: float = 1e-9,
    tol_rot: float = 1e-9,
    flip_tol: float = 0.5,
    **numeric_options: float | int,
) -> IKSolution:
    """Inverse kinematics of ``targets`` for ``task`` (``"position"``, ``"axis"``, ``"pose"``).

    ``targets``: see :mod:`legcore.ik.targets` — positions (..., 3) m, position + axis (..., 6),
    or poses (..., 4, 4), world frame. ``path``: the last batch axis is a path (warm start,
    branch tracking, ``flip`` reported where the joints jump by more than ``flip_tol`` rad or m
    from the previous reachable sample). ``q0``: start / reference configuration (first sample
    of each path, or every target without a path); default ``rest``. ``rest``: the posture a
    redundant chain is pulled to (numeric solver); default ``robot.home``.

    ``method``: ``"auto"`` (the closed form when ``robot.ik_family`` solves this task — PUMA 560
    poses, 5-DOF arm with the tool axis straight down, leg positions — else numeric),
    ``"closed_form"`` (ValueError if there is none) or ``"numeric"``. A closed form returns per
    sample the branch inside the limits nearest the reference (``q0``, or along a path the
    previous sample). ``tol`` m / ``tol_rot`` rad: accuracy required of every returned sample.
    ``numeric_options`` go to :func:`~legcore.ik.numeric.solve_numeric` (``max_iter``,
    ``restarts``, ``null_gain``, ``null_tol``, ``max_step``, ``max_substeps``, ``rot_weight``).
    """
    if method not in ("auto", "closed_form", "numeric"):
        raise ValueError(f"method: must be 'auto', 'closed_form' or 'numeric', got {method!r}")
    unknown = sorted(set(numeric_options) - set(_NUMERIC_DEFAULTS))
    if unknown:
        raise ValueError(f"{unknown}: not options of the numerical solver")
    p, Rt, batch = parse_targets(task, targets)
    found = None if method == "numeric" else closed_form_candidates(robot, task, p, Rt)
    if found is None:
        if method == "closed_form":
            raise ValueError(
                f"method: robot {robot.name!r} (ik_family {robot.ik_family!r}) has no closed "
                f"form for task {task!r}"
            )
        opts: dict[str, Any] = {**_NUMERIC_DEFAULTS, **numeric_options}
        return solve_parsed(
            robot, p, Rt, batch, task, q0=q0, rest=rest, path=path, tol=tol, tol_rot=tol_rot,
            flip_tol=flip_tol, **opts,
        )
    for name, v in (("tol", tol), ("tol_rot", tol_rot), ("flip_tol", flip_tol)):
        if not (math.isfinite(v) and v > 0.0):
            raise ValueError(f"{name}: must be a finite value > 0, got {v!r}")
    cand, ok, names = found
    n = robot.nq
    if path and len(batch) == 0:
        raise ValueError("targets: path=True needs a batch of samples (..., K, ...)")
    ref = robot.home if rest is None else np.asarray(rest, dtype=float)
    ref = ref if q0 is None else np.asarray(q0, dtype=float)
    lead = batch[:-1] if path else batch
    try:
        q_init = np.array(np.broadcast_to(ref, (*lead, n)), dtype=float).reshape(-1, n)
    except ValueError:
        raise ValueError(f"q0: shape {np.shape(ref)} does not broadcast to {(*lead, n)}") from None
    if not np.all(np.isfinite(q_init)):
        raise ValueError("q0: must be finite")
    P = q_init.shape[0]
    K = batch[-1] if path else 1
    B = cand.shape[1]
    q3, idx = track_branches(
        robot, cand.reshape(P, K, B, n), ok.reshape(P, K, B), q_init, path
    )
    q = q3.reshape(-1, n)
    found_ok = idx.reshape(-1) >= 0
    ep = np.full(q.shape[0], np.nan)
    er = np.full(q.shape[0], np.nan)
    if found_ok.any():
        e_p, e_r = task_errors(task, fk(robot, q[found_ok]), p[found_ok], Rt[found_ok])
        ep[found_ok], er[found_ok] = e_p, e_r
    good = found_ok & (ep <= tol) & (er <= tol_rot) & robot.within_limits(
        np.where(found_ok[:, None], q, 0.0), tol=0.0
    )
    q = np.where(good[:, None], q, np.nan)
    flip = np.zeros((P, K), dtype=bool)
    if path and K > 1:
        flip = _jumps(q.reshape(P, K, n), good.reshape(P, K), flip_tol)
    ep, er = np.where(good, ep, np.nan), np.where(good, er, np.nan)
    return IKSolution(
        q=q.reshape(*batch, n),
        reachable=good.reshape(batch),
        within_limits=good.reshape(batch),
        branch=np.where(good, idx.reshape(-1), -1).astype(np.int64).reshape(batch),
        error=np.hypot(ep, er).reshape(batch),
        iterations=np.zeros(batch, dtype=np.int64),
        branch_names=names,
        method=str(robot.ik_family),
        flip=flip.reshape(batch),
        position_error=ep.reshape(batch),
        rotation_error=er.reshape(batch),
        task=task,
    )


def _jumps(q: np.ndarray, good: np.ndarray, flip_tol: float) -> np.ndarray:
    """(P, K) True where a reachable sample jumps > ``flip_tol`` from the previous reachable one."""
    P, K, n = q.shape
    # index of the previous reachable sample, per path (forward fill of reachable indices)
    ks = np.where(good, np.arange(K)[None, :], -1)
    last = np.maximum.accumulate(ks, axis=1)
    prev = np.concatenate([np.full((P, 1), -1), last[:, :-1]], axis=1)
    has_prev = good & (prev >= 0)
    q_prev = np.take_along_axis(q, np.maximum(prev, 0)[..., None], axis=1)
    jump = np.nanmax(np.abs(q - q_prev), axis=-1, initial=0.0)
    return has_prev & (jump > flip_tol)
