"""``quadruped_gait`` — seed 003: the 4-beat walk of the animatronic quadruped, its servo table,
and the step that walks with the least energy under a static stability margin.

Source: seed 003 (Pailos, Bima, Libal 2017): 2-DOF legs (front elbow back, rear knee forward),
law-of-cosines IK (eqs 5–9), the gait of its Fig. 8 / text ("the four legs out of phase by
exactly a quarter of the cycle"), and its Table 2 (servo angle sequence per leg, positions
1…48, link angles Ang3/Ang4 and DH angles q3/q4). DESIGN.md §2 Problems item 4.

Model (SI units; body frame x forward, y left, z up; leg frame x down, y forward):

* **Gait**: :data:`legcore.gaits.QUADRUPED_WALK` (lift-off order FL → RR → FR → RL, offsets
  0, ¼, ½, ¾) with duty factor β (one foot in the air at a time for β = ¾; four-foot overlap
  for β > ¾). The body moves forward at the constant ``speed`` v, level and without rotation.
* **Foot path** (:mod:`legcore.problems.quadruped_gait_cycle`): a level stance stroke of length
  s at the depth H below the hip, centred at c, and a C² swing of height h (built-in profile or
  the user's ``swing_points``). Cycle time ``T = s / (β v)``; distance per cycle ``D = v T =
  s / β``.
* **IK** per sample and leg with the anatomical branch (:func:`legcore.ik.leg2.leg2_ik`, branch
  from ``robot.meta["branch"]``, joint limits enforced); joint rates from the analytic Jacobian.
* **Loads**: the stance feet carry the weight of the whole robot (body + legs) in static
  equilibrium (vertical reactions, :func:`~legcore.problems.quadruped_gait_cycle.stance_loads`,
  the load handed over linearly during the four-foot phases); each leg's joint torques are
  ``τ = RNEA(q, q̇, q̈) − J_vᵀ F_foot`` (the body moves uniformly, so the fixed-base RNEA of
  each leg is exact for its own links). ``stance_load="none"`` leaves the feet unloaded
  (swing-only dynamics).
* **Objective**: mechanical energy of all 8 joints over one cycle, ``E = Σ ∫ |τ q̇| dt``
  (``energy_model``), per metre walked (``E / D``, J/m; default) or per cycle (J).
* **Constraints** ``G ≤ 0`` (columns): (0) stability margin: ``margin_min − min_t margin`` in
  mm, the margin being :func:`legcore.gaits.stability_margin` of the whole robot's COM (body
  plus leg links) in the support polygon of the stance feet, over the cycle grid and just
  before/after every lift-off and touch-down; (1) reach: fraction of samples whose foot target
  is out of reach, outside the joint limits or singular (straight leg); (2) joint speed:
  ``max |q̇| / q̇_max − 1``; (3) torque: ``max |τ| / τ_max − 1`` (servo stall torque).
* **Decision** ``x = (s, h, β)``: step length (m), step height (m), duty factor, within
  ``*_bounds`` (equal bounds fix a variable).

Outputs: the decoded :class:`~legcore.problems.study.Solution` has the 8-joint ``Motion`` (legs
side by side, ``"FL.shoulder"`` …), the seed 000 metric table per joint, and in ``extra`` the
``servo_table`` (one row per time step, one column per servo, with the servo mapping
``servo = offset + direction · Ang``, ``Ang3 = 90° − q3``, ``Ang4 = 90° − q3 − q4``), the
``table2`` (the stance stroke in the paper's 48 positions and columns) and ``table2_paper`` (the
printed rows beside ours).

Seed data and our choices (docs/studies.md (seed 003)): depth H = 0.1648 m, stroke
centre c = −1.2 mm and the default step length 0.119 m come from Table 2's first and last
printed positions (the paper's 48-position stroke); the paper gives no timing, step height or
body speed: v = 0.03 m/s, h = 0.03 m and β = 0.8 are ours.
"""

from __future__ import annotations

import math
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, field_validator, model_validator

from legcore.dynamics import inverse_dynamics
from legcore.energy import integrate
from legcore.gaits import QUADRUPED_WALK, Gait, leg_phase, stability_margin, support_polygon
from legcore.ik.leg2 import leg2_fk, leg2_ik
from legcore.joint_metrics import joint_metrics
from legcore.kinematics import fk, frames
from legcore.problems.quadruped_gait_cycle import (
    SwingShape,
    foot_cycle,
    leg2_rates,
    load_share,
    servo_angles_deg,
    stance_loads,
)
from legcore.problems.study import Motion, Solution, Study, StudyParams, StudyProblem
from legcore.robots.catalog.animatronic_quadruped import TABLE2
from legcore.robots.legged import LeggedRobot
from legcore.robots.spec import DHRobotSpec

__all__ = ["Params", "QuadrupedGaitProblem", "STUDY", "TABLE2_PAPER", "build"]

FloatArray = NDArray[np.float64]

G0 = 9.81  # m/s², as the catalog's leg models
#: Objective value of a step whose feet cannot follow the path (finite, so that optimisers and
#: fronts stay numeric; the reach constraint marks the row infeasible).
UNREACHABLE_F = 1.0e6
_EVENT_EPS = 1e-7  # phase offset of the margin samples just before/after a lift-off/touch-down
_SINGULAR = 1e-6  # |sin q4| below which a leg counts as straight (singular)

#: Seed 003 Table 2 as printed: position, front (Ang3, Ang4, q3DA, q4DA), rear (Ang3, Ang4,
#: q3TA, q4TA), degrees — kept with the robot in the catalog.
TABLE2_PAPER: tuple[tuple[int, tuple[int, ...], tuple[int, ...]], ...] = TABLE2
_TABLE2_COLUMNS = ("position", "Ang3", "Ang4", "q3DA", "q4DA", "Ang3", "Ang4", "q3TA", "q4TA")

Pair = tuple[float, float]


def _finite(name: str, v: float) -> float:
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be a finite number, got {v}")
    return v


class Params(StudyParams):
    """Parameters of the ``quadruped_gait`` study (SI units; defaults = seed 003 where it has
    them, see the module docstring for the ones we chose).

    Default step (the ``default_step`` baseline, and what the optimum is compared with):
    ``step_length`` s (m), ``step_height`` h (m), ``duty`` β. Search box: ``*_bounds``.
    ``speed`` body speed v (m/s); ``depth`` foot depth below the hip in stance H (m);
    ``stroke_center`` c (m, forward of the hip); ``swing_points`` optional user swing profile
    ``[(ξ, η), …]`` (ξ from −0.5 at lift-off to 0.5 at touch-down, η ≥ 0 lift, 0 at both ends,
    scaled so its peak is h); ``samples_per_cycle`` K (multiple of 4: the beats fall on the
    grid); ``stability_margin`` required static margin (m); ``com_offset`` body COM from the
    body centre (x, y) m; ``stance_load`` "body_weight" or "none"; ``energy_model``
    "mechanical" (∫|τ q̇|) or "positive_work" (∫max(τ q̇, 0)); ``objective`` "energy_per_metre"
    (J/m) or "energy_per_cycle" (J); ``servo_offset_deg`` / ``servo_direction`` per leg
    (two servos each) override the catalog's ``meta["servo"]``; ``table_positions`` number of
    stroke positions of the Table 2-like output (the paper's 48).
    """

    kind: Literal["quadruped_gait"] = "quadruped_gait"
    step_length: float = Field(default=0.119, gt=0.0, le=1.0)
    step_height: float = Field(default=0.03, ge=0.0, le=1.0)
    duty: float = Field(default=0.8, gt=0.0, lt=1.0)
    step_length_bounds: Pair = (0.04, 0.13)
    step_height_bounds: Pair = (0.01, 0.05)
    duty_bounds: Pair = (0.75, 0.9)
    speed: float = Field(default=0.03, gt=0.0, le=10.0)
    depth: float = Field(default=0.1648, gt=0.0, le=10.0)
    stroke_center: float = Field(default=-0.0012, ge=-10.0, le=10.0)
    swing_points: tuple[Pair, ...] | None = Field(default=None, max_length=1000)
    samples_per_cycle: int = Field(default=64, ge=16, le=4096)
    stability_margin: float = Field(default=0.001, ge=-1.0, le=1.0)
    com_offset: Pair = (0.0, 0.0)
    stance_load: Literal["body_weight", "none"] = "body_weight"
    energy_model: Literal["mechanical", "positive_work"] = "mechanical"
    objective: Literal["energy_per_metre", "energy_per_cycle"] = "energy_per_metre"
    servo_offset_deg: dict[str, Pair] | None = None
    servo_direction: dict[str, tuple[int, int]] | None = None
    table_positions: int = Field(default=48, ge=2, le=1000)

    @field_validator(
        "step_length", "step_height", "duty", "speed", "depth", "stroke_center", "stability_margin"
    )
    @classmethod
    def _finite_scalar(cls, v: float) -> float:
        return _finite("value", v)

    @field_validator("com_offset")
    @classmethod
    def _finite_pair(cls, v: Pair) -> Pair:
        if not all(math.isfinite(a) and abs(a) <= 10.0 for a in v):
            raise ValueError(f"must be two finite numbers within ±10 m, got {v}")
        return v

    @field_validator("samples_per_cycle")
    @classmethod
    def _multiple_of_4(cls, v: int) -> int:
        if v % 4:
            raise ValueError(f"must be a multiple of 4 (the four beats of the walk), got {v}")
        return v

    @field_validator("swing_points")
    @classmethod
    def _swing_points(cls, v: tuple[Pair, ...] | None) -> tuple[Pair, ...] | None:
        if v is not None:
            SwingShape(tuple(v))  # raises ValueError with the reason
        return v

    @field_validator("servo_direction")
    @classmethod
    def _directions(cls, v: dict[str, tuple[int, int]] | None) -> Any:
        if v is not None:
            for leg, d in v.items():
                if any(x not in (-1, 1) for x in d):
                    raise ValueError(f"{leg}: directions must be +1 or -1, got {d}")
        return v

    @field_validator("servo_offset_deg")
    @classmethod
    def _offsets(cls, v: dict[str, Pair] | None) -> Any:
        if v is not None:
            for leg, o in v.items():
                if not all(math.isfinite(a) for a in o):
                    raise ValueError(f"{leg}: offsets must be finite degrees, got {o}")
        return v

    @model_validator(mode="after")
    def _bounds(self) -> Params:
        limits = {
            "step_length_bounds": (0.0, 1.0, False),
            "step_height_bounds": (0.0, 1.0, True),
            "duty_bounds": (0.0, 1.0, False),
        }
        for name, (lo_min, hi_max, closed) in limits.items():
            lo, hi = getattr(self, name)
            if not (math.isfinite(lo) and math.isfinite(hi)):
                raise ValueError(f"{name}: must be finite, got {(lo, hi)}")
            if lo > hi:
                raise ValueError(f"{name}: lower bound {lo} above upper bound {hi}")
            low_ok = lo >= lo_min if closed else lo > lo_min
            if not low_ok or hi > hi_max or (name == "duty_bounds" and hi >= 1.0):
                raise ValueError(
                    f"{name}: must lie in {'[' if closed else '('}{lo_min}, {hi_max}"
                    f"{')' if name == 'duty_bounds' else ']'}, got {(lo, hi)}"
                )
        return self


class QuadrupedGaitProblem(StudyProblem):
    """Energy of the 4-beat walk per metre (or per cycle) over ``x = (s, h, β)``; see the module
    docstring for the model and the constraint columns."""

    constraint_names = ("stability_margin_mm", "unreachable_fraction", "joint_speed", "torque")

    def __init__(self, robot: LeggedRobot, params: Params) -> None:
        self.robot = robot
        self.params = params
        self.gait: Gait = QUADRUPED_WALK
        self.legs = _check_robot(robot, self.gait)
        self.leg_names = tuple(leg.name for leg in self.legs)
        self.offsets = np.array(
            [self.gait.offsets[self.gait.legs.index(n)] for n in self.leg_names]
        )
        meta = robot.meta or {}
        self.branch = np.array([_branch(meta, leg) for leg in self.legs], dtype=float)
        self.L = [tuple(float(j.a) for j in leg.robot.spec.joints) for leg in self.legs]
        # link COMs (n, 3) in DH link frame i, the frames `legcore.kinematics.frames` returns
        self.link_com = [np.array([j.com for j in leg.robot.spec.joints]) for leg in self.legs]
        self.shape = None if params.swing_points is None else SwingShape(tuple(params.swing_points))
        self.mass = float(robot.body_mass) + sum(
            float(leg.robot.chain.mass.sum()) for leg in self.legs
        )
        self.servo = _servo_mapping(meta, self.leg_names, params)
        self.joint_names = tuple(
            f"{leg.name}.{j.name or f'q{i + 1}'}"
            for leg in self.legs
            for i, j in enumerate(leg.robot.spec.joints)
        )
        self.objective_names = (params.objective,)
        self.n_samples = (params.samples_per_cycle + 1) * len(self.legs)
        p = params
        super().__init__(
            3,
            1,
            4,
            xl=[p.step_length_bounds[0], p.step_height_bounds[0], p.duty_bounds[0]],
            xu=[p.step_length_bounds[1], p.step_height_bounds[1], p.duty_bounds[1]],
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
        T = s / (beta * p.speed)  # (B, 1)
        # Phase grid: one closed cycle, then (for the margin only) both sides of every event.
        grid = np.broadcast_to(np.arange(K + 1) / K, (B, K + 1))
        events = np.concatenate((self.offsets[None, :] + 0 * beta, self.offsets + (1.0 - beta)), -1)
        ev = np.concatenate((events - _EVENT_EPS, events + _EVENT_EPS), -1) % 1.0
        phi = np.concatenate((grid, ev), -1)  # (B, M)
        u = leg_phase(self.gait, phi)[..., [self.gait.legs.index(n) for n in self.leg_names]]
        n_leg = len(self.legs)
        Tt = T[..., None]
        feet, support, share, ok_all = [], [], [], []
        q_l, qd_l, qdd_l, com_num = [], [], [], 0.0
        for j, leg in enumerate(self.legs):
            rb = leg.robot
            pos, dpos, ddpos, st = foot_cycle(
                u[..., j], s, h, beta, p.depth, p.stroke_center, self.shape
            )
            q, ok = leg2_ik(pos, self.L[j], self.branch[j], rb.q_min, rb.q_max)
            ok &= np.abs(np.sin(np.where(ok, q[..., 1], 0.0))) > _SINGULAR
            q = np.where(ok[..., None], q, rb.home)
            p3 = np.concatenate((pos, np.zeros(pos.shape[:-1] + (1,))), -1)
            feet.append(leg.foot_in_body(p3))
            support.append(st)
            share.append(load_share(u[..., j], beta, np.maximum(beta - 0.75, 0.0)))
            ok_all.append(ok)
            # link COMs (leg base frame) -> body frame, mass-weighted
            F = frames(rb, q)  # (B, M, n+1, 4, 4)
            c_link = np.einsum("...lij,lj->...li", F[..., 1:, :3, :3], self.link_com[j])
            c_link = c_link + F[..., 1:, :3, 3]
            com_num = com_num + np.einsum("...li,l->...i", leg.foot_in_body(c_link), rb.chain.mass)
            qk = q[:, : K + 1]
            qd, qdd, _ = leg2_rates(qk, dpos[:, : K + 1] / Tt, ddpos[:, : K + 1] / Tt**2, self.L[j])
            bad_rate = ~np.all(np.isfinite(qd) & np.isfinite(qdd), axis=-1)
            qd = np.where(bad_rate[..., None], 0.0, qd)
            qdd = np.where(bad_rate[..., None], 0.0, qdd)
            ok_all[-1] = ok_all[-1].copy()
            ok_all[-1][:, : K + 1] &= ~bad_rate
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
                self.mass * G0,
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
            Jv = _leg2_jv(q_l[j], self.L[j])  # (B, K+1, 2, 2): rows x, y of the leg frame
            F_leg = loads[..., j, None] * up[:2]  # ground reaction on the foot, leg frame x, y
            tau = tau - np.einsum("...ij,...i->...j", Jv, F_leg)
            power = tau * qd_l[j]
            if p.energy_model == "positive_work":
                power = np.maximum(power, 0.0)
            else:
                power = np.abs(power)
            e = integrate(power, t)  # (B, 2)
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

    def _objective_constraints(self, r: dict[str, Any]) -> tuple[FloatArray, FloatArray]:
        p = self.params
        f = r["E"] / r["D"] if p.objective == "energy_per_metre" else r["E"].copy()
        f = np.where((r["bad"] > 0) | ~np.isfinite(f), UNREACHABLE_F, f)
        G = np.stack(
            (
                (p.stability_margin - r["margin"]) * 1e3,
                r["bad"],
                r["qd_ratio"] - 1.0,
                r["tau_ratio"] - 1.0,
            ),
            -1,
        )
        G = np.where(np.isfinite(G), G, 1e6)
        return f[:, None], G

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self._objective_constraints(self.simulate(X))

    # ------------------------------------------------------------------ decoding
    def solution(self, x: FloatArray) -> Solution:
        x = np.asarray(x, dtype=float).reshape(-1)
        if x.shape != (3,) or not np.all(np.isfinite(x)):
            raise ValueError(
                f"x: expected 3 finite numbers (step_length, step_height, duty), got {x}"
            )
        r = self.simulate(x[None, :], detail=True)
        F, G = self._objective_constraints(r)
        d = {k: (v[0] if isinstance(v, np.ndarray) and v.ndim >= 1 else v) for k, v in r.items()}
        t, q, qd, qdd, tau = d["t"], d["q"], d["qd"], d["qdd"], d["tau"]
        p = self.params
        power = tau * qd
        absp = np.maximum(power, 0.0) if p.energy_model == "positive_work" else np.abs(power)
        cum = np.concatenate(([0.0], np.cumsum(0.5 * (absp[1:] + absp[:-1]).sum(-1) * np.diff(t))))
        x_body = p.speed * t  # body displacement (m) along world x
        body_h = p.depth - float(np.mean([leg.hip[2, 3] for leg in self.legs]))
        body = np.stack((x_body, np.zeros_like(t), np.full_like(t, body_h)), -1)
        feet_w = d["feet"] + body[:, None, :]
        com_w = d["com"] + body
        tool_leg = self.leg_names.index("FR") if "FR" in self.leg_names else 0
        # seed 000 metrics per joint; D = the FR foot's path relative to the body over a cycle
        jerk = _periodic_jerk(t, qdd)
        jm = joint_metrics(t, q, tau, qd=qd, qdd=qdd, jerk=jerk, tool_pos=d["feet"][:, tool_leg])
        reachable = bool(np.all(d["reachable"]))
        feasible = bool(np.all(G <= 0.0))
        E, D = float(d["E"]), float(d["D"])
        E_joint = d["E_joint"]
        n_j = [leg.robot.nq for leg in self.legs]
        starts = np.cumsum([0, *n_j])
        sup = d["support"]
        swing_mask = ~np.repeat(sup, n_j, axis=-1)
        e_swing = float(integrate((absp * swing_mask)[:, :], t).sum())
        metrics: dict[str, float] = {
            "energy_per_cycle_J": E,
            "energy_per_metre_J_per_m": E / D if D > 0 else float("nan"),
            "energy_swing_J": e_swing,
            "energy_stance_J": E - e_swing,
            "cycle_time_s": float(d["T"]),
            "distance_per_cycle_m": D,
            "speed_m_s": p.speed,
            "step_length_m": float(x[0]),
            "step_height_m": float(x[1]),
            "duty": float(x[2]),
            "min_stability_margin_m": float(d["margin"]),
            "required_stability_margin_m": p.stability_margin,
            "max_joint_speed_ratio": float(d["qd_ratio"]),
            "max_torque_ratio": float(d["tau_ratio"]),
            "max_torque_Nm": float(np.max(np.abs(tau))),
            "max_joint_speed_rad_s": float(np.max(np.abs(qd))),
            "max_foot_load_N": float(np.max(d["loads"])),
            "min_foot_load_N": float(np.min(d["loads"])),
            "reachable": float(reachable),
            "feasible": float(feasible),
        }
        for j, name in enumerate(self.leg_names):
            metrics[f"energy_{name}_J"] = float(E_joint[starts[j] : starts[j + 1]].sum())
        table = [
            {
                "metric": row.label,
                "key": row.key,
                "unit": row.unit,
                **(
                    {"values": list(row.per_joint)}
                    if row.per_joint is not None
                    else {"total": row.total}
                ),
            }
            for row in jm.as_table()
        ]
        polys, n_poly = support_polygon(feet_w, sup)
        scene: dict[str, Any] = {
            "frame": "world: x along the walk, z up; ground at z = 0",
            "ground_z": 0.0,
            "feet": feet_w,
            "foot_names": self.leg_names,
            "support": sup,
            "support_polygon": np.concatenate((polys, np.zeros(polys.shape[:-1] + (1,))), -1),
            "support_polygon_n": n_poly,
            "com": com_w,
            "com_ground": com_w * np.array([1.0, 1.0, 0.0]),
            "body_position": body,
            "body_size": self.robot.body_size,
            "stability_margin": d["margin_t"],
            "foot_loads_N": d["loads"],
        }
        motion = Motion(
            t=t,
            q=q,
            joint_names=self.joint_names,
            qd=qd,
            qdd=qdd,
            jerk=jerk,
            tau=tau,
            power=power,
            energy=cum,
            tool=feet_w[:, tool_leg],
            robot=self.robot.name,
            legs=self.leg_names,
            scene=scene,
        )
        extra = {
            "objective": p.objective,
            "constraints": dict(zip(self.constraint_names, (float(g) for g in G[0]), strict=True)),
            "gait": {
                "name": self.gait.name,
                "legs": list(self.gait.legs),
                "offsets": list(self.gait.offsets),
                "duty": float(x[2]),
                "lift_off_order": [
                    n for _, n in sorted(zip(self.gait.offsets, self.gait.legs, strict=True))
                ],
                "source": self.gait.source,
            },
            "table_columns": list(self.joint_names),
            "servo_table": self.servo_table(t, q),
            "table2": self.table2(float(x[0])),
        }
        return Solution(
            x=x.copy(),
            objectives={p.objective: float(F[0, 0])},
            metrics=metrics,
            table=table,
            motion=motion,
            extra=extra,
        )

    def servo_table(self, t: FloatArray, q: FloatArray) -> dict[str, Any]:
        """Servo commands (deg) per time step (rows) and servo (columns) over one cycle.

        ``t`` (K+1,) s, ``q`` (K+1, 8) rad (legs side by side); the closing sample is left out,
        so the K rows are positions 1…K of the cycle.
        """
        servos, cols = [], []
        for j, leg in enumerate(self.legs):
            m = self.servo[leg.name]
            _, cmd = servo_angles_deg(
                q[:-1, 2 * j : 2 * j + 2],
                m["link_offset"],
                m["link_matrix"],
                m["servo_offset"],
                m["servo_direction"],
            )
            cols.append(cmd)
            for i, jn in enumerate(("q3", "q4")):
                servos.append(
                    {
                        "name": self.joint_names[2 * j + i],
                        "leg": leg.name,
                        "paper_leg": m["paper_name"],
                        "dh_angle": jn,
                        "link_angle": ("Ang3", "Ang4")[i],
                        "offset_deg": m["servo_offset"][i],
                        "direction": m["servo_direction"][i],
                    }
                )
        cmd_all = np.concatenate(cols, -1)
        rows = [
            [k + 1, round(float(t[k]), 6), *(round(float(v), 2) for v in cmd_all[k])]
            for k in range(cmd_all.shape[0])
        ]
        return {
            "mapping": "servo = offset + direction * Ang; Ang3 = 90 - q3, Ang4 = 90 - q3 - q4 "
            "(deg; q3, q4 the DH angles of seed 003)",
            "columns": ["position", "t_s", *self.joint_names],
            "servos": servos,
            "rows": rows,
        }

    def table2(self, s: float, positions: int | None = None) -> dict[str, Any]:
        """Seed 003 Table 2 layout for the stance stroke of step length ``s`` (m): ``positions``
        equally spaced foot positions from touch-down (front) to lift-off (back) at the depth H,
        front-right and rear-right legs: link angles Ang3/Ang4 and DH q3/q4 in degrees (DH
        angles wrapped into [0, 360) as the paper prints them; its front q3 column adds 360°
        to every row, e.g. 369 for 9°). Rows of unreachable positions hold None."""
        p = self.params
        n = positions or p.table_positions
        y = p.stroke_center + 0.5 * s - s * np.linspace(0.0, 1.0, n)
        P = np.stack((np.full(n, p.depth), y), -1)
        cols: list[FloatArray] = []
        legs = {}
        for name in ("FR", "RR"):
            j = self.leg_names.index(name)  # the legs were checked: FL, FR, RL, RR
            leg = self.legs[j]
            legs[name] = leg.name
            q, ok = leg2_ik(P, self.L[j], self.branch[j], leg.robot.q_min, leg.robot.q_max)
            m = self.servo[leg.name]
            ang, _ = servo_angles_deg(q, m["link_offset"], m["link_matrix"], (0.0, 0.0), (1, 1))
            cols += [ang, np.mod(np.degrees(q), 360.0)]
        A = np.concatenate(cols, -1)
        rows = [
            [k + 1, *(None if not np.isfinite(v) else round(float(v), 2) for v in A[k])]
            for k in range(n)
        ]
        return {
            "legs": legs,
            "columns": list(_TABLE2_COLUMNS),
            "rows": rows,
            "stroke": {"step_length_m": s, "depth_m": p.depth, "center_m": p.stroke_center},
        }

    def table2_comparison(self) -> dict[str, Any]:
        """The paper's printed Table 2 rows beside ours at the same stroke positions (default
        step length), with the differences (deg) and the foot depth of the printed rows."""
        ours = self.table2(self.params.step_length, 48)["rows"]
        rows = []
        for pos, front, rear in TABLE2_PAPER:
            printed = [*front, *rear]
            mine = ours[pos - 1][1:]
            diff = [
                None if m is None else round(_wrap180(m - v), 2)
                for m, v in zip(mine, printed, strict=True)
            ]
            depths = []
            for k, row in enumerate((front, rear)):
                q = np.radians([90.0 - row[0], row[0] - row[1]])
                depths.append(round(float(leg2_fk(q, self.L[0 if k == 0 else -1])[0]), 5))
            rows.append(
                {
                    "position": pos,
                    "paper": printed,
                    "ours": mine,
                    "diff_deg": diff,
                    "paper_foot_depth_m": depths,
                }
            )
        return {"columns": list(_TABLE2_COLUMNS[1:]), "rows": rows}

    def baseline_solutions(self) -> dict[str, Solution]:
        p = self.params
        out = {
            "default_step": self.solution(np.array([p.step_length, p.step_height, p.duty])),
            "paper_walk": self.solution(np.array([p.step_length, p.step_height, 0.75])),
        }
        return out

    def extras(self, front_X: FloatArray, front_F: FloatArray) -> dict[str, Any]:
        return {"table2_paper": self.table2_comparison()}


def _periodic_jerk(t: FloatArray, qdd: FloatArray) -> FloatArray:
    """Jerk (K, n) rad/s³ by differentiating ``qdd`` on the closed cycle grid (periodic central
    differences; the cycle is C², so the jerk is piecewise continuous)."""
    dt = t[1] - t[0]
    core = qdd[:-1]
    j = (np.roll(core, -1, axis=0) - np.roll(core, 1, axis=0)) / (2.0 * dt)
    return np.concatenate((j, j[:1]), 0)


def _wrap180(a: float) -> float:
    return (a + 180.0) % 360.0 - 180.0


def _leg2_jv(q: FloatArray, L: tuple[float, ...]) -> FloatArray:
    """Planar foot Jacobian (..., 2, 2) of the 2-DOF leg: rows (x, y) of the leg frame."""
    l1, l2 = L
    a, b = q[..., 0], q[..., 0] + q[..., 1]
    s1, c1, s12, c12 = np.sin(a), np.cos(a), np.sin(b), np.cos(b)
    return np.stack(
        (
            np.stack((-(l1 * s1 + l2 * s12), -l2 * s12), -1),
            np.stack((l1 * c1 + l2 * c12, l2 * c12), -1),
        ),
        -2,
    )


def _branch(meta: dict[str, Any], leg: Any) -> int:
    br = meta.get("branch", {})
    if isinstance(br, dict) and leg.name in br:
        return int(br[leg.name])
    rb = leg.robot  # the joint limits of q4 hold the branch
    if rb.q_min[1] >= 0.0:
        return 1
    if rb.q_max[1] <= 0.0:
        return -1
    raise ValueError(
        f"robot: leg {leg.name!r} has no branch in meta['branch'] and its knee limits "
        f"[{rb.q_min[1]}, {rb.q_max[1]}] do not decide one"
    )


def _check_robot(robot: Any, gait: Gait) -> tuple[Any, ...]:
    """The robot's legs, checked: four 2-DOF ``leg2`` legs named as the gait's, consistent
    planar kinematics and gravity pointing down the body's z."""
    if not isinstance(robot, LeggedRobot):
        raise ValueError("robot: the quadruped_gait study needs a legged robot")
    names = tuple(leg.name for leg in robot.legs)
    if sorted(names) != sorted(gait.legs):
        raise ValueError(f"robot: needs legs {list(gait.legs)} (4-beat walk), got {list(names)}")
    for leg in robot.legs:
        rb = leg.robot
        if rb.nq != 2 or rb.ik_family != "leg2" or not isinstance(rb.spec, DHRobotSpec):
            raise ValueError(
                f"robot: leg {leg.name!r} must be a 2-DOF DH leg with ik 'leg2' (seed 003), "
                f"got nq={rb.nq}, ik={rb.ik_family!r}"
            )
        L = [float(j.a) for j in rb.spec.joints]
        q_test = rb.home + np.array([[0.0, 0.0], [0.3, 0.2], [-0.4, 0.5]])
        p_model = fk(rb, q_test)[:, :3, 3]
        p_leg2 = leg2_fk(q_test, L)
        if not np.allclose(p_model, p_leg2, atol=1e-9):
            raise ValueError(
                f"robot: leg {leg.name!r} kinematics differ from the leg2 convention "
                f"(x down, y forward, a = link lengths, alpha = 0)"
            )
        g_body = leg.hip[:3, :3] @ rb.chain.gravity
        g_norm = max(float(np.linalg.norm(g_body)), 1e-300)
        if not np.allclose(g_body / g_norm, [0.0, 0.0, -1.0], atol=1e-6):
            raise ValueError(
                f"robot: leg {leg.name!r} gravity {rb.chain.gravity.tolist()} (leg frame) does "
                f"not point down the body's z axis"
            )
    return tuple(robot.legs)


def _servo_mapping(
    meta: dict[str, Any], legs: tuple[str, ...], params: Params
) -> dict[str, dict[str, Any]]:
    servo = meta.get("servo", {}) if isinstance(meta.get("servo", {}), dict) else {}
    link_offset = tuple(servo.get("link_angle_offset_deg", (90.0, 90.0)))
    link_matrix = tuple(
        tuple(r) for r in servo.get("link_angle_matrix", ((-1.0, 0.0), (-1.0, -1.0)))
    )
    offs = dict(servo.get("servo_offset_deg", {}))
    dirs = dict(servo.get("servo_direction", {}))
    for name, table in (
        ("servo_offset_deg", params.servo_offset_deg),
        ("servo_direction", params.servo_direction),
    ):
        if table is not None:
            unknown = sorted(set(table) - set(legs))
            if unknown:
                raise ValueError(f"{name}: unknown legs {unknown}; legs are {list(legs)}")
    offs.update(params.servo_offset_deg or {})
    dirs.update(params.servo_direction or {})
    names = meta.get("paper_names", {})
    return {
        n: {
            "link_offset": link_offset,
            "link_matrix": link_matrix,
            "servo_offset": tuple(float(v) for v in offs.get(n, (0.0, 0.0))),
            "servo_direction": tuple(int(v) for v in dirs.get(n, (1, 1))),
            "paper_name": names.get(n, n) if isinstance(names, dict) else n,
        }
        for n in legs
    }


def build(robot: Any, params: Params) -> QuadrupedGaitProblem:
    """The study's problem for ``robot`` (a 4-legged :class:`LeggedRobot`) and ``params``."""
    return QuadrupedGaitProblem(robot, params)


STUDY = Study(
    kind="quadruped_gait",
    title="Quadruped 4-beat walk: servo table and minimum-energy step under a stability margin",
    seed_paper="003",
    params=Params,
    default_robot="animatronic_quadruped",
    default_optimizer={
        "kind": "hka",
        "params": {
            "n_samples": 50,
            "n_best": 5,
            "alpha": 0.9,
            "init": "survey",
            "survey_size": 300,
            "survey_best": 3,
            "penalty": 1e3,
        },
    },
    default_generations=40,
    build=build,
    robot_kinds=("legged",),
)
