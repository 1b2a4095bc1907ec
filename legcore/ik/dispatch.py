"""Inverse kinematics by robot family: :func:`ik` dispatches on ``robot.ik_family`` to the closed
forms (``legcore.ik.puma560``, ``legcore.ik.arm5``, ``legcore.ik.leg3``, ``legcore.ik.leg2``) and
to damped least squares (:func:`legcore.ik.dls.ik_dls`) otherwise. Unreachable targets are
reported per sample (``reachable`` False, ``q`` NaN); joint limits are reported
(``within_limits``), never enforced by clipping.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.ik.dls import ik_dls
from legcore.ik.result import IKResult, _as_target, _residual
from legcore.joint_angles import wrap_to_limits
from legcore.robots.model import Robot
from legcore.robots.spec import DHRobotSpec

__all__ = ["ik"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]


def _select_branch(
    sols: FloatArray,
    reach: BoolArray,
    within: BoolArray,
    branch: int | str | None,
    names: tuple[str, ...],
    q_ref: FloatArray,
) -> tuple[FloatArray, BoolArray, BoolArray, IntArray]:
    """Pick one solution per sample from (N, k, n) candidates."""
    N, k, n = sols.shape
    if branch is not None:
        if isinstance(branch, str):
            if branch not in names:
                raise ValueError(f"branch: unknown {branch!r}; one of {names}")
            b = names.index(branch)
        else:
            b = int(branch)
            if not 0 <= b < k:
                raise ValueError(f"branch: must be in 0..{k - 1}, got {branch}")
        idx = np.full(N, b, dtype=np.int64)
    else:
        # prefer reachable & within limits, then reachable; then the nearest q_ref (L1)
        d = np.sum(np.abs(sols - q_ref[:, None, :]), axis=-1)
        d = np.where(np.isnan(d), np.inf, d)
        score = d + np.where(within, 0.0, 1e6) + np.where(reach, 0.0, 1e12)
        idx = np.argmin(score, axis=-1).astype(np.int64)
    rows = np.arange(N)
    q = sols[rows, idx]
    r = reach[rows, idx]
    w = within[rows, idx] & r
    q = np.where(r[:, None], q, np.nan)
    idx = np.where(r, idx, -1)
    return q, r, w, idx


def _ref_config(robot: Robot, q_ref: ArrayLike | None, batch: tuple[int, ...]) -> FloatArray:
    """``q_ref`` (default ``robot.home``) broadcast to the targets' batch, flattened (N, n)."""
    n = robot.nq
    a = robot.home if q_ref is None else np.asarray(q_ref, dtype=float)
    if a.shape[-1:] != (n,):
        raise ValueError(f"q_ref: last axis must have length nq = {n}, got {a.shape}")
    try:
        return np.array(np.broadcast_to(a, (*batch, n)).reshape(-1, n), dtype=float)
    except ValueError:
        raise ValueError(
            f"q_ref: shape {a.shape} does not broadcast to the targets' batch {(*batch, n)}"
        ) from None


def ik(
    robot: Robot,
    target: ArrayLike,
    *,
    branch: int | str | None = None,
    q_ref: ArrayLike | None = None,
    yaw: ArrayLike | None = None,
    **dls_options: float | int | bool,
) -> IKResult:
    """Inverse kinematics of ``target`` — poses (..., 4, 4) or tool positions (..., 3), world, m.

    Dispatches on ``robot.ik_family``:

    - ``"puma560"`` (poses): all 8 closed-form branches (:mod:`legcore.ik.puma560`);
    - ``"arm5_down"`` (positions, or poses whose tool z axis points straight down): the 5-DOF arm
      of seed 004 with the tool pointing down; ``yaw`` (...,) rad is the heading of the tool x
      axis in the world xy plane (from the pose when one is given; joint 5 = 0 when neither);
      a pose that is not pointing down is reported unreachable;
    - ``"leg3"`` / ``"leg2"`` (positions; poses use their translation): the leg closed forms;
    - ``"dls"`` or None: :func:`ik_dls` from ``q_ref`` (default ``robot.home``), with
      ``dls_options`` passed on.

    Closed forms return the branch ``branch`` (index or name, see ``result.branch_names``) or,
    when None, per sample the reachable solution inside the joint limits nearest ``q_ref``
    (default ``robot.home``) in the L1 joint distance, falling back to one outside the limits.
    Revolute angles are shifted by 2π into the limits where possible (:func:`wrap_to_limits`).
    """
    family = robot.ik_family
    if family in (None, "dls"):
        if branch is not None or yaw is not None:
            raise ValueError("branch/yaw: only meaningful for closed-form IK families")
        q0 = robot.home if q_ref is None else q_ref
        return ik_dls(robot, target, q0, **dls_options)  # type: ignore[arg-type]
    if dls_options:
        raise ValueError(f"{sorted(dls_options)}: options of ik_dls, not of {family!r} IK")
    tf, is_pose, batch = _as_target(target)
    N = tf.shape[0]
    ref = _ref_config(robot, q_ref, batch)
    revolute = ~robot.chain.prismatic
    if family == "puma560":
        from legcore.ik.puma560 import BRANCH_NAMES, puma560_geometry, puma560_ik

        if not is_pose:
            raise ValueError("target: the PUMA 560 IK needs poses (..., 4, 4), not positions")
        if yaw is not None:
            raise ValueError("yaw: not used by the PUMA 560 IK (give full poses)")
        sol = puma560_ik(tf, puma560_geometry(robot.spec), robot.q_min, robot.q_max, ref[:, None])
        names: tuple[str, ...] = BRANCH_NAMES
        sols, reach, within = sol.q, sol.reachable, sol.within_limits
    elif family == "arm5_down":
        from legcore.ik.arm5 import BRANCH_NAMES as ARM5_NAMES
        from legcore.ik.arm5 import arm5_geometry, arm5_ik_down

        geo = arm5_geometry(robot.spec)
        if is_pose:
            if yaw is not None:
                raise ValueError("yaw: give it only with positions; poses carry their own yaw")
            p = tf[:, :3, 3]
            down = (np.hypot(tf[:, 0, 2], tf[:, 1, 2]) < 1e-9) & (tf[:, 2, 2] < 0.0)
            yaw_arr: FloatArray | None = np.arctan2(tf[:, 1, 0], tf[:, 0, 0])
        else:
            p = tf
            down = np.ones(N, dtype=bool)
            yaw_arr = None
            if yaw is not None:
                yaw_arr = np.broadcast_to(np.asarray(yaw, dtype=float), batch).reshape(-1)
        sol5 = arm5_ik_down(p, geo, yaw_arr, robot.q_min, robot.q_max, ref[:, None])
        names = ARM5_NAMES
        sols, reach, within = sol5.q, sol5.reachable & down[:, None], sol5.within_limits
        within = within & down[:, None]
    elif family in ("leg3", "leg2"):
        if yaw is not None:
            raise ValueError(f"yaw: not used by the {family!r} IK")
        p = tf[:, :3, 3] if is_pose else tf
        sols, reach, names = _leg_ik(robot, family, p)
        sols = wrap_to_limits(sols, robot.q_min, robot.q_max, ref[:, None], revolute)
        within = reach & robot.within_limits(sols)
        is_pose = False  # legs match positions only
        tf = p
    else:  # pragma: no cover - spec validation restricts the families
        raise ValueError(f"robot: unknown ik_family {family!r}")
    q, r, w, idx = _select_branch(sols, reach, within, branch, names, ref)
    err = _residual(robot, q, tf, is_pose)
    return IKResult(
        q=q.reshape(*batch, robot.nq),
        reachable=r.reshape(batch),
        within_limits=w.reshape(batch),
        branch=idx.reshape(batch),
        error=err.reshape(batch),
        iterations=np.zeros(batch, dtype=np.int64),
        branch_names=names,
        method=family,
    )


def _leg_ik(
    robot: Robot, family: str, p: FloatArray
) -> tuple[FloatArray, BoolArray, tuple[str, ...]]:
    """Both knee branches (N, 2, n) of the leg closed forms in ``legcore.ik.leg3`` / ``leg2``.

    The robot must be the standard-DH chain those modules solve (``d = 0``; α = (90°, 0, 0) for
    ``leg3``, (0, 0) for ``leg2``; link lengths = the spec's ``a``; no tool offset). Targets are
    mapped into the leg base frame with the spec's ``base``; DH offsets are subtracted.
    """
    spec = robot.spec
    if not isinstance(spec, DHRobotSpec) or spec.convention != "standard":
        raise ValueError(f"robot: the {family!r} closed form needs a standard-DH robot spec")
    j = spec.joints
    alphas = (math.pi / 2, 0.0, 0.0) if family == "leg3" else (0.0, 0.0)
    if len(j) != len(alphas) or any(x.type != "revolute" for x in j):
        raise ValueError(f"robot: the {family!r} closed form needs {len(alphas)} revolute joints")
    for i, (x, al) in enumerate(zip(j, alphas, strict=True)):
        if abs(x.alpha - al) > 1e-9 or abs(x.d) > 1e-12:
            raise ValueError(
                f"spec.joints.{i}: the {family!r} closed form needs d = 0 and "
                f"α = {tuple(round(math.degrees(a)) for a in alphas)}°"
            )
    if spec.tool is not None and np.abs(np.asarray(spec.tool)[:3, 3]).max() > 1e-12:
        raise ValueError(f"spec.tool: the {family!r} closed form needs the tool at the foot")
    L = np.array([x.a for x in j])
    offset = np.array([x.offset for x in j])
    if spec.base is not None:
        base = np.asarray(spec.base, dtype=float)
        p = (p - base[:3, 3]) @ base[:3, :3]
    if family == "leg3":
        from legcore.ik.leg3 import KNEE_DOWN, KNEE_UP, leg3_ik

        branches = ((KNEE_UP, "knee-up"), (KNEE_DOWN, "knee-down"))
        solve: Callable[..., tuple[FloatArray, BoolArray]] = leg3_ik
    else:
        from legcore.ik.leg2 import ELBOW_BACK, KNEE_FORWARD, leg2_ik

        branches = ((ELBOW_BACK, "elbow-back"), (KNEE_FORWARD, "knee-forward"))
        solve = leg2_ik
    qs, oks = [], []
    lo, hi = robot.q_min + offset, robot.q_max + offset
    for b, _ in branches:
        # the solvers pick, per branch, a yaw family inside the limits when one exists
        q_lim, ok_lim = solve(p, L, b, lo, hi)
        q_free, ok_free = solve(p, L, b)
        qs.append(np.where(ok_lim[:, None], q_lim, q_free) - offset)
        oks.append(ok_lim | ok_free)
    return np.stack(qs, axis=1), np.stack(oks, axis=1), tuple(name for _, name in branches)
