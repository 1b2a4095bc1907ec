"""``quadruped_gait`` — seed 003: the 4-beat walk of a quadruped, its servo table, and the step
that walks with the least energy under a static stability margin.

Any quadruped with 2- or 3-joint legs, one at each corner of the body (the catalog's
``animatronic_quadruped`` of seed 003; Solo12, ANYmal, Go1 … from their URDF): the legs come
from the robot (:mod:`legcore.studies.quadruped_gait.legs`), their corner from the hip
position. The gait is the robot's: depth, standing posture, stroke centre, step, speed and
margin are derived from its leg length by the rules of
:mod:`legcore.studies.quadruped_gait.defaults` (checked before a job is queued), except on seed
003's own robot, where its paper's values fill them (:mod:`.preset`); a value given is used as
given (``examples/presets/`` for Solo12, ANYmal, Go1).

Source: seed 003 (Pailos, Bima, Libal 2017): 2-DOF legs (front elbow back, rear knee forward),
law-of-cosines IK (eqs 5–9), the gait of its Fig. 8 / text ("the four legs out of phase by
exactly a quarter of the cycle"), and its Table 2 (servo angle sequence per leg, positions
1…48, link angles Ang3/Ang4 and DH angles q3/q4). DESIGN.md §2 Problems item 4.

Model (SI units; body frame x forward, y left, z up; leg frame x down, y forward):

* **Gait**: :data:`legcore.gaits.QUADRUPED_WALK` (lift-off order FL → RR → FR → RL, offsets
  0, ¼, ½, ¾) with duty factor β (one foot in the air at a time for β = ¾; four-foot overlap
  for β > ¾). The body moves forward at the constant ``speed`` v, level and without rotation.
* **Foot path** (:mod:`legcore.studies.quadruped_gait.cycle`): a level stance stroke of length
  s at the depth H below the hip, centred at c, and a C² swing of height h (built-in profile or
  the user's ``swing_points``). Cycle time ``T = s / (β v)``; distance per cycle ``D = v T =
  s / β``.
* **Foot path in the body frame**: the cycle of every leg lies in the vertical plane through
  its hip, ``foot_lateral`` beside it (default: where the leg's foot is at ``q_ref``).
* **IK** per sample and leg: the closed form with the anatomical branch for seed 003's 2-joint
  legs (:func:`legcore.ik.leg2.leg2_ik`, branch from ``robot.meta["branch"]``, joint limits
  enforced; analytic joint rates), :func:`legcore.ik.solve` along the cycle from the posture
  ``q_ref`` for any other leg (rates from the Jacobian).
* **Loads**: the stance feet carry the weight of the whole robot (body + legs) in static
  equilibrium (vertical reactions, :func:`~legcore.studies.quadruped_gait.cycle.stance_loads`,
  the load handed over linearly during the four-foot phases); each leg's joint torques are
  ``τ = RNEA(q, q̇, q̈) − J_vᵀ F_foot`` (the body moves uniformly, so the fixed-base RNEA of
  each leg is exact for its own links). ``stance_load="none"`` leaves the feet unloaded
  (swing-only dynamics).
* **Objective**: mechanical energy of all joints over one cycle, ``E = Σ ∫ |τ q̇| dt``
  (``energy_model``), per metre walked (``E / D``, J/m; default) or per cycle (J).
* **Constraints** ``G ≤ 0`` (columns): (0) stability margin: ``margin_min − min_t margin`` in
  mm, the margin being :func:`legcore.support_polygon.stability_margin` of the whole robot's COM
  (body plus leg links) in the support polygon of the stance feet, over the cycle grid and just
  before/after every lift-off and touch-down; (1) reach: fraction of samples whose foot target
  is out of reach, outside the joint limits or singular (straight leg); (2) joint speed:
  ``max |q̇| / q̇_max − 1``; (3) torque: ``max |τ| / τ_max − 1`` (servo stall torque); (4) no
  foot pulls on the ground: the largest downward force a stance foot would need, as a share
  of the robot's weight (≤ 1e-9). :meth:`QuadrupedGaitProblem.violations` says each in words
  with its size (:mod:`.feasibility`).
* **Decision** ``x = (s, h, β)``: step length (m), step height (m), duty factor, within
  ``*_bounds`` (equal bounds fix a variable).

Outputs: the decoded :class:`~legcore.studies.study.Solution` has the ``Motion`` of all joints
(legs side by side, ``"FL.shoulder"`` …), the seed 000 metric table per joint, and in ``extra``
the ``servo_table`` (one row per time step, one column per servo, with the servo mapping
``servo = offset + direction · Ang``; seed 003's robot: ``Ang3 = 90° − q3``,
``Ang4 = 90° − q3 − q4``; others: the joint angles), and for 2-joint closed-form legs the
``table2`` (the stance stroke in the paper's 48 positions and columns) and ``table2_paper`` (the
printed rows beside ours, ``compare_table2``).

Seed data and our choices (docs/studies.md (seed 003); :mod:`.preset`): depth H = 0.1648 m,
stroke centre c = −1.2 mm and the default step length 0.119 m come from Table 2's first and
last printed positions (the paper's 48-position stroke); the paper gives no timing, step height
or body speed: v = 0.03 m/s, h = 0.03 m and β = 0.8 are ours.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore.chain_points import chain_points
from legcore.dynamics import inverse_dynamics
from legcore.energy import integrate
from legcore.gaits import QUADRUPED_WALK, Gait, leg_phase
from legcore.robots.catalog.animatronic_quadruped import TABLE2
from legcore.robots.legged import LeggedRobot
from legcore.studies.quadruped_gait import decode
from legcore.studies.quadruped_gait.cycle import (
    SwingShape,
    foot_cycle,
    load_share,
    stance_loads,
)
from legcore.studies.quadruped_gait.feasibility import step_report
from legcore.studies.quadruped_gait.legs import GaitLeg, gait_legs
from legcore.studies.quadruped_gait.params import Params
from legcore.studies.quadruped_gait.tables import (
    servo_mapping,
    servo_table,
    table2,
    table2_comparison,
)
from legcore.studies.study import Solution, StudyProblem, Violation
from legcore.support_polygon import stability_margin

__all__ = ["Params", "QuadrupedGaitProblem", "TABLE2_PAPER", "UNREACHABLE_F"]

FloatArray = NDArray[np.float64]

#: Objective value of a step whose feet cannot follow the path (finite, so that optimisers and
#: fronts stay numeric; the reach constraint marks the row infeasible).
UNREACHABLE_F = 1.0e6
#: Rounding allowance of the no-pull constraint (fraction of the robot's weight).
_PULL_TOL = 1e-9
_EVENT_EPS = 1e-7  # phase offset of the margin samples just before/after a lift-off/touch-down

#: Seed 003 Table 2 as printed: position, front (Ang3, Ang4, q3DA, q4DA), rear (Ang3, Ang4,
#: q3TA, q4TA), degrees — kept with its robot in the catalog (``compare_table2``).
TABLE2_PAPER: tuple[tuple[int, tuple[int, ...], tuple[int, ...]], ...] = TABLE2


class QuadrupedGaitProblem(StudyProblem):
    """Energy of the 4-beat walk per metre (or per cycle) over ``x = (s, h, β)``; see the module
    docstring for the model and the constraint columns."""

    constraint_names: tuple[str, ...] = (
        "stability_margin_mm", "unreachable_fraction", "joint_speed", "torque", "foot_pull")

    def __init__(self, robot: LeggedRobot, params: Params) -> None:
        self.robot = robot
        self.params = params
        self.gait: Gait = QUADRUPED_WALK
        self.gait_legs: tuple[GaitLeg, ...] = gait_legs(robot, params.q_ref, params.foot_lateral)
        self.legs = tuple(g.leg for g in self.gait_legs)
        self.leg_names = tuple(leg.name for leg in self.legs)
        self.roles = tuple(g.role for g in self.gait_legs)
        self.offsets = np.array([self.gait.offsets[self.gait.legs.index(r)] for r in self.roles])
        self.numeric = params.ik == "numeric"
        self.shape = None if params.swing_points is None else SwingShape(tuple(params.swing_points))
        self.mass = float(robot.body_mass) + sum(
            float(leg.robot.chain.mass.sum()) for leg in self.legs
        )
        self.g = float(np.linalg.norm(self.legs[0].robot.chain.gravity))
        self.servo = servo_mapping(dict(robot.meta or {}), self.gait_legs, params)
        self.joint_names = tuple(
            f"{leg.name}.{name}" for leg in self.legs for name in _joint_names(leg.robot)
        )
        self.n_joints = tuple(leg.robot.nq for leg in self.legs)
        self.objective_names = (params.objective,)
        self.n_samples = (params.samples_per_cycle + 1) * len(self.legs)
        p = params
        #: the robot-relative values (derived by STUDY.task when not given)
        self.speed = float(p.need("speed"))
        self.depth = float(p.need("depth"))
        self.stroke_center = float(p.need("stroke_center"))
        self.required_margin = float(p.need("stability_margin"))
        self.default_x = np.array([p.need("step_length"), p.need("step_height"), p.duty])
        sl, sh = p.need("step_length_bounds"), p.need("step_height_bounds")
        super().__init__(
            3,
            1,
            5,
            xl=[sl[0], sh[0], p.duty_bounds[0]],
            xu=[sl[1], sh[1], p.duty_bounds[1]],
            name="quadruped_gait",
        )

    # ------------------------------------------------------------------ core
    def simulate(self, X: FloatArray, detail: bool = False) -> dict[str, Any]:
        """Walk one cycle for every row of ``X`` (B, 3) = (s, h, β) in one batch.

        Returns arrays keyed by name (B leading): ``E`` (B,) J per cycle, ``D`` (B,) m per
        cycle, ``T`` (B,) s, ``margin`` (B,) m (minimum over the cycle), ``bad`` (B,) fraction
        of infeasible samples, ``qd_ratio``/``tau_ratio`` (B,) max |q̇|/q̇_max and |τ|/τ_max;
        with ``detail`` also the time series (``t``, ``q``, ``qd``, ``qdd``, ``tau``, ``feet``,
        ``support``, ``com``, ``loads``, ``margin_t``, per-joint ``E_joint``).
        """
        p = self.params
        K = p.samples_per_cycle
        X = np.asarray(X, dtype=float)
        B = X.shape[0]
        s, h, beta = X[:, 0:1], X[:, 1:2], X[:, 2:3]
        T = s / (beta * self.speed)  # (B, 1)
        # Phase grid: one closed cycle, then (for the margin only) both sides of every event.
        grid = np.broadcast_to(np.arange(K + 1) / K, (B, K + 1))
        events = np.concatenate((self.offsets[None, :] + 0 * beta, self.offsets + (1.0 - beta)), -1)
        ev = np.concatenate((events - _EVENT_EPS, events + _EVENT_EPS), -1) % 1.0
        phi = np.concatenate((grid, ev), -1)  # (B, M)
        u = leg_phase(self.gait, phi)[..., [self.gait.legs.index(r) for r in self.roles]]
        near = np.rint(ev * K).astype(np.int64)  # grid sample next to each event sample
        n_leg = len(self.legs)
        feet, support, share, ok_all = [], [], [], []
        q_l, qd_l, qdd_l, com_num = [], [], [], 0.0
        for j, g in enumerate(self.gait_legs):
            leg, rb = g.leg, g.leg.robot
            pos, dpos, ddpos, st = foot_cycle(
                u[..., j], s, h, beta, self.depth, self.stroke_center, self.shape
            )
            qk, qd, qdd, ok_k = g.motion(pos[:, : K + 1], dpos[:, : K + 1], ddpos[:, : K + 1],
                                         T, self.numeric)
            q0 = np.take_along_axis(qk, near[..., None], axis=1)
            qe, ok_e = g.posture(pos[:, K + 1 :], q0, self.numeric)
            q = np.concatenate((qk, qe), 1)
            feet.append(leg.hip[:3, 3] + g.cycle_to_body(pos))
            support.append(st)
            share.append(load_share(u[..., j], beta, np.maximum(beta - 0.75, 0.0)))
            ok_all.append(np.concatenate((ok_k, ok_e), 1))
            # link COMs (leg base frame) -> body frame, mass-weighted
            c_link = chain_points(rb, q, offsets=g.com_link)[..., 1:, :]  # (B, M, n, 3)
            com_num = com_num + np.einsum("...li,l->...i", leg.foot_in_body(c_link), rb.chain.mass)
            q_l.append(qk)
            qd_l.append(qd)
            qdd_l.append(qdd)
        feet_a = np.stack(feet, -2)  # (B, M, n_leg, 3) body frame
        sup = np.stack(support, -1)  # (B, M, n_leg)
        ok_a = np.stack(ok_all, -1)
        body_c = np.array([p.com_offset[0], p.com_offset[1], 0.0])
        com = (float(self.robot.body_mass) * body_c + com_num) / self.mass  # (B, M, 3)
        margin_t = stability_margin(feet_a, sup, com[..., :2])
        margin = margin_t.min(axis=-1)
        bad = 1.0 - ok_a.mean(axis=(-2, -1))
        # dynamics on the cycle grid
        t = grid * T  # (B, K+1)
        if p.stance_load == "body_weight":
            loads = stance_loads(
                feet_a[:, : K + 1, :, :2],
                np.stack(share, -1)[:, : K + 1],
                com[:, : K + 1, :2],
                self.mass * self.g,
            )
        else:
            loads = np.zeros((B, K + 1, n_leg))
        E = np.zeros(B)
        E_joint, tau_l = [], []
        qd_ratio = np.zeros(B)
        tau_ratio = np.zeros(B)
        for j, leg in enumerate(self.legs):
            rb = leg.robot
            tau = inverse_dynamics(rb, q_l[j], qd_l[j], qdd_l[j])
            up = leg.hip[:3, :3].T @ np.array([0.0, 0.0, 1.0])  # body "up" in the leg frame
            Jv = _foot_jacobian(rb, q_l[j])  # (B, K+1, 3, n)
            F_leg = loads[..., j, None] * up  # vertical ground reaction on the foot, leg frame
            tau = tau - np.einsum("...ij,...i->...j", Jv, F_leg)
            power = tau * qd_l[j]
            if p.energy_model == "positive_work":
                power = np.maximum(power, 0.0)
            else:
                power = np.abs(power)
            e = integrate(power, t)  # (B, n)
            E = E + e.sum(-1)
            E_joint.append(e)
            tau_l.append(tau)
            qd_ratio = np.maximum(qd_ratio, np.max(np.abs(qd_l[j]) / rb.qd_max, axis=(-2, -1)))
            with np.errstate(invalid="ignore"):
                tr = np.where(np.isfinite(rb.tau_max), np.abs(tau) / rb.tau_max, 0.0)
            tau_ratio = np.maximum(tau_ratio, tr.max(axis=(-2, -1)))
        out: dict[str, Any] = {
            "E": E,
            "D": (s / beta)[:, 0],
            "T": T[:, 0],
            "margin": margin,
            "bad": bad,
            "qd_ratio": qd_ratio,
            "tau_ratio": tau_ratio,
            "pull": np.max(-loads, axis=(-2, -1)) / (self.mass * self.g),
        }
        if detail:
            out.update(
                t=t,
                q=np.concatenate(q_l, -1),
                qd=np.concatenate(qd_l, -1),
                qdd=np.concatenate(qdd_l, -1),
                tau=np.concatenate(tau_l, -1),
                E_joint=np.concatenate(E_joint, -1),
                feet=feet_a[:, : K + 1],
                support=sup[:, : K + 1],
                com=com[:, : K + 1],
                loads=loads,
                margin_t=margin_t[:, : K + 1],
                reachable=ok_a[:, : K + 1],
            )
        return out

    def objective_constraints(self, r: dict[str, Any]) -> tuple[FloatArray, FloatArray]:
        """(F (B, 1), G (B, 5)) of a simulation (:meth:`simulate`)."""
        p = self.params
        f = r["E"] / r["D"] if p.objective == "energy_per_metre" else r["E"].copy()
        f = np.where((r["bad"] > 0) | ~np.isfinite(f), UNREACHABLE_F, f)
        G = np.stack(
            (
                (self.required_margin - r["margin"]) * 1e3,
                r["bad"],
                r["qd_ratio"] - 1.0,
                r["tau_ratio"] - 1.0,
                r["pull"] - _PULL_TOL,
            ),
            -1,
        )
        G = np.where(np.isfinite(G), G, 1e6)
        return f[:, None], G

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.objective_constraints(self.simulate(X))

    def violations(self, x: FloatArray) -> tuple[Violation, ...]:
        """What step ``x`` violates, in words with sizes and units (margin in mm, the joint
        over its speed or torque limit, the share out of reach, a foot pulling on the ground:
        :mod:`~legcore.studies.quadruped_gait.feasibility`)."""
        return step_report(self, x).violations()

    # ------------------------------------------------------------------ decoding
    def solution(self, x: FloatArray) -> Solution:
        """One step ``x`` = (step_length m, step_height m, duty) decoded: the cycle's motion on
        the walking body, energy and margin metrics, the per-joint table, servo and Table 2
        layouts (:func:`legcore.studies.quadruped_gait.decode.solution`)."""
        return decode.solution(self, x)

    def servo_table(self, t: FloatArray, q: FloatArray) -> dict[str, Any]:
        """Servo commands (deg) per time step and servo over one cycle (see
        :func:`~legcore.studies.quadruped_gait.tables.servo_table`)."""
        return servo_table(self.gait_legs, self.servo, self.joint_names, t, q)

    def table2(self, s: float, positions: int | None = None) -> dict[str, Any] | None:
        """Seed 003 Table 2 layout of the stance stroke of step length ``s`` (m), or None for
        legs without the 2-joint closed form (:func:`~legcore.studies.quadruped_gait.tables.
        table2`)."""
        return table2(self.gait_legs, self.servo, self.params, s, positions)

    def table2_comparison(self) -> dict[str, Any] | None:
        """Seed 003's printed Table 2 beside ours (None where :meth:`table2` is None)."""
        return table2_comparison(self.gait_legs, self.servo, self.params, TABLE2_PAPER)

    def baseline_solutions(self) -> dict[str, Solution]:
        out = {
            "default_step": self.solution(self.default_x),
            "paper_walk": self.solution(np.array([*self.default_x[:2], 0.75])),
        }
        return out

    def extras(self, front_X: FloatArray, front_F: FloatArray) -> dict[str, Any]:
        out: dict[str, Any] = {"legs": dict(zip(self.leg_names, self.roles, strict=True))}
        if self.params.compare_table2:
            cmp = self.table2_comparison()
            if cmp is not None:
                out["table2_paper"] = cmp
        return out



def _foot_jacobian(rb: Any, q: FloatArray) -> FloatArray:
    """Translational foot Jacobian (..., 3, n) of a leg chain in its base frame."""
    from legcore.kinematics import jacobian

    return jacobian(rb, q)[..., :3, :]


def _joint_names(rb: Any) -> tuple[str, ...]:
    spec = rb.spec
    joints = getattr(spec, "joints", None)
    if isinstance(joints, list):
        return tuple(j.name or f"q{i + 1}" for i, j in enumerate(joints))
    return tuple(list(rb.model.names)[1:])
