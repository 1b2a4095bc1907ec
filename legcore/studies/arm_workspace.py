"""Where an arm is well conditioned, and how far it reaches: the workspace analysis that the arm
study kinds (``path_tracking``, ``path_placement``) derive their default tasks from.

Everything comes from the robot model by sampled forward kinematics (one vectorised pass over a
Halton set of configurations) and a few batched IK solves — no per-sample Python loop:

- :func:`arm_workspace` — the arm's *frame* (its shoulder: the point of joint 1's axis nearest
  joint 2 at home; ``up`` against gravity; ``forward``: the horizontal direction from the base
  axis toward the tool at home) and its *reach* (the largest distance of the tool point from
  the shoulder over :data:`SAMPLES` configurations inside the joint limits, joint 1 held at
  home), with each sample's tool point, tool axis, joint-limit margin and *dexterity*;
- :func:`dexterity` — the smallest singular value of the arm's *task* Jacobian, dimensionless:
  the tool point's rows divided by the reach L (a characteristic length) and, for a task that
  holds a tool axis a, the two rotation rows that tilt a (``(I − a aᵀ) ω``). 0 at a singularity
  of the task; ≈ 1 when every task direction moves as easily as a joint turning the whole
  reach. It is the conditioning the path following needs: joint rates are ≤ (tool speed / L) /
  dexterity;
- :func:`limit_margin` — the distance of each joint to its nearest limit as a fraction of its
  range (one turn at most);
- :func:`centres` — configurations that hold a tool axis (or none) at their tool point, ranked
  by dexterity among those keeping :data:`MIN_MARGIN` of every joint range free: the
  well-conditioned part of the workspace for that tool orientation. Candidates are the most
  dexterous samples whose tool axis is nearest the asked one, each moved onto the axis by a
  batched numerical IK started from it.

A robot's analysis is cached (robots are immutable), so the pre-flight check of a study kind
and the listings (``legcore.studies.fit``) pay for it once: ~10-30 ms per arm.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from legcore.ik import solve
from legcore.ik.numeric import halton_seeds
from legcore.kinematics import fk_jacobian, jacobian
from legcore.robots.model import Robot

__all__ = [
    "MIN_MARGIN",
    "SAMPLES",
    "ArmWorkspace",
    "Centre",
    "arm_workspace",
    "centres",
    "dexterity",
    "limit_margin",
    "plane_basis",
]

FloatArray = NDArray[np.float64]

#: Configurations sampled per arm (Halton, inside the joint limits, joint 1 at home).
SAMPLES = 2048
#: Joint-limit margin a well-conditioned configuration keeps on every joint (fraction of range).
MIN_MARGIN = 0.1
#: Candidate configurations moved onto a tool axis per orientation (:func:`centres`).
CANDIDATES = 32

_CACHE: weakref.WeakKeyDictionary[Robot, ArmWorkspace] = weakref.WeakKeyDictionary()


@dataclass(frozen=True, eq=False)
class ArmWorkspace:
    """The sampled workspace of an arm (world frame, SI units).

    ``shoulder`` (3,) m; ``up`` (3,) unit vector against gravity; ``forward`` (3,) unit,
    horizontal (⊥ ``up``), from joint 1's axis toward the tool at home; ``axis1`` (3,) joint 1's
    axis (unit, world, at home); ``reach`` m: the
    largest distance of the tool point from the shoulder over the samples. Samples: ``q``
    (N, n) rad, tool points ``p`` (N, 3) m, tool axes ``z`` (N, 3), ``margin`` (N,) (see
    :func:`limit_margin`) and ``dexterity`` (N,) of the position task (see :func:`dexterity`).
    """

    shoulder: FloatArray
    up: FloatArray
    forward: FloatArray
    axis1: FloatArray
    reach: float
    q: FloatArray
    p: FloatArray
    z: FloatArray
    margin: FloatArray
    dexterity: FloatArray

    @property
    def down(self) -> FloatArray:
        """The direction of gravity (3,), unit."""
        return -self.up

    def radial(self, p: ArrayLike) -> FloatArray:
        """Unit horizontal direction (…, 3) from the vertical through the shoulder toward the
        points ``p`` (…, 3); ``forward`` where a point is on that vertical."""
        d = np.asarray(p, dtype=float) - self.shoulder
        h = d - (d @ self.up)[..., None] * self.up
        norm = np.linalg.norm(h, axis=-1, keepdims=True)
        return np.where(norm > 1e-9 * self.reach, h / np.maximum(norm, 1e-300), self.forward)


@dataclass(frozen=True)
class Centre:
    """A well-conditioned configuration ``q`` (n,) rad holding tool ``axis`` (3,) (None: any)
    at tool point ``p`` (3,) m, with its task ``dexterity`` and joint-limit ``margin``."""

    q: FloatArray
    p: FloatArray
    axis: FloatArray | None
    dexterity: float
    margin: float


def limit_margin(robot: Robot, q: ArrayLike) -> FloatArray:
    """(…,) the smallest distance of a joint of ``q`` (…, n) to its nearest limit, as a fraction
    of its range (ranges longer than one turn count as one turn: such a joint has room)."""
    q = np.asarray(q, dtype=float)
    span = np.minimum(robot.q_max - robot.q_min, 2.0 * math.pi)
    room = np.minimum(q - robot.q_min, robot.q_max - q)
    room = np.where(robot.q_max - robot.q_min > 2.0 * math.pi, np.maximum(room, 0.5 * span), room)
    return np.asarray(np.min(room / span, axis=-1))


def dexterity(robot: Robot, q: ArrayLike, axis: ArrayLike | None, reach: float,
              plane: ArrayLike | None = None, J: FloatArray | None = None) -> FloatArray:
    """(…,) how easily the tool moves at ``q`` (…, n) in the directions of ``plane`` (3, k),
    holding tool ``axis`` (3,) (None: any orientation) — dimensionless (module docstring).

    The joint rates that move the tool point at velocity v while the axis does not tilt are
    q̇ = A⁺ [v; 0], with A the tool point's rows of the Jacobian and, with an axis, the two
    rows of the angular velocity about the directions ⊥ the axis (the least-norm solution, a
    structurally dependent row — e.g. a 5-joint arm's roll about the tool axis — dropped).
    The dexterity is ``1 / (reach · max‖A⁺ [v; 0]‖)`` over unit v in the span of ``plane``
    (default: every direction, then it is σ_min of the tool point's Jacobian over ``reach``):
    1 when moving the tool at 1 m/s needs joint rates of 1/reach rad/s, 0 at a singularity or
    where some v cannot be followed while keeping the axis. ``J``: the tool Jacobian (…, 6, n)
    if already computed."""
    J = jacobian(robot, q) if J is None else J
    rows = [J[..., :3, :]]
    if axis is not None:
        a = np.asarray(axis, dtype=float)
        a = a / np.linalg.norm(a)
        e = np.eye(3)[int(np.argmin(np.abs(a)))]
        b1 = np.cross(a, e)
        b1 /= np.linalg.norm(b1)
        b2 = np.cross(a, b1)  # rotations about b1, b2 tilt the axis
        rows.append(np.einsum("i,...in->...n", b1, J[..., 3:, :])[..., None, :])
        rows.append(np.einsum("i,...in->...n", b2, J[..., 3:, :])[..., None, :])
    A = np.concatenate(rows, axis=-2)  # (…, m, n)
    B = np.eye(3) if plane is None else np.asarray(plane, dtype=float).reshape(3, -1)
    Bm = np.zeros((A.shape[-2], B.shape[1]))
    Bm[:3] = B
    G = np.linalg.pinv(A, rcond=1e-9) @ Bm  # (…, n, k) joint rates per tool speed
    followed = np.abs(A @ G - Bm).max(axis=(-2, -1)) <= 1e-6
    gain = np.linalg.svd(G, compute_uv=False)[..., 0]
    with np.errstate(divide="ignore"):
        d = np.where(followed & (gain > 0.0), 1.0 / (reach * gain), 0.0)
    return np.asarray(d)


def plane_basis(normal: ArrayLike) -> FloatArray:
    """(3, 2) orthonormal basis of the plane ⊥ ``normal`` (3,)."""
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    e = np.eye(3)[int(np.argmin(np.abs(n)))]
    b1 = np.cross(n, e)
    b1 /= np.linalg.norm(b1)
    return np.stack([b1, np.cross(n, b1)], axis=1)


def _frame(robot: Robot) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """(shoulder, up, forward, joint 1's axis) of ``robot`` at home (:class:`ArmWorkspace`)."""
    model, data = robot.model, robot.model.createData()
    pin.forwardKinematics(model, data, robot.home)
    o1 = np.asarray(data.oMi[1].translation)
    a1 = np.asarray(data.oMi[1].rotation) @ robot.chain.axis[0]
    o2 = np.asarray(data.oMi[2].translation) if robot.nq > 1 else o1
    shoulder = o1 + a1 * float((o2 - o1) @ a1)
    g = np.asarray(robot.chain.gravity, dtype=float)
    up = -g / np.linalg.norm(g) if np.linalg.norm(g) > 0.0 else np.array([0.0, 0.0, 1.0])
    tool = fk_jacobian(robot, robot.home)[0][:3, 3]
    forward = np.zeros(3)
    for d in (tool - shoulder, o2 - o1, np.eye(3)[0], np.eye(3)[1]):
        h = d - (d @ up) * up
        if np.linalg.norm(h) > 1e-6:
            forward = h / np.linalg.norm(h)
            break
    return shoulder, up, forward, a1 / np.linalg.norm(a1)


def arm_workspace(robot: Robot) -> ArmWorkspace:
    """The sampled workspace of ``robot`` (see :class:`ArmWorkspace`; cached per robot)."""
    hit = _CACHE.get(robot)
    if hit is not None:
        return hit
    shoulder, up, forward, axis1 = _frame(robot)
    q = halton_seeds(SAMPLES, robot.q_min, robot.q_max, robot.home)
    q[:, 0] = robot.home[0]
    T, J = fk_jacobian(robot, q)
    p = T[:, :3, 3]
    reach = float(max(np.linalg.norm(p - shoulder, axis=-1).max(),
                      np.linalg.norm(T[0, :3, 3] - shoulder)))
    ws = ArmWorkspace(
        shoulder=shoulder, up=up, forward=forward, axis1=axis1, reach=reach, q=q, p=p,
        z=T[:, :3, 2].copy(), margin=_inner_margin(robot, q),
        dexterity=dexterity(robot, q, None, reach, J=J),
    )
    _CACHE[robot] = ws
    return ws


def _inner_margin(robot: Robot, q: FloatArray) -> FloatArray:
    """:func:`limit_margin` of the joints after the first (joint 1 turns the whole arm: the
    path's azimuth, not its conditioning)."""
    if robot.nq < 2:
        return limit_margin(robot, q)
    lo, hi = robot.q_min[1:], robot.q_max[1:]
    span = np.minimum(hi - lo, 2.0 * math.pi)
    room = np.minimum(q[:, 1:] - lo, hi - q[:, 1:])
    room = np.where(hi - lo > 2.0 * math.pi, np.maximum(room, 0.5 * span), room)
    return np.asarray(np.min(room / span, axis=-1))


def _face_forward(robot: Robot, ws: ArmWorkspace, q: FloatArray, p: FloatArray) -> tuple[
        FloatArray, FloatArray]:
    """Configurations ``q`` (N, n) and tool points ``p`` (N, 3) turned about joint 1's axis so
    that each point lies in the ``forward`` direction (in front of the arm, where its tool is at
    home) — when joint 1's axis is vertical (turning about it changes neither a vertical tool
    axis nor the conditioning) and its limits keep :data:`MIN_MARGIN` of its range free."""
    a1 = ws.axis1
    if abs(float(a1 @ ws.up)) < 1.0 - 1e-9:
        return q, p
    r = ws.radial(p)
    ang = np.arctan2(np.cross(r, ws.forward) @ ws.up, r @ ws.forward) * float(a1 @ ws.up)
    q1 = q[:, 0] + ang
    lo, hi = robot.q_min[0], robot.q_max[0]
    room = MIN_MARGIN * min(hi - lo, 2.0 * math.pi)
    ok = (q1 >= lo + room) & (q1 <= hi - room)
    if not ok.any():
        return q, p
    q = q.copy()
    q[ok, 0] = q1[ok]
    c, s = np.cos(ang * float(a1 @ ws.up)), np.sin(ang * float(a1 @ ws.up))
    d = p - ws.shoulder
    h = d @ ws.up
    u = d - h[:, None] * ws.up
    rot = (c[:, None] * u + s[:, None] * np.cross(ws.up, u) + h[:, None] * ws.up
           + ws.shoulder)
    return q, np.where(ok[:, None], rot, p)


def centres(robot: Robot, axis: ArrayLike | None, normal: ArrayLike | None = None,
            count: int = CANDIDATES) -> list[Centre]:
    """Well-conditioned configurations holding tool ``axis`` (3,) (None: position only), best
    first by their :func:`dexterity` for moves in the plane ⊥ ``normal`` (default: ``axis``,
    or for a free orientation the horizontal plane). Each keeps :data:`MIN_MARGIN` of every
    joint range free (joint 1 aside) and holds its axis to 1e-9 rad; the list is empty when
    the arm can hold the axis nowhere it was looked for."""
    ws = arm_workspace(robot)
    ok = ws.margin >= MIN_MARGIN
    if not ok.any():
        ok = ws.margin >= 0.5 * ws.margin.max()
    idx = np.flatnonzero(ok)
    n = ws.up if normal is None and axis is None else np.asarray(
        axis if normal is None else normal, dtype=float)
    B = plane_basis(n)
    if axis is None:
        cand = idx[np.argsort(-ws.dexterity[idx], kind="stable")[:4 * count]]
        q, p = ws.q[cand], ws.p[cand]
        a = None
    else:
        a = np.asarray(axis, dtype=float)
        a = a / np.linalg.norm(a)
        # the dexterous half of the samples, those whose tool axis is nearest ``a`` first
        top = idx[ws.dexterity[idx] >= np.quantile(ws.dexterity[idx], 0.5)]
        near = top[np.argsort(-(ws.z[top] @ a), kind="stable")[:count]]
        targets = np.concatenate([ws.p[near], np.broadcast_to(a, (near.size, 3))], axis=1)
        sol = solve(robot, targets, "axis", q0=ws.q[near], rest=robot.home, restarts=2)
        if not sol.reachable.any():
            return []
        q, p = sol.q[sol.reachable], ws.p[near][sol.reachable]
    if a is None or abs(float(a @ ws.up)) > 1.0 - 1e-12:
        q, p = _face_forward(robot, ws, q, p)
    d = dexterity(robot, q, a, ws.reach, B)
    m = _inner_margin(robot, q)
    keep = (m >= MIN_MARGIN) & (d > 0.0)
    if not keep.any():
        keep = (m >= 0.5 * m.max()) & (d > 0.0)
    order = np.flatnonzero(keep)[np.argsort(-d[keep], kind="stable")][:count]
    return [Centre(q[i].copy(), p[i].copy(), a, float(d[i]), float(m[i])) for i in order]
