"""The joints of an arm along a fixed tool path, as functions of arc length: q(σ), q′, q″, q‴.

A ``path_tracking`` study optimises the *timing* of a path whose geometry is fixed. So the
inverse kinematics is solved once, when the problem is built, at nodes every ``spacing`` m of
arc length (:func:`legcore.ik.solve` with ``path=True``: warm-started, one continuous branch;
a closed form where the robot's family has one, the numerical solver otherwise), and each
segment's joint curve is interpolated by a quintic spline through its nodes — one spline per
segment, so that q″ may jump at a join where the path's curvature does. A candidate's motion
is then q(t) = Q(σ(t)) by the chain rule (:func:`legcore.trajectories.sampling.compose_time_law`),
with no IK in the optimisation loop::

    q̇ = Q′ σ̇,   q̈ = Q″ σ̇² + Q′ σ̈,   q⃛ = Q‴ σ̇³ + 3 Q″ σ̇ σ̈ + Q′ σ⃛

The interpolation is checked when it is built: forward kinematics of Q at the midpoints
between nodes must lie on the path to ``tol`` (m) and keep the tool orientation to ``tol``
(rad); a segment that does not is re-solved with half the spacing (up to three times). The
spline error shrinks as spacing⁶: at the default 2 mm it is ~1e-12 m on the seed 004 capsule.

:class:`ToolOrientation` states what the tool must keep while it runs the path: a fixed axis
(pointing down is the axis (0, 0, −1)), optionally a fixed heading about it, or nothing
(position only). Rest-posture redundancy (a 6- or 7-joint arm with the spin about the tool
axis free) is resolved by the numerical IK toward ``rest``, converged tightly (``null_tol``
1e-10 rad) so that Q is smooth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PPoly, make_interp_spline

from legcore.ik import solve
from legcore.ik.targets import IKSolution, task_errors
from legcore.kinematics import fk
from legcore.robots.model import Robot
from legcore.studies.path_tracking.kin import ArcLengthPath

__all__ = ["JointPath", "ToolOrientation", "check_slowest_speed", "joint_path", "speed_caps"]

FloatArray = NDArray[np.float64]

_DEGREE = 5  # quintic splines: C⁴ inside a segment, q‴ continuous for the jerk
_MIN_INTERVALS = 16  # spline intervals per segment at least
_REFINE = 3  # times a segment's spacing may be halved
_NULL_TOL = 1e-10  # rad: redundancy resolved this tightly (smooth Q for a redundant arm)
_MAX_NODES = 20_000  # IK nodes along the whole path at most (the spacing grows beyond)


@dataclass(frozen=True)
class ToolOrientation:
    """What the tool keeps along the path (world frame).

    ``axis``: unit direction (3,) of the tool z axis, fixed in the world; None: the orientation
    is free (position only). ``yaw`` (rad, only with an axis): the heading of the tool x axis
    about the axis, also fixed; None: the spin about the axis is free. The heading is measured
    from the world x axis projected on the plane normal to the axis, toward the projected world
    y axis (world y then z when the axis is nearly along x) — for a vertical tool, the heading
    in the world xy plane.
    """

    axis: tuple[float, float, float] | None
    yaw: float | None = None

    def __post_init__(self) -> None:
        if self.axis is None:
            if self.yaw is not None:
                raise ValueError("tool_yaw: a heading needs a tool axis (orientation 'free')")
            return
        a = np.asarray(self.axis, dtype=float)
        norm = float(np.linalg.norm(a))
        if a.shape != (3,) or not math.isfinite(norm) or norm < 1e-9:
            raise ValueError(f"tool_axis: must be a non-zero 3-vector, got {self.axis!r}")
        object.__setattr__(self, "axis", tuple(float(v) for v in a / norm))

    @property
    def task(self) -> str:
        """The IK task: ``"position"``, ``"axis"`` or ``"pose"``."""
        if self.axis is None:
            return "position"
        return "axis" if self.yaw is None else "pose"

    def rotation(self) -> FloatArray:
        """Tool rotation (3, 3) with z = ``axis`` and x at heading ``yaw`` (0 if None)."""
        if self.axis is None:
            raise ValueError("tool_axis: a free orientation has no rotation")
        z = np.asarray(self.axis)
        ex, ey, ez = np.eye(3)
        u, w = (ex, ey) if np.linalg.norm(ex - (ex @ z) * z) >= 0.5 else (ey, ez)
        x0 = u - (u @ z) * z
        x0 /= np.linalg.norm(x0)
        y0 = w - (w @ z) * z - (w @ x0) * x0
        y0 /= np.linalg.norm(y0)
        yaw = 0.0 if self.yaw is None else self.yaw
        x = math.cos(yaw) * x0 + math.sin(yaw) * y0
        return np.stack([x, np.cross(z, x), z], axis=-1)

    def targets(self, p: FloatArray) -> FloatArray:
        """IK targets of :attr:`task` for tool points ``p`` (N, 3) m."""
        p = np.asarray(p, dtype=float)
        if self.axis is None:
            return p
        if self.yaw is None:
            return np.concatenate([p, np.broadcast_to(self.axis, p.shape)], axis=-1)
        T = np.broadcast_to(np.eye(4), (*p.shape[:-1], 4, 4)).copy()
        T[..., :3, :3] = self.rotation()
        T[..., :3, 3] = p
        return T

    def errors(self, T: FloatArray, p: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(position error (N,) m, orientation error (N,) rad) of tool poses ``T`` (N, 4, 4)
        against points ``p`` (N, 3) and this orientation."""
        Rt = np.broadcast_to(np.eye(3) if self.axis is None else self.rotation(), T.shape[:-2]
                             + (3, 3))
        return task_errors(self.task, T, p, Rt)

    def describe(self) -> str:
        if self.axis is None:
            return "the tool orientation free"
        text = f"the tool axis along {np.round(self.axis, 6).tolist()}"
        return text if self.yaw is None else f"{text} at heading {self.yaw:.6g} rad"


@dataclass(frozen=True, eq=False)
class JointPath:
    """q(σ) (n joints) along a path of total length ``length`` (m), piecewise quintic.

    ``poly``: the piecewise polynomial (breaks in σ, m); ``sigma`` (N,) m and ``q`` (N, n) the
    IK nodes (joins appear twice: the end of a segment and the start of the next);
    ``segment`` (N,) the segment of each node; ``path_error`` m and ``orientation_error`` rad:
    the largest error of FK(Q) at the midpoints checked when built.
    """

    poly: PPoly
    sigma: FloatArray
    q: FloatArray
    segment: NDArray[np.int64]
    length: float
    path_error: float
    orientation_error: float

    def derivatives(self, sigma: FloatArray) -> FloatArray:
        """Q, Q′, Q″, Q‴ at arc lengths ``sigma`` (any shape S) → (4, *S, n) (rad, rad/m, …).

        At a break (a node, or a join) the values of the interval after it are returned.
        """
        s = np.asarray(sigma, dtype=float)
        flat = s.reshape(-1)
        out = np.stack([self.poly(flat, nu) for nu in range(4)])
        return out.reshape(4, *s.shape, out.shape[-1])


def _nodes(lengths: FloatArray, counts: NDArray[np.int64]) -> tuple[FloatArray, NDArray[np.int64]]:
    """Arc lengths of the nodes (each segment from its start to its end) and their segments."""
    start = np.concatenate([[0.0], np.cumsum(lengths)])
    sig = [start[k] + lengths[k] * np.linspace(0.0, 1.0, int(c) + 1) for k, c in enumerate(counts)]
    seg = [np.full(int(c) + 1, k) for k, c in enumerate(counts)]
    return np.concatenate(sig), np.concatenate(seg)


def _pieces(sig: FloatArray, q: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Quintic interpolating spline through (sig, q) of one segment as local polynomial
    coefficients: (breaks (m+1,), c (6, m, n)) in PPoly's order (highest power first)."""
    spl = make_interp_spline(sig, q, k=_DEGREE)
    c = np.stack([spl(sig[:-1], nu=_DEGREE - j) / math.factorial(_DEGREE - j)
                  for j in range(_DEGREE + 1)])
    return sig, c


def _check_reach(robot: Robot, p: FloatArray, seg: NDArray[np.int64]) -> None:
    """ValueError naming the first point ``p`` (N, 3) farther from the arm's first joint than
    the arm can ever reach (the sum of its link offsets and prismatic travels)."""
    c = robot.chain
    travel = np.where(c.prismatic, np.maximum(np.abs(robot.q_min), np.abs(robot.q_max)), 0.0)
    reach = float(np.linalg.norm(c.p[1:], axis=-1).sum() + np.linalg.norm(c.tool_p)
                  + travel.sum())
    d = np.linalg.norm(p - c.p[0], axis=-1)
    far = np.flatnonzero(d > reach * (1.0 + 1e-9))
    if far.size:
        i = int(far[0])
        raise ValueError(
            f"segments.{seg[i]}: tool point {np.round(p[i], 4).tolist()} m is {d[i]:.3g} m from "
            f"the first joint of {robot.name}, beyond its reach ({reach:.3g} m)"
        )


def _check_solution(
    robot: Robot, tool: ToolOrientation, sol: IKSolution, seg: NDArray[np.int64], p: FloatArray,
    flips: bool = True,
) -> None:
    """ValueError naming the first node out of reach, or (``flips``) where the IK jumps
    branch."""

    def at(i: int) -> str:
        return f"segments.{seg[i]}: tool point {np.round(p[i], 4).tolist()} m"

    bad = np.flatnonzero(~sol.reachable)
    if bad.size:
        raise ValueError(f"{at(int(bad[0]))} is out of reach of {robot.name} with "
                         f"{tool.describe()} (inside its joint limits)")
    jumps = np.flatnonzero(sol.flip) if flips else np.zeros(0, dtype=np.int64)
    if jumps.size:
        i = int(jumps[0])
        jump = float(np.abs(sol.q[i] - sol.q[i - 1]).max())
        raise ValueError(
            f"{at(i)}: {robot.name} must jump {jump:.3g} rad to another IK branch there (a "
            f"singularity or a joint limit on the way); change the path or the rest posture"
        )


def joint_path(
    robot: Robot,
    path: ArcLengthPath,
    tool: ToolOrientation,
    rest: FloatArray,
    *,
    spacing: float = 2e-3,
    tol: float = 1e-8,
) -> JointPath:
    """Solve and interpolate the joints of ``robot`` along ``path`` (see the module docstring).

    ``rest`` (n,) rad: the IK starts the path from this posture (its branch is followed) and a
    redundant arm is pulled toward it. ``spacing`` (m): node spacing (at least 16 intervals per
    segment, at most 20 000 nodes in all). ``tol``: m and rad, accuracy of the interpolated
    motion. Raises ``ValueError`` naming the segment (``segments.k: …``) where the path leaves
    the reachable workspace (inside the joint limits), where the arm would have to jump to
    another IK branch, or where the joints cannot be interpolated to ``tol`` (a singularity).
    """
    D = path.lengths
    # cheap checks first (a user's path is checked before any dense IK): every point within
    # the arm's reach, then a coarse IK pass of 16 intervals per segment
    sig, seg = _nodes(D, np.full(D.size, _MIN_INTERVALS))
    p = path.derivatives(sig)[0]
    _check_reach(robot, p, seg)
    coarse = solve(robot, tool.targets(p), tool.task, q0=rest, rest=rest, path=True)
    _check_solution(robot, tool, coarse, seg, p, flips=False)
    spacing = max(spacing, float(D.sum()) / _MAX_NODES)
    counts = np.maximum(_MIN_INTERVALS, np.ceil(D / spacing)).astype(np.int64)
    for attempt in range(_REFINE + 1):
        sig, seg = _nodes(D, counts)
        p = path.derivatives(sig)[0]
        sol = solve(robot, tool.targets(p), tool.task, q0=rest, rest=rest, path=True,
                    null_tol=_NULL_TOL)
        _check_solution(robot, tool, sol, seg, p)
        breaks, coeffs = [], []
        for k in range(D.size):
            b, c = _pieces(sig[seg == k], sol.q[seg == k])
            breaks.append(b[:-1])
            coeffs.append(c)
        poly = PPoly(np.concatenate(coeffs, axis=1), np.append(np.concatenate(breaks), sig[-1]))
        # check between the nodes: FK of the interpolated joints on the path
        mid = 0.5 * (sig[1:] + sig[:-1])
        inner = seg[1:] == seg[:-1]
        mid, mseg = mid[inner], seg[1:][inner]
        e_p, e_r = tool.errors(fk(robot, poly(mid)), path.derivatives(mid)[0])
        err = np.maximum(e_p, e_r)
        worse = np.unique(mseg[err > tol])
        if worse.size == 0:
            return JointPath(poly, sig, sol.q, seg, float(sig[-1]), float(e_p.max()),
                             float(e_r.max()))
        if attempt == _REFINE:
            i = int(np.argmax(err))
            raise ValueError(
                f"segments.{mseg[i]}: the joints of {robot.name} change too fast near tool point "
                f"{np.round(path.derivatives(mid[i:i + 1])[0][0], 4).tolist()} m to follow the "
                f"path to {tol:g} (error {err[i]:.2g}; a singularity is near)"
            )
        counts[worse] *= 2
    raise AssertionError("unreachable")  # pragma: no cover


def speed_caps(jp: JointPath, qd_max: FloatArray, V_bounds: tuple[float, float]) -> FloatArray:
    """Per segment (n,), the upper bound of its cruise speed in the decision box (m/s):
    ``V_bounds[1]``, lowered to the largest tool speed at which every joint keeps its speed
    limit ``qd_max`` (n_joints,) at *some* node of the segment (+1 %). A cruise speed is reached
    somewhere on its segment, so a faster one breaks a limit there: no feasible law is cut off."""
    dq = np.abs(jp.derivatives(jp.sigma)[1])  # rad per m of path, (N, n)
    with np.errstate(divide="ignore"):
        v = np.min(qd_max / dq, axis=1)  # (N,) fastest speed at each node
    caps = np.array([v[jp.segment == k].max() for k in range(int(jp.segment.max()) + 1)])
    return np.clip(1.01 * caps, V_bounds[0], V_bounds[1])


def check_slowest_speed(jp: JointPath, path: ArcLengthPath, robot: Robot, v_min: float) -> None:
    """ValueError unless, at tool speed ``v_min`` (m/s), every joint keeps its speed limit at
    every node of the path — otherwise no law can run it (a singularity is near)."""
    dq = np.abs(jp.derivatives(jp.sigma)[1])  # rad per m of path
    over = dq * v_min / robot.qd_max
    if over.max() > 1.0:
        i, j = (int(v) for v in np.unravel_index(int(np.argmax(over)), over.shape))
        p = path.derivatives(jp.sigma[i:i + 1])[0][0]
        raise ValueError(
            f"segments.{jp.segment[i]}: at tool point {np.round(p, 4).tolist()} m joint "
            f"{robot.model.names[j + 1]} of {robot.name} turns {dq[i, j]:.3g} rad per m of "
            f"path: even at the slowest speed V_bounds[0] = {v_min:g} m/s it would exceed its "
            f"speed limit {robot.qd_max[j]:g} rad/s (a singularity is near)"
        )
