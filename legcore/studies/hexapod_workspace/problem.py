"""``hexapod_workspace`` — seed 002: MOEA/D workspace of a hexapod in tripod gait.

Source: seed 002 (Domínguez, Sepúlveda, Montiel, Castillo), §3.1 eqs (11)–(14), §4, Table 2,
Figs 6–9; robot ``citedi_hexapod`` (see its catalog docstring and docs/legged.md).

Any hexapod with 3-joint legs, three on each side of the walking axis: the catalog's, one from
URDF, or a parametric one (``hexapod``: leg lengths and hip layout,
:mod:`legcore.studies.hexapod_workspace.robot`). Legs, tripods and the study frame (walking
along +y) come from :mod:`legcore.studies.hexapod_workspace.legs`; seed 002's legs use the
closed forms of its eqs (5)–(10), other legs the numerical FK/IK. The robot-relative defaults
(stance posture, θ1 bounds, pose grid, hypervolume reference) are derived from the robot
(:mod:`~legcore.studies.hexapod_workspace.defaults`); seed 002's values are its preset on
``citedi_hexapod`` (:mod:`~legcore.studies.hexapod_workspace.preset`), which the description
below quotes.

Problem (eq 11). The tripod 1-3-5 stands on the ground with θ1 = 0, θ2 = −π/8, θ3 = −π/4 on
every stance leg (stance ``t``). The decision is the new coxa angles ``x = (θ1,1, θ1,3, θ1,5)``
(``[−π/6, π/6]`` each; θ2, θ3 stay fixed) which put the feet at new body-frame positions
(eqs 5–7) at ``t+1``. The body can make that move with the feet fixed on the ground only if the
support triangle at ``t+1`` is congruent to the one at ``t``; the paper asks for two angles and
the perimeter to be equal and minimises the three errors::

    f1 = |β1ᵗ − β1ᵗ⁺¹|  (rad),   f2 = |β5ᵗ − β5ᵗ⁺¹|  (rad),   f3 = |pᵗ − pᵗ⁺¹|  (m)

with β1, β5 the triangle's angles at feet 1 and 5 and p its perimeter (eqs 12–14, through
:func:`legcore.tripod_stability.support_triangle`; ``triangle_formula="interior"`` = the exact
interior angles, ``"paper"`` = eqs 12–13 as printed — see docs/legged.md for their typos). F is
computed for the whole population in one vectorised call.

Stability (Fig. 6): the body centre must stay inside the support triangle, i.e. the distances
S_f, S_b along x to the front and back diagonals must be positive. The paper applies it *after*
the optimisation — its Fig. 9b shows a Pareto-optimal solution "inside the workspace that is not
viable" — so its preset (``stability="classify"``) makes it a post-hoc classification of the
front (the split is in the study extras); the default elsewhere, ``stability="constraint"``,
makes it two constraints ``G = −(S_f, S_b) ≤ 0``: a stance the robot cannot hold is no answer.

**Feasible** means statically stable (S_f > 0 and S_b > 0 at t+1), in either mode:
:meth:`HexapodWorkspaceProblem.violations` reports an unstable solution (its S_f/S_b below 0,
in m), so a run whose optimum is unstable — possible with ``classify`` — says
``feasible: false``. The triangle errors f1–f3 (the feet's slip) are objectives, not
constraints: a near-congruent solution is the answer, its slip is reported.

Outputs (``extras``): the front with each point's body displacement (a planar rigid fit of the
new triangle onto the fixed feet), stability and foot slip; the stable/unstable split; the
workspace of Fig. 8a (the front's body displacements) and the full workspace of Fig. 8b by
mirroring (front/back mirror of the same tripod: the opposite walking direction; left/right
mirror: the same solutions for tripod 2-4-6); and, beyond the paper, the exact workspace of body
poses ``(x, y, yaw)`` reachable with the three feet fixed by the leg IK with θ1, θ2, θ3 free
(:func:`~legcore.studies.hexapod_workspace.geometry.pose_workspace`).

``solution(x)`` decodes a decision into the body moving from ``t`` to ``t+1`` with the feet fixed
(joint angles by IK along the fitted body motion, quintic time law), the metrics, a Table-2-like
per-leg table and the support triangle for the recording. Baselines: the paper's Table 2
solutions a–d (with the printed numbers beside ours) and the start stance.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore.studies.hexapod_workspace import report
from legcore.studies.hexapod_workspace.defaults import study_robot
from legcore.studies.hexapod_workspace.geometry import (
    PoseWorkspace,
    Tripod,
    body_pose_ik,
    fit_body_motion,
    is_mirror_symmetric,
    mirror_left_right,
    pose_workspace,
    tripod_from_robot,
)
from legcore.studies.hexapod_workspace.legs import STANCE_ROLES, leg_roles
from legcore.studies.hexapod_workspace.params import HV_REF, Params
from legcore.studies.study import Motion, Solution, StudyProblem
from legcore.studies.task import Violation
from legcore.support_polygon import stability_margin
from legcore.trajectories.profiles import QuinticProfile
from legcore.tripod_stability import support_triangle, tripod_feet, tripod_stability

__all__ = ["HV_REF", "PAPER_TABLE2", "HexapodWorkspaceProblem", "Params"]

FloatArray = NDArray[np.float64]

#: Seed 002 Table 2 as printed: θ1 of legs 1, 3, 5 (rad), foot x, y (cm) and f1, f2, f3 — the
#: ``paper_*`` baselines (``paper_baselines``).
PAPER_TABLE2: dict[str, dict[str, Any]] = {
    "a": {"theta1": (0.3883, 0.5103, 0.3975), "x_cm": (9.544, 9.198, -9.52),
          "y_cm": (7.472, -1.81, -2.528), "f": (0.0001, 0.0009, 0.0764)},
    "b": {"theta1": (-0.5236, -0.2223, 0.4682), "x_cm": (9.155, 9.869, -9.327),
          "y_cm": (1.735, -6.44, -2.947), "f": (0.0, 0.014, 0.0006)},
    "c": {"theta1": (-0.3883, -0.5103, -0.3975), "x_cm": (9.544, 9.198, -9.521),
          "y_cm": (2.528, -8.19, 2.528), "f": (0.0001, 0.0009, 0.0764)},
    "d": {"theta1": (-0.3883, -0.5069, -0.3975), "x_cm": (9.544, 9.209, -9.521),
          "y_cm": (2.528, -8.17, 2.528), "f": (0.0001, 0.0009, 0.0759)},
}

class HexapodWorkspaceProblem(StudyProblem):
    """Seed 002's eq (11) for one tripod: decision θ1 of (front, back, middle) legs, three
    objectives (rad, rad, m), optional stability constraints. See the module docstring."""

    objective_names = ("f1_beta1", "f2_beta5", "f3_perimeter")
    n_samples = 1

    def __init__(self, robot: Any, params: Params) -> None:
        self.params = params
        robot = study_robot(robot, params)
        self.robot = robot
        self.tripod: Tripod = tripod_from_robot(robot, params.stance)
        roles = leg_roles(robot)
        self.stance_legs = {k: tuple(roles[r] for r in v) for k, v in STANCE_ROLES.items()}
        self.theta_start = np.asarray(params.theta1_start, dtype=float)
        self.theta2, self.theta3 = params.value("theta2"), params.value("theta3")
        self.q_stance = np.column_stack((self.theta_start, np.full(3, self.theta2),
                                         np.full(3, self.theta3)))  # (3 legs, 3 joints)
        self._check_limits(params)
        self.feet_start = self.feet(self.theta_start[None])[0]          # (3, 3) world
        b1, b5, p = self._triangle(self.feet_start[None])
        self.beta1_0, self.beta5_0, self.perimeter_0 = float(b1[0]), float(b5[0]), float(p[0])
        S = self.stability(self.feet_start[None])[0]
        self.S_start = S
        self.symmetry = is_mirror_symmetric(robot)
        n_constr = 2 if params.stability == "constraint" else 0
        self.constraint_names = ("S_f", "S_b")[:n_constr]
        super().__init__(3, 3, n_constr, xl=params.value("theta1_min"),
                         xu=params.value("theta1_max"),
                         name=f"hexapod_workspace[{'-'.join(self.tripod.legs)}]")

    # ------------------------------------------------------------------ set-up checks
    def _check_limits(self, params: Params) -> None:
        t = self.tripod
        for k, leg in enumerate(t.legs):
            lo, hi = t.q_min[k], t.q_max[k]
            t_lo, t_hi = params.value("theta1_min"), params.value("theta1_max")
            if t_lo < lo[0] - 1e-9 or t_hi > hi[0] + 1e-9:
                raise ValueError(
                    f"problem.theta1_min: [{t_lo:.4f}, {t_hi:.4f}] rad "
                    f"exceeds the coxa limits [{lo[0]:.4f}, {hi[0]:.4f}] of leg {leg}")
            for name, j, v in (("theta1_start", 0, self.theta_start[k]),
                               ("theta2", 1, self.theta2), ("theta3", 2, self.theta3)):
                if not lo[j] - 1e-9 <= v <= hi[j] + 1e-9:
                    raise ValueError(f"problem.{name}: {v:.4f} rad is outside the joint limits "
                                     f"[{lo[j]:.4f}, {hi[j]:.4f}] of leg {leg}")
        z = self.feet(self.theta_start[None])[0, :, 2] - t.hips[:, 2, 3]
        if not np.all(z < 0.0):
            raise ValueError(f"problem.theta2: the stance feet must be below the hips "
                             f"(foot z = {z.max():.4f} m from its hip with theta2, theta3 given)")

    # ------------------------------------------------------------------ vectorised pieces
    def feet(self, theta1: FloatArray) -> FloatArray:
        """Study-frame feet (B, 3, 3) of coxa angles (B, 3) with θ2, θ3 fixed (eqs 5–7 for
        seed 002's legs), m."""
        if self.tripod.closed_form:
            return tripod_feet(theta1, self.tripod.hips, self.tripod.L, self.theta2, self.theta3)
        th1 = np.asarray(theta1, dtype=float)
        q = np.stack(np.broadcast_arrays(th1, self.theta2, self.theta3), -1)
        return self.tripod.feet(q)

    def _triangle(self, feet: FloatArray) -> tuple[Any, Any, Any]:
        return support_triangle(feet[..., 0, :], feet[..., 1, :], feet[..., 2, :],
                                formula=self.params.triangle_formula)

    def stability(self, feet: FloatArray) -> FloatArray:
        """(B, 2) ``(S_f, S_b)`` (m) of the body centre (origin of the body frame) for body-frame
        feet (B, 3, 3) in (front, back, middle) order; stable iff both are > 0 (Fig. 6)."""
        S_f, S_b = tripod_stability(feet[..., 0, :], feet[..., 2, :], feet[..., 1, :])
        return np.stack((S_f, S_b), axis=-1)

    def objectives(self, X: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``F`` (B, 3), ``S`` (B, 2) = (S_f, S_b), and the feet (B, 3, 3) of a population."""
        feet = self.feet(X)
        b1, b5, p = self._triangle(feet)
        F = np.stack((np.abs(self.beta1_0 - b1), np.abs(self.beta5_0 - b5),
                      np.abs(self.perimeter_0 - p)), axis=-1)
        # eq (13) as printed can leave its domain (asin of > 1): count that as the worst error
        F = np.where(np.isfinite(F), F, math.pi)
        return F, self.stability(feet), feet

    def _evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray | None]:
        F, S, _ = self.objectives(X)
        if self.n_constr == 0:
            return F, None
        return F, -np.clip(S, -1.0, 1.0)

    def violations(self, x: FloatArray) -> tuple[Violation, ...]:
        """What makes ``x`` infeasible: the body centre outside the support triangle at t+1
        (S_f ≤ 0 or S_b ≤ 0, m), whatever ``stability`` says — with ``classify`` the optimiser
        does not enforce it, but the answer still says so. The amount is how far the centre is
        past that diagonal along x (m; the perpendicular distance when the diagonal is parallel
        to x)."""
        x = np.asarray(x, dtype=float).reshape(1, 3)
        _, S, feet = self.objectives(x)
        margin = float(stability_margin(feet[0]))
        out = []
        for name, s, diagonal in (("S_f", float(S[0, 0]), "front"),
                                  ("S_b", float(S[0, 1]), "back")):
            if s > 0.0:
                continue
            amount = -s if math.isfinite(s) else max(-margin, 0.0)
            out.append(Violation(name, amount, "m",
                                 f"body centre {amount:.3g} m outside the support triangle's "
                                 f"{diagonal} diagonal: statically unstable"))
        return tuple(out)

    def body_motion(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Body displacement ``(x, y, yaw)`` (B, 3) that best keeps the feet fixed, and the foot
        slip (B, 3) in m that it leaves (0 for an exactly congruent triangle)."""
        feet = self.feet(np.atleast_2d(X))
        d, yaw, slip = fit_body_motion(self.feet_start, feet)
        return np.column_stack((d, yaw)), slip

    def exact_ik(self, pose: FloatArray) -> tuple[FloatArray, NDArray[np.bool_]]:
        """Joint angles (B, 3, 3) and per-leg reachability (B, 3) of body poses (B, 3) with the
        stance feet fixed and θ1, θ2, θ3 free (``knee`` branch, joint limits)."""
        pose = np.atleast_2d(pose)
        return body_pose_ik(self.tripod, self.feet_start, pose[:, 0], pose[:, 1], pose[:, 2],
                            knee=self.params.knee, q_ref=self.q_stance)

    # ------------------------------------------------------------------ decoding
    def solution(self, x: FloatArray) -> Solution:
        """Decode coxa angles ``x`` (3,) rad of (front, back, middle) legs.

        ``objectives``: f1, f2 (rad), f3 (m). ``metrics``: ``theta1_<leg>`` (rad); ``beta1``,
        ``beta5`` (rad), ``perimeter`` (m) at t+1; ``S_f``, ``S_b`` (m, along x, Fig. 6),
        ``stable`` (1/0), ``stability_margin`` (m, perpendicular distance to the nearest edge,
        negative outside); ``body_dx``, ``body_dy`` (m), ``body_dyaw`` (rad): the rigid body
        motion that best keeps the feet fixed, ``foot_slip_max`` (m) the slip it leaves;
        ``exact_reachable`` (1/0): that pose is reachable with the feet exactly fixed (IK,
        θ2/θ3 free), ``theta2_exact_max_dev``/``theta3_exact_max_dev`` (rad) how far θ2/θ3 must
        then leave their fixed values; ``motion_feet_fixed`` (1/0) whether the motion keeps the
        feet fixed (else it is the paper's θ1 interpolation). Undefined values (the θ2/θ3
        deviations of an unreachable pose; S_f/S_b when a diagonal is parallel to x) are left
        out / None, so ``decode(x)`` is strict JSON. ``table``: per-leg rows like Table 2.
        ``extra``: legs, feet at t and t+1, body pose, exact joint angles.
        """
        x = np.asarray(x, dtype=float).reshape(-1)
        if x.shape != (3,) or not np.all(np.isfinite(x)):
            raise ValueError(f"x: expected 3 finite coxa angles (rad), got {x.tolist()}")
        F, S, feet = self.objectives(x[None])
        F, S, feet = F[0], S[0], feet[0]
        pose, slip = self.body_motion(x[None])
        pose, slip = pose[0], slip[0]
        q_exact, ok_exact = self.exact_ik(pose[None])
        q_exact, ok_exact = q_exact[0], ok_exact[0]
        b1, b5, p = self._triangle(feet[None])
        legs = self.tripod.legs
        stable = bool(S[0] > 0.0 and S[1] > 0.0)
        motion, feet_fixed = self._motion(x, pose)
        with np.errstate(invalid="ignore"):
            dev2 = float(np.nanmax(np.abs(q_exact[:, 1] - self.theta2))) if ok_exact.all() \
                else float("nan")
            dev3 = float(np.nanmax(np.abs(q_exact[:, 2] - self.theta3))) if ok_exact.all() \
                else float("nan")
        metrics: dict[str, float] = {
            **{f"theta1_{leg}": float(v) for leg, v in zip(legs, x, strict=True)},
            "beta1": float(b1[0]), "beta5": float(b5[0]), "perimeter": float(p[0]),
            "S_f": float(S[0]), "S_b": float(S[1]), "stable": float(stable),
            # an unbounded distance (diagonal ~parallel to x) is no number: null + this flag
            "S_f_unbounded": float(not math.isfinite(S[0])),
            "S_b_unbounded": float(not math.isfinite(S[1])),
            "stability_margin": float(stability_margin(feet)),
            "body_dx": float(pose[0]), "body_dy": float(pose[1]), "body_dyaw": float(pose[2]),
            "foot_slip_max": float(slip.max()),
            "exact_reachable": float(ok_exact.all()),
            "theta2_exact_max_dev": dev2, "theta3_exact_max_dev": dev3,
            "motion_feet_fixed": float(feet_fixed),
        }
        # strict JSON: an undefined value (unreachable pose, diagonal parallel to x) is left out
        metrics = {k: v for k, v in metrics.items() if math.isfinite(v)}
        table = [
            {"metric": "theta1", "unit": "rad", "values": x.tolist()},
            {"metric": "foot_x", "unit": "m", "values": feet[:, 0].tolist()},
            {"metric": "foot_y", "unit": "m", "values": feet[:, 1].tolist()},
            {"metric": "foot_slip", "unit": "m", "values": slip.tolist()},
            {"metric": "theta2_exact", "unit": "rad", "values": _json_list(q_exact[:, 1])},
            {"metric": "theta3_exact", "unit": "rad", "values": _json_list(q_exact[:, 2])},
        ]
        extra = {
            "legs": list(legs),
            "feet_t": self.feet_start.tolist(),
            "feet_t1_body": feet.tolist(),
            "body_pose": pose.tolist(),
            "q_exact": _json_list(q_exact),
            "stable": stable,
        }
        return Solution(x=x.copy(), objectives=dict(zip(self.objective_names, F.tolist(),
                                                        strict=True)),
                        metrics=metrics, table=table, motion=motion, extra=extra)

    def _motion(self, x: FloatArray, pose: FloatArray) -> tuple[Motion, bool]:
        """Body moving from t to t+1 with the feet fixed: poses s·(x, y, yaw) along a quintic
        time law, legs by IK. Where IK fails somewhere on the way, fall back to the paper's
        motion (θ1 linear, θ2, θ3 fixed; feet may slip) and say so."""
        p = self.params
        K = p.motion_samples
        t = np.linspace(0.0, p.duration, K)
        s = QuinticProfile(p.duration).s(t)
        poses = s[:, None] * pose[None, :]
        q, ok = self.exact_ik(poses)
        feet_fixed = bool(ok.all())
        if not feet_fixed:
            th1 = self.theta_start + s[:, None] * (x - self.theta_start)
            q = np.stack((th1, np.full_like(th1, self.theta2), np.full_like(th1, self.theta3)),
                         axis=-1)
            poses, _ = self.body_motion(th1)
        Q = q.reshape(K, 9)
        qd: FloatArray = np.asarray(np.gradient(Q, t, axis=0))
        qdd: FloatArray = np.asarray(np.gradient(qd, t, axis=0))
        c, sn = np.cos(poses[:, 2]), np.sin(poses[:, 2])
        body_T = np.zeros((K, 4, 4))
        body_T[:, 0, 0], body_T[:, 0, 1], body_T[:, 1, 0], body_T[:, 1, 1] = c, -sn, sn, c
        body_T[:, 2, 2] = body_T[:, 3, 3] = 1.0
        body_T[:, 0, 3], body_T[:, 1, 3] = poses[:, 0], poses[:, 1]
        tool = np.column_stack((poses[:, 0], poses[:, 1], np.zeros(K)))
        legs = self.tripod.legs
        names = tuple(f"{leg}.q{j + 1}" for leg in legs for j in range(3))
        scene: dict[str, Any] = {
            "frame": "world = study frame at stance t (z up, walking along +y)",
            "support_polygon": self.feet_start[[0, 2, 1]],     # front, middle, back
            "feet": {leg: self.feet_start[k] for k, leg in enumerate(legs)},
            "ground_z": float(self.feet_start[0, 2]),
            "body_T": body_T,
            "body_size": tuple(float(v) for v in getattr(self.robot, "body_size", ())),
            "hips": {leg: self.tripod.hips[k] for k, leg in enumerate(legs)},
            "tool": "body centre path (the moving platform of the Delta analogy, Fig. 4)",
        }
        motion = Motion(t=t, q=Q, joint_names=names, qd=qd, qdd=qdd, tool=tool,
                        robot=getattr(self.robot, "name", ""), legs=legs, scene=scene)
        return motion, feet_fixed

    # ------------------------------------------------------------------ baselines
    def baseline_solutions(self) -> dict[str, Solution]:
        """The start stance (F = 0: the ideal point), the paper's straight walk of §3 (front and
        back legs −Δθ1, middle leg +Δθ1, ``straight_step``) and its Table 2 solutions a–d
        (printed values in ``extra["paper"]``; mirrored left/right, θ → −θ, for stance 2-4-6)."""
        out: dict[str, Solution] = {}
        out["start"] = self.solution(self.theta_start)
        step = self.params.straight_step * np.array([-1.0, -1.0, 1.0])
        if self.params.stance == "246":
            step = mirror_left_right(step)
        straight = np.clip(self.theta_start + step, self.xl, self.xu)
        out["straight_walk"] = self.solution(straight)
        for key, row in (PAPER_TABLE2 if self.params.paper_baselines else {}).items():
            theta = np.asarray(row["theta1"], dtype=float)
            if self.params.stance == "246":
                theta = mirror_left_right(theta)
            sol = self.solution(theta)
            paper = {
                "theta1": list(row["theta1"]),
                "foot_x_m": [v / 100.0 for v in row["x_cm"]],
                "foot_y_m": [v / 100.0 for v in row["y_cm"]],
                "f": list(row["f"]),
                "note": ("printed for legs L1, L3, L5; f3 presumably in cm"
                         + ("; mirrored onto L4, L6, L2" if self.params.stance == "246" else "")),
            }
            out[f"paper_{key}"] = Solution(x=sol.x, objectives=sol.objectives,
                                           metrics=sol.metrics, table=sol.table,
                                           motion=sol.motion, extra={**sol.extra, "paper": paper})
        return out

    # ------------------------------------------------------------------ study-level outputs
    def front_report(self, X: FloatArray) -> dict[str, Any]:
        """Per-point data of a front X (k, 3): F, S_f/S_b, stable flag, body pose, slip, and
        whether the fitted pose is exactly reachable (IK, θ2/θ3 free)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        F, S, _ = self.objectives(X)
        pose, slip = self.body_motion(X)
        q, ok = self.exact_ik(pose)
        stable = (S[:, 0] > 0.0) & (S[:, 1] > 0.0)
        return {"theta1": X, "F": F, "S": S, "stable": stable, "pose": pose, "slip": slip,
                "exact_reachable": ok.all(axis=-1), "q_exact": q}

    def pose_workspace(self) -> PoseWorkspace:
        """The exact body-pose workspace on the ``Params`` grid (see geometry module)."""
        x, y, yaw = self.params.pose_grid()
        return pose_workspace(self.tripod, self.feet_start, x, y, yaw, knee=self.params.knee,
                              q_ref=self.q_stance)

    def extras(self, front_X: FloatArray, front_F: FloatArray) -> dict[str, Any]:
        """The stance at t, the front with its stability split, Fig. 8's workspaces, the
        hypervolume and the exact pose workspace
        (:func:`legcore.studies.hexapod_workspace.report.extras`)."""
        return report.extras(self, front_X, front_F)


def _json_list(a: FloatArray) -> Any:
    """``a.tolist()`` with NaN/inf as None (strict JSON)."""
    arr = np.asarray(a, dtype=object)
    arr[~np.isfinite(np.asarray(a, dtype=float))] = None
    return arr.tolist()
