"""A leg's own geometry, for the robot-relative defaults of ``swing_energy``
(:mod:`legcore.studies.swing_energy.defaults`): which leg swings, the body's axes in its base
frame, its length, its knee branch and its nominal stance.

Frames. A leg of a legged robot has its base frame at the hip; the body's forward axis is its
``meta["forward"]`` (default x, :mod:`legcore.robots.legged`), expressed in the leg's base frame
through the hip's rotation. A plain serial chain is taken as a leg whose base frame is the body
frame (x forward, z up) — or, when its foot at home lies out to the side by more than half its
length (a leg mounted on the side of a body, as seed 000's hexapod leg), stepping across that
reach (:func:`leg_forward`). Up is +z of the base frame (the study refuses a leg whose gravity
is not
along −z).

- :func:`front_leg` — the first front leg of a legged robot: the legs whose hips lie furthest
  forward (within 1 mm), the first of them in the robot's order.
- :func:`hip_index` — the hip's pitch joint: the second joint (after the hip's abduction or
  yaw joint) of a leg of 3 or more joints, the first of a 2-joint leg.
- :func:`leg_length` — ``L``: the stretched leg below the hip, the largest distance from the
  hip's pitch joint to the foot over the joints after it, joint limits ignored.
- :func:`bend` — how a posture bends: the offset ``o`` (m) of the knee (the joint after the
  hip's pitch joint furthest from the line from that joint to the foot) from that line, signed
  as ``o·(up − forward)``: > 0 when the knee lies behind the line (a knee that points backward)
  or, for a leg bending sideways, above it.
- :func:`reference_posture` — the posture that names the leg's own knee branch: its home posture
  (inside the limits) when that is bent, else the home posture bent 0.3 rad by the joint that
  bends it most toward the body's centre (:func:`knee_toward_centre`: a front leg's knee
  behind, a rear leg's ahead, as ``quadruped_gait`` stands; a serial chain's behind).
- :func:`branch_of` / :func:`solve_on_branch` — the knee branch of a target: the IK solutions
  inside the joint limits from about 3n starts (the reference posture, ± 0.6 rad on each
  joint, each knee mirrored); the branch is the only one found (the joint limits force it),
  else the reference posture's bend; the solution on it nearest the reference posture (then
  the stance posture).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray
from scipy.optimize import minimize

from legcore.ik import solve
from legcore.kinematics import fk, fk_jacobian
from legcore.robots.legged import LeggedRobot
from legcore.robots.model import Robot

__all__ = [
    "BEND_TOL",
    "Branch",
    "bend",
    "body_forward",
    "branch_of",
    "front_leg",
    "hip_index",
    "joint_origins",
    "knee_toward_centre",
    "leg_forward",
    "leg_length",
    "reference_posture",
    "sigma_min",
    "solve_on_branch",
]

FloatArray = NDArray[np.float64]

#: A posture whose knee is within this fraction of the leg length of the hip–foot line is
#: straight (its bend names no branch).
BEND_TOL = 0.01
#: How far (rad) a straight home posture is bent to name the conventional branch.
BEND_PROBE = 0.3
#: The extra starts of the branch search, rad from the reference posture, per joint.
SEED_STEP = 0.6
_UP = np.array([0.0, 0.0, 1.0])
#: A serial chain whose foot lies out to the side at home by more than this × its length is a
#: leg mounted on the side of a body: it steps across that reach (:func:`leg_forward`).
SIDEWAYS = 0.5


def body_forward(robot: LeggedRobot) -> FloatArray:
    """The body's forward axis (3,) in its body frame: ``meta["forward"]`` or x."""
    f = (robot.meta or {}).get("forward", (1.0, 0.0, 0.0))
    v = np.asarray(f, dtype=float)
    return v / float(np.linalg.norm(v))


def front_leg(robot: LeggedRobot) -> tuple[str, str]:
    """``(leg name, rule in words)``: the first front leg — of the legs whose hips lie furthest
    forward along the body's forward axis (within 1 mm), the first in the robot's order."""
    f = body_forward(robot)
    ahead = np.array([float(np.asarray(g.hip)[:3, 3] @ f) for g in robot.legs])
    front = [g.name for g, a in zip(robot.legs, ahead, strict=True) if a >= ahead.max() - 1e-3]
    axis = "x" if np.allclose(f, [1.0, 0.0, 0.0]) else f"{f.round(3).tolist()}"
    rule = (f"the first front leg: the hips of {front} lie furthest forward along the body's "
            f"forward axis {axis} ({ahead.max():.4g} m), {front[0]} comes first")
    return front[0], rule


def leg_forward(robot: object, leg: str | None, L: float | None = None) -> FloatArray:
    """The body's forward axis (3,) in the base frame of the leg that swings: the leg ``leg`` of
    a legged robot (through its hip's rotation, made horizontal); for a serial chain of length
    ``L`` (m) x — unless its foot at home lies out to the side by more than
    :data:`SIDEWAYS` × L (a leg mounted on the side of a body, as a hexapod's or seed 000's):
    then the horizontal direction across that reach (+x, else +y, when it is one of them)."""
    if isinstance(robot, LeggedRobot) and leg is not None:
        R = np.asarray(robot.leg(leg).hip, dtype=float)[:3, :3]
        f = R.T @ body_forward(robot)
        f = f - (f @ _UP) * _UP
        n = float(np.linalg.norm(f))
        if n > 1e-9:
            return f / n
    if isinstance(robot, Robot) and L is not None:
        foot = fk(robot, np.clip(robot.home, robot.q_min, robot.q_max))[:3, 3]
        out = foot - (foot @ _UP) * _UP
        reach = float(np.linalg.norm(out))
        if reach > SIDEWAYS * L:
            f = np.cross(_UP, out / reach)
            flip = f[0] < -1e-9 or (abs(f[0]) <= 1e-9 and f[1] < 0.0)
            return -f if flip else f
    return np.array([1.0, 0.0, 0.0])


def hip_index(chain: Robot) -> int:
    """Index (0-based) of the hip's pitch joint: the second joint of a leg of 3 or more joints
    (after the hip's abduction or yaw joint), the first of a 2-joint leg."""
    return 1 if chain.nq >= 3 else 0


def knee_toward_centre(robot: object, leg: str | None) -> int:
    """The conventional knee side of a straight leg: toward the body's centre — +1 (behind the
    hip–foot line) for a leg whose hip is ahead of the body's centre (or a serial chain), −1
    (ahead of it) for a rear leg — as :mod:`legcore.studies.quadruped_gait` stands."""
    if isinstance(robot, LeggedRobot) and leg is not None:
        ahead = float(np.asarray(robot.leg(leg).hip, dtype=float)[:3, 3] @ body_forward(robot))
        return 1 if ahead >= 0.0 else -1
    return 1


def leg_length(chain: Robot) -> float:
    """``L`` (m): the stretched leg below the hip — the largest distance from the hip's pitch
    joint (:func:`hip_index`) to the foot over the joints after it, limits ignored. Local
    maximisation (L-BFGS-B, analytic gradient) from zero, the home posture and 8 Halton
    starts; the joints before the hip's pitch joint (which do not change the distance) at 0."""
    from legcore.ik.numeric import halton_seeds

    n, a = chain.nq, hip_index(chain)
    q = np.zeros(n)
    hip = joint_origins(chain, q)[0, a]

    def neg(z: FloatArray) -> tuple[float, FloatArray]:
        q[a:] = z
        T, J = fk_jacobian(chain, q)
        d = T[:3, 3] - hip
        return -float(d @ d), -2.0 * (d @ J[:3, a:])

    m = n - a
    starts = [np.zeros(m), np.asarray(chain.home, dtype=float)[a:]]
    starts += list(halton_seeds(8, np.full(m, -math.pi), np.full(m, math.pi), np.zeros(m)))
    best = 0.0
    for z0 in starts:
        res = minimize(neg, z0, jac=True, method="L-BFGS-B", options={"maxiter": 200})
        best = max(best, -float(res.fun), -neg(z0)[0])
    return math.sqrt(best)


def joint_origins(chain: Robot, Q: FloatArray) -> FloatArray:
    """World positions (B, n, 3) m of the joints (points on their axes: Pinocchio's joint
    frames) of postures ``Q`` (B, n)."""
    model, data = chain.model, chain.data()
    Q = np.atleast_2d(np.asarray(Q, dtype=float))
    out = np.empty((Q.shape[0], chain.nq, 3))
    for b, q in enumerate(Q):
        pin.forwardKinematics(model, data, q)
        out[b] = [data.oMi[j].translation for j in range(1, chain.nq + 1)]
    return out


def bend(chain: Robot, q: FloatArray, forward: FloatArray) -> FloatArray:
    """Signed bend (B,) m of postures ``q`` (B, n) or (n,). The knee is the joint after the
    hip's pitch joint (the second joint; the first of a 2-joint leg) furthest from the line from
    that joint to the foot, and ``o`` its offset from the line; the bend is ``o·(up − forward)``:
    > 0 when the knee lies behind the line (or, for a leg bending sideways, above it), < 0 in
    front of (below) it, 0 for a straight leg."""
    Q = np.atleast_2d(np.asarray(q, dtype=float))
    J = joint_origins(chain, Q)  # (B, n, 3)
    foot = fk(chain, Q)[:, :3, 3]
    a = hip_index(chain)
    d = foot - J[:, a]
    norm = np.linalg.norm(d, axis=-1)
    dh = d / np.where(norm > 1e-12, norm, 1.0)[:, None]
    r = J[:, a + 1:] - J[:, a:a + 1]  # (B, m, 3)
    o = r - np.einsum("bmk,bk->bm", r, dh)[..., None] * dh[:, None, :]
    k = np.argmax(np.linalg.norm(o, axis=-1), axis=-1)
    ok = np.take_along_axis(o, k[:, None, None], axis=1)[:, 0]  # (B, 3)
    out = ok @ (_UP - forward)
    return np.where(norm > 1e-12, out, 0.0)


def sigma_min(chain: Robot, q: FloatArray) -> float:
    """Smallest singular value (m/rad) of the foot's position Jacobian at ``q`` (of its
    min(3, n) largest): near 0 at a singular (stretched or folded) posture."""
    J = fk_jacobian(chain, np.asarray(q, dtype=float))[1][:3]
    s = np.linalg.svd(J, compute_uv=False)
    return float(s[min(3, chain.nq) - 1])


@dataclass(frozen=True)
class Branch:
    """A leg's knee branch: ``sign`` +1 (knee behind the hip–foot line), −1 (ahead of it);
    ``reference`` (n,) rad, the posture that names it; ``why``: the rule, in words."""

    sign: int
    reference: FloatArray
    why: str


def reference_posture(chain: Robot, forward: FloatArray, L: float, prefer: int = 1
                      ) -> tuple[FloatArray, str]:
    """The posture that names the leg's own branch, and how it was found (module docstring):
    the home posture inside the limits when it is bent (more than 1 % of ``L`` off the
    hip–foot line), else the home posture bent by :data:`BEND_PROBE` rad by the joint and sign
    that bend it most to the side ``prefer`` (+1: knee behind, −1: ahead;
    :func:`knee_toward_centre`)."""
    home = np.clip(np.asarray(chain.home, dtype=float), chain.q_min, chain.q_max)
    b = float(bend(chain, home, forward)[0])
    if abs(b) > BEND_TOL * L:
        side = "behind" if b > 0 else "ahead of"
        return home, f"its home posture's, knee {side} the hip–foot line"
    probes = []
    for j in range(chain.nq):
        for sgn in (1.0, -1.0):
            q = home.copy()
            q[j] = np.clip(q[j] + sgn * BEND_PROBE, chain.q_min[j], chain.q_max[j])
            probes.append(q)
    Q = np.stack(probes)
    bends = prefer * bend(chain, Q, forward)
    i = int(np.argmax(bends))
    side = "behind" if prefer > 0 else "ahead of"
    if bends[i] > BEND_TOL * L:
        return Q[i], (f"its home posture is straight: knee toward the body's centre, {side} the "
                      "hip–foot line (convention)")
    return home, "its home posture's (straight, and no joint bends it)"


def _candidates(chain: Robot, target: FloatArray, reference: FloatArray) -> FloatArray:
    """IK solutions (m, n) inside the joint limits of the foot position ``target`` (3,), from the
    reference posture, the reference ± :data:`SEED_STEP` rad per joint, and the reference with
    each joint after the hip's pitch joint mirrored (−q: the knee bent the other way);
    duplicates merged."""
    n = chain.nq
    seeds = [reference]
    for j in range(n):
        for sgn in (1.0, -1.0):
            q = reference.copy()
            q[j] = np.clip(q[j] + sgn * SEED_STEP, chain.q_min[j], chain.q_max[j])
            seeds.append(q)
    for j in range(hip_index(chain) + 1, n):  # each knee bent the other way
        q = reference.copy()
        q[j] = np.clip(-q[j], chain.q_min[j], chain.q_max[j])
        seeds.append(q)
    Q0 = np.stack(seeds)
    targets = np.tile(np.asarray(target, dtype=float), (len(seeds), 1))
    sol = solve(chain, targets, "position", q0=Q0, rest=reference, method="numeric")
    found = np.asarray(sol.q)[np.asarray(sol.reachable)]
    out: list[FloatArray] = []
    for q in found:
        if not any(np.allclose(q, r, atol=1e-6) for r in out):
            out.append(q)
    return np.array(out).reshape(-1, n)


def branch_of(chain: Robot, target: FloatArray, forward: FloatArray, L: float,
              prefer: int = 1) -> tuple[Branch, FloatArray] | None:
    """The leg's own knee branch and the posture on it that puts the foot at ``target`` (the
    nominal stance), or None when no posture inside the limits reaches it (module docstring:
    the only branch the joint limits leave, else the home posture's bend, else the knee toward
    the body's centre, ``prefer``)."""
    reference, why = reference_posture(chain, forward, L, prefer)
    Q = _candidates(chain, np.asarray(target, dtype=float), reference)
    if Q.shape[0] == 0:
        return None
    b = bend(chain, Q, forward)
    signs = {int(np.sign(v)) for v in b if abs(v) > BEND_TOL * L}
    if len(signs) == 1:
        sign = signs.pop()
        why = "the only one the IK finds inside the joint limits"
    elif len(signs) == 0:
        sign = 0
        why = "straight (no branch)"
    else:
        ref_bend = float(bend(chain, reference, forward)[0])
        sign = 1 if ref_bend >= 0 else -1
    keep = np.sign(b) == sign if sign else np.ones(len(b), dtype=bool)
    Qk = Q[keep]
    i = int(np.argmin(np.linalg.norm(Qk - reference, axis=1)))
    return Branch(sign, reference, why), Qk[i]


def solve_on_branch(chain: Robot, target: FloatArray, branch: Branch, start: FloatArray,
                    forward: FloatArray, L: float) -> FloatArray | None:
    """The posture (n,) on ``branch`` that puts the foot at ``target``, nearest ``start`` (the
    stance posture), or None when none inside the limits reaches it."""
    Q = _candidates(chain, np.asarray(target, dtype=float), np.asarray(start, dtype=float))
    if Q.shape[0] == 0:
        return None
    if branch.sign:
        b = bend(chain, Q, forward)
        Q = Q[np.sign(b) == branch.sign]
        if Q.shape[0] == 0:
            return None
    return Q[int(np.argmin(np.linalg.norm(Q - start, axis=1)))]
