"""``path_tracking`` — seed 004 as a task: an arm runs a composite line/arc path in any plane.

The path is a chain of lines and arcs in a plane (default: seed 004's capsule — two 10 cm
semicircles and two 40 cm lines on the plane z = 0.50 m, its fig. 14), with the tool pointing
down, along another fixed axis, or free (:mod:`legcore.studies.path_tracking.params`). The tool
runs it with a time law whose decision variables are the cruise speed of every segment (or one
speed for all), the start/stop ramp times t_a, t_d and the blend time t_b of the speed changes
between segments (:mod:`legcore.studies.path_tracking.timelaw`). Any serial arm of ≥ 5 joints
that can reach the path does (DH or URDF; redundant arms resolved toward a rest posture).

When the problem is built, the IK of the whole path is solved once and interpolated in arc
length (:mod:`legcore.studies.path_tracking.joints`: q(σ) and its σ-derivatives; checked to
1e-8 m on the path). For a whole population at once the problem then

1. builds every candidate's arc-length law σ(t) and samples it at K = ``n_samples`` instants
   spread over its own duration (every ramp and cruise gets samples);
2. composes the joint trajectory by the chain rule, q(t) = Q(σ(t)) → q, q̇, q̈, q⃛ (B, K, n);
3. computes the joint torques by RNEA in one call (``dynamics.inverse_dynamics``) and the
   mechanical energy E = Σ_i ∫ |τ_i q̇_i| dt (``energy.mechanical_energy``, trapezoid).

Objectives (minimised, ``objective``): ``"time"`` — cycle time T (s); ``"energy"`` — E (J);
``"energy_time"`` — both (T, E). Constraints G ≤ 0 over all samples: joint speeds
``max|q̇_i| / q̇_max,i − 1``, joint accelerations ``max|q̈_i| / q̈_max,i − 1`` (``qdd_max``),
joint torques ``max|τ_i| / τ_max,i − 1``, ramps fitting inside their segments
``max_k fit_k − 1``, and with ``T_max`` the cycle time ``T / T_max − 1``.

The limits hold between the samples too (``limit_check`` > 1, every task but seed 004's
preset): every candidate is also checked just before each speed-ramp boundary and on both
sides of each segment join (:meth:`PathTrackingProblem.edge_times`: q̈ jumps there, and the
regular samples only approach the one-sided limits), a candidate within a few % of a limit
again on ``limit_check`` × K samples (the larger peaks count), and
:meth:`PathTrackingProblem.violations` reports every limit the decoded motion breaks on that
dense resampling (which joint, by how much, in its units).

Baselines: ``seed`` — the paper's own law (V = 10 cm/s on every segment, t_a = t_d = 3 s:
segment times 4.6416 / 4 / 3.1416 / 5.5 s, profiles accel · constant · constant · decel; on
another arm the same law with the derived reference speed V), and ``seed_max_V`` — the same
scheme at the largest single V that satisfies every constraint. The front's % changes are
computed against the seed law only when it is feasible (else None, with the reason).

Defaults relative to the arm (the path scaled to its reach, placed where it is well
conditioned, a tool orientation it holds): :mod:`legcore.studies.path_tracking.defaults`;
seed 004's own settings: :mod:`legcore.studies.path_tracking.preset`.
"""

from __future__ import annotations

import math
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore import kinematics
from legcore.dynamics import inverse_dynamics
from legcore.energy import mechanical_energy
from legcore.joint_metrics import joint_metrics
from legcore.problems.base import constraint_violation
from legcore.robots.capabilities import Needs
from legcore.robots.model import Robot
from legcore.studies.path_tracking import limits
from legcore.studies.path_tracking.joints import (
    JointPath,
    check_slowest_speed,
    joint_path,
    speed_caps,
)
from legcore.studies.path_tracking.kin import ArcLengthPath, compose_ppoly, peak_abs
from legcore.studies.path_tracking.params import (
    CAPSULE,
    DEFAULT_QDD_MAX,
    SEED_SEGMENT_TIMES,
    ArcSegment,
    LineSegment,
    Params,
)
from legcore.studies.path_tracking.timelaw import (
    RampShape,
    TimeLaw,
    build_time_law,
    segment_profiles,
)
from legcore.studies.study import Motion, Solution, StudyProblem
from legcore.studies.task import Violation
from legcore.trajectories.sampling import compose_time_law

__all__ = [
    "CAPSULE",
    "DEFAULT_QDD_MAX",
    "NEEDS",
    "SEED_SEGMENT_TIMES",
    "ArcSegment",
    "LineSegment",
    "Params",
    "PathTrackingProblem",
]

FloatArray = NDArray[np.float64]

#: What the study needs from a robot: a serial arm of at least 5 actuated joints.
NEEDS = Needs(serial=True, min_joints=5)

_RAMP_SAMPLES = 10  # time samples at least inside every speed ramp


def _cumulative_trapezoid(y: FloatArray, t: FloatArray) -> FloatArray:
    """∫_0^t y dt (K,) by the trapezoid rule on samples ``y`` (K,) at times ``t`` (K,)."""
    return np.concatenate([[0.0], np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(t))])


def _per_joint(
    value: float | tuple[float, ...] | str | None, robot: Robot, name: str
) -> FloatArray:
    """A per-joint acceleration limit (n,) from one value, one per joint, None (inf) or
    ``"robot"``: the robot's ``qdd_max``, :data:`DEFAULT_QDD_MAX` where it has none."""
    if value is None:
        return np.full(robot.nq, np.inf)
    if value == "robot":
        return np.where(np.isfinite(robot.qdd_max), robot.qdd_max, DEFAULT_QDD_MAX)
    if isinstance(value, tuple):
        if len(value) != robot.nq:
            raise ValueError(f"{name}: {len(value)} values for the {robot.nq} joints of "
                             f"{robot.name} (give one value, or one per joint)")
        return np.asarray(value, dtype=float)
    return np.full(robot.nq, float(value))


class PathTrackingProblem(StudyProblem):
    """Timing of a fixed path run by an arm (see the module docstring).

    Decision vector: ``speeds="per_segment"``: (V_1 … V_n, t_a, t_d[, t_b]) — t_b only when
    n > 1; ``speeds="single"``: (V, t_a, t_d). m/s and s. ``variable_names`` lists them;
    ``constraint_names`` the columns of G. ``joints``: the arm's joints along the path
    (:class:`~legcore.studies.path_tracking.joints.JointPath`); ``qdd_max`` (n,) rad/s²;
    ``V_max``: the upper bounds of the speeds in the decision box (``speed_caps``).
    """

    def __init__(self, robot: Robot, params: Params) -> None:
        if not isinstance(robot, Robot) or robot.nq < 5:
            raise ValueError(
                f"robot: path_tracking needs a serial arm of ≥ 5 actuated joints; robot "
                f"{getattr(robot, 'name', robot)} has {getattr(robot, 'nq', 'no serial chain')}"
            )
        if not params.concrete():
            raise ValueError("segments: the robot-relative parameters are not derived yet "
                             "(build through Study.build / legcore.run)")
        assert params.segments is not None and params.V_bounds is not None
        self.robot = robot
        self.params = params
        self.path = ArcLengthPath(tuple(s.curve() for s in params.segments), params.plane())
        self.tool = params.tool()
        self.qdd_max = _per_joint(params.qdd_max, robot, "qdd_max")
        rest = robot.home if params.rest is None else np.asarray(params.rest, dtype=float)
        if rest.shape != (robot.nq,):
            raise ValueError(f"rest: {rest.size} values for the {robot.nq} joints of "
                             f"{robot.name}")
        if not robot.within_limits(rest, tol=0.0):
            raise ValueError(f"rest: {np.round(rest, 4).tolist()} rad is outside the joint "
                             f"limits of {robot.name}")
        self.rest = rest
        self.n_seg = len(params.segments)
        self.n_samples = params.n_samples
        n = self.n_seg
        if params.speeds == "single":
            names = ["V", "t_a", "t_d"]
        else:
            names = [f"V_{k + 1}" for k in range(n)] + ["t_a", "t_d"] + (["t_b"] if n > 1 else [])
        self.variable_names: tuple[str, ...] = tuple(names)
        self.joints: JointPath = joint_path(robot, self.path, self.tool, rest)
        check_slowest_speed(self.joints, self.path, robot, params.V_bounds[0])
        caps = speed_caps(self.joints, robot.qd_max, params.V_bounds)
        self.V_max = np.array([caps.min()]) if params.speeds == "single" else caps
        n_v = self.V_max.size
        xl = [params.V_bounds[0]] * n_v + [params.ramp_bounds[0]] * (len(names) - n_v)
        xu = self.V_max.tolist() + [params.ramp_bounds[1]] * (len(names) - n_v)
        joints = [f"q{i + 1}" for i in range(robot.nq)]
        cons = [f"{lim}.{j}" for lim in ("qd_max", "qdd_max", "tau_max") for j in joints]
        cons.append("ramps_fit")
        if params.T_max is not None:
            cons.append("T_max")
        self.constraint_names: tuple[str, ...] = tuple(cons)
        self.objective_names = {
            "time": ("time",),
            "energy": ("energy",),
            "energy_time": ("time", "energy"),
        }[params.objective]
        super().__init__(
            len(names),
            len(self.objective_names),
            len(cons),
            xl=xl,
            xu=xu,
            name=f"path_tracking[{robot.name}]",
        )
        # load the evaluation's numba kernels now: the first evaluate() is measured by
        # legcore.memory (tracemalloc) and must see arrays, not numba's cache loader
        self._evaluate(self.seed_x()[None])

    # ------------------------------------------------------------------ decoding of X
    def split(self, X: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """(B, n_var) → segment speeds V (B, n) m/s, t_a, t_d, t_b (B,) s."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        n = self.n_seg
        if self.params.speeds == "single":
            V = np.repeat(X[:, :1], n, axis=1)
            return V, X[:, 1], X[:, 2], np.zeros(X.shape[0])
        t_b = X[:, n + 2] if n > 1 else np.zeros(X.shape[0])
        return X[:, :n], X[:, n], X[:, n + 1], t_b

    def seed_x(self, V: float | None = None) -> FloatArray:
        """The seed's law as a decision vector: one speed ``V`` (default ``params.V``) on every
        segment, ``params.t_a``/``t_d``; t_b (irrelevant at equal speeds) = its lower bound."""
        p = self.params
        assert p.V is not None
        v = p.V if V is None else V
        if p.speeds == "single":
            return np.array([v, p.t_a, p.t_d])
        tail = [p.ramp_bounds[0]] if self.n_seg > 1 else []
        return np.array([v] * self.n_seg + [p.t_a, p.t_d] + tail)

    def time_law(self, X: FloatArray, shape: RampShape | None = None) -> TimeLaw:
        """The arc-length laws of a batch (``shape`` overrides ``params.ramp``)."""
        V, t_a, t_d, t_b = self.split(X)
        return build_time_law(self.path.lengths, V, t_a, t_d, t_b, shape or self.params.ramp)

    # ------------------------------------------------------------------ batch simulation
    def simulate(
        self, X: FloatArray, shape: RampShape | None = None, full: bool = True,
        samples: int | None = None, extra_times: bool = False,
    ) -> dict[str, Any]:
        """Whole-batch motion: ``t`` (B, K) s, tool ``p``/``pd``/``pdd``/``pddd`` (B, K, 3),
        ``q``/``qd``/``qdd``/``jerk``/``tau`` (B, K, n), ``law``, ``E`` (B,) J, ``E_joint``
        (B, n) J, ``T`` (B,) s, and ``G`` (B, n_constr) on these K samples (``samples``,
        default ``n_samples``; with ``extra_times`` also the instants just before every
        phase boundary and just before and after every segment join, where q̈ jumps:
        :meth:`edge_times`). ``full=False`` (the evaluation): no tool path, and
        ``E``/``E_joint`` only when an objective is the energy. The joints by one numba pass
        (``compose_ppoly``), equal to ``compose_time_law(self.joints.derivatives(σ),
        σ-derivatives)``."""
        law = self.time_law(X, shape)
        B, n = law.T.shape[0], self.robot.nq
        if samples == 0:
            t = np.sort(self.edge_times(law), axis=1)
        else:
            t = law.sample_times(self.n_samples if samples is None else int(samples),
                                 _RAMP_SAMPLES)
            if extra_times:
                t = np.sort(np.concatenate([t, self.edge_times(law)], axis=1), axis=1)
        K = t.shape[1]
        sig = law.evaluate(t)  # (4, B, K)
        s4 = sig.reshape(4, B * K)
        Q = compose_ppoly(self.joints.poly, s4).reshape(4, B, K, n)
        q, qd, qdd, jerk = Q
        tau = inverse_dynamics(self.robot, q, qd, qdd)
        r = self.robot
        G = [peak_abs(qd) / r.qd_max - 1.0, peak_abs(qdd) / self.qdd_max - 1.0,
             peak_abs(tau) / r.tau_max - 1.0, (law.fit.max(axis=1) - 1.0)[:, None]]
        if self.params.T_max is not None:
            G.append((law.T / self.params.T_max - 1.0)[:, None])
        Gm = np.concatenate(G, axis=1)
        Gm = np.where(np.isfinite(Gm), Gm, 1e6)
        out = {
            "law": law, "t": t, "q": q, "qd": qd, "qdd": qdd, "jerk": jerk, "tau": tau,
            "T": law.T, "G": Gm,
        }
        regular = samples is None and not extra_times  # the objective's own samples
        if full or ("energy" in self.objective_names and regular):
            en = mechanical_energy(qd, tau, t)
            out.update(E=en.total, E_joint=en.per_joint)
        if full:
            P = compose_time_law(self.path.derivatives(s4[0]), s4).reshape(4, B, K, 3)
            out.update(p=P[0], pd=P[1], pdd=P[2], pddd=P[3])
        return out

    def _objectives(self, sim: dict[str, Any]) -> FloatArray:
        key = {"time": "T", "energy": "E"}
        return np.stack([sim[key[name]] for name in self.objective_names], axis=1)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        sim = self.simulate(X, full=False)
        G = sim["G"]
        if self.params.limit_check > 1:
            G = self._dense_limits(X, G, self.params.limit_check)
        return self._objectives(sim), G

    def edge_times(self, law: TimeLaw) -> FloatArray:
        """(B, E) instants where the joint accelerations jump (:func:`.limits.edge_times`)."""
        return limits.edge_times(self, law)

    def _dense_limits(self, X: FloatArray, G: FloatArray, factor: int,
                      shape: RampShape | None = None, every: bool = False) -> FloatArray:
        return limits.dense_limits(self, X, G, factor, shape, every)

    # ------------------------------------------------------------------ decoding
    def solution(self, x: FloatArray, shape: RampShape | None = None) -> Solution:
        """One decision vector decoded: the full Motion, metrics, per-joint table, extras."""
        x = np.asarray(x, dtype=float).reshape(1, -1)
        if x.shape[1] != self.n_var:
            raise ValueError(f"x: expected {self.n_var} values {self.variable_names}, "
                             f"got {x.shape[1]}")
        sim = self.simulate(x, shape)
        law: TimeLaw = sim["law"]
        t = sim["t"][0]
        q, qd, qdd, jerk, tau = (sim[k][0] for k in ("q", "qd", "qdd", "jerk", "tau"))
        T_tool = kinematics.fk(self.robot, q)
        tool = T_tool[:, :3, 3]
        power = tau * qd
        energy = _cumulative_trapezoid(np.abs(power).sum(axis=1), t)
        G = sim["G"][0]
        if self.params.limit_check > 1:
            G = self._dense_limits(x, sim["G"], self.params.limit_check, shape)[0]
        cv = float(constraint_violation(G[None, :])[0])
        seg_T = law.segment_times()[0]
        V, t_a, t_d, t_b = (a[0] for a in self.split(x))
        jm = joint_metrics(t, q, tau, qd=qd, qdd=qdd, jerk=jerk, tool_pos=tool)
        table: list[dict[str, Any]] = [
            {"metric": row.label, "key": row.key, "unit": row.unit, "values": list(row.per_joint)}
            for row in jm.as_table() if row.per_joint is not None
        ]
        table += [
            {"metric": "q_min", "key": "q_min", "unit": "rad", "values": q.min(axis=0).tolist()},
            {"metric": "q_max", "key": "q_max", "unit": "rad", "values": q.max(axis=0).tolist()},
            {"metric": "ω_max/ω_lim", "key": "qd_use", "unit": "1",
             "values": (jm.omega_max / self.robot.qd_max).tolist()},
            {"metric": "α_max/α_lim", "key": "qdd_use", "unit": "1",
             "values": (np.abs(qdd).max(axis=0) / self.qdd_max).tolist()},
            {"metric": "τ_max/τ_lim", "key": "tau_use", "unit": "1",
             "values": (jm.tau_max / self.robot.tau_max).tolist()},
        ]
        T, E = float(sim["T"][0]), float(sim["E"][0])
        metrics: dict[str, float] = {
            "time": T,
            "energy": E,
            "feasible": float(cv <= 0.0),
            "cv": cv,
            "path_length": float(jm.path_length),
            "theta_total": float(jm.theta_total),
            "tool_speed_max": float(np.linalg.norm(sim["pd"][0], axis=1).max()),
            "qd_use_max": float(np.max(jm.omega_max / self.robot.qd_max)),
            "qdd_use_max": float(np.max(np.abs(qdd).max(axis=0) / self.qdd_max)),
            "tau_use_max": float(np.max(jm.tau_max / self.robot.tau_max)),
            "t_a": float(t_a),
            "t_d": float(t_d),
            "t_b": float(t_b),
            "ramp_shrink": float(law.shrink[0]),
        }
        for k in range(self.n_seg):
            metrics[f"T_{k + 1}"] = float(seg_T[k])
            metrics[f"V_{k + 1}"] = float(V[k])
        e_path, e_rot = self.tool.errors(T_tool, sim["p"][0])
        motion = Motion(
            t=t,
            q=q,
            joint_names=tuple(self.robot.model.names[1:]),
            qd=qd,
            qdd=qdd,
            jerk=jerk,
            tau=tau,
            power=power,
            energy=energy,
            tool=tool,
            robot=self.robot.name,
            scene={"path": self.path.polyline(), "targets": self.path.joins},
        )
        extra = {
            "variable_names": list(self.variable_names),
            "segment_times": seg_T.tolist(),
            "segment_speeds": V.tolist(),
            "segment_profiles": segment_profiles(V),
            "ramp": shape or self.params.ramp,
            "orientation": self.tool.describe(),
            "rest": self.rest.tolist(),
            "qdd_max": self.qdd_max.tolist(),
            "constraints": dict(zip(self.constraint_names, G.tolist(), strict=True)),
            "energy_per_joint": sim["E_joint"][0].tolist(),
            "orientation_error": float(e_rot.max()),
            "path_error": float(e_path.max()),
        }
        objectives = {name: metrics[name] for name in self.objective_names}
        return Solution(x=x[0].copy(), objectives=objectives, metrics=metrics, table=table,
                        motion=motion, extra=extra)

    def violations(self, x: FloatArray) -> tuple[Violation, ...]:
        """Every limit the motion of ``x`` breaks, on its samples and on a resampling of at
        least 10 × ``n_samples`` and the instants where q̈ jumps (so between the optimiser's
        samples too): which joint, its peak and its limit in rad/s, rad/s² or N·m; the ramps'
        overrun; the cycle time (:func:`.limits.limit_violations`)."""
        return limits.limit_violations(self, x)

    # ------------------------------------------------------------------ baselines
    @cached_property
    def seed_max_V(self) -> float:
        """Largest single V (m/s) for which the seed's scheme (t_a, t_d of ``params``, linear
        ramps) satisfies every constraint; found by two batched scans of the V box."""
        assert self.params.V_bounds is not None
        lo, hi = self.params.V_bounds
        best = float("nan")
        for _ in range(3):
            Vs = np.linspace(lo, hi, 41)
            X = np.stack([self.seed_x(v) for v in Vs])
            G = self.simulate(X, "linear", full=False)["G"]
            if self.params.limit_check > 1:
                G = self._dense_limits(X, G, self.params.limit_check, "linear")
            ok = np.all(G <= 0.0, axis=1)
            if not ok.any():
                break
            i = int(np.flatnonzero(ok).max())
            best = float(Vs[i])
            if i == Vs.size - 1:
                break
            lo, hi = Vs[i], Vs[i + 1]
        return best

    def baseline_solutions(self) -> dict[str, Solution]:
        """``seed``: the paper's law; ``seed_max_V``: the same scheme at the fastest feasible V
        (both with the seed's linear ramps)."""
        out = {"seed": self.solution(self.seed_x(), "linear")}
        v = self.seed_max_V
        if math.isfinite(v):
            out["seed_max_V"] = self.solution(self.seed_x(v), "linear")
        return out

    def extras(self, front_X: FloatArray, front_F: FloatArray) -> dict[str, Any]:
        """The front in readable form with the % change of each objective against the seed
        law — only when that law is feasible on this arm (else None, and ``change_pct_reason``
        says which limits it breaks)."""
        x_seed = self.seed_x()
        seed = self._objectives(self.simulate(x_seed[None, :], "linear"))[0]
        broken = self._seed_violations()
        rows = []
        for x, f in zip(np.atleast_2d(front_X), np.atleast_2d(front_F), strict=True):
            row: dict[str, Any] = {
                name: float(v) for name, v in zip(self.variable_names, x, strict=True)}
            row |= {name: float(v) for name, v in zip(self.objective_names, f, strict=True)}
            row |= {f"{name}_change_pct": None if broken else float(100.0 * (v / s - 1.0))
                    for name, v, s in zip(self.objective_names, f, seed, strict=True)}
            rows.append(row)
        rows.sort(key=lambda r: r[self.objective_names[0]])
        out: dict[str, Any] = {
            "seed_objectives": dict(zip(self.objective_names, seed.tolist(), strict=True)),
            "seed_feasible": not broken,
            "seed_max_V": self.seed_max_V,
            "front": rows,
        }
        if broken:
            out["change_pct_reason"] = (
                "no % change: the reference (the paper's time law) is infeasible on "
                f"{self.robot.name}: " + "; ".join(v.text for v in broken))
        return out

    def _seed_violations(self) -> tuple[Violation, ...]:
        """What the seed law (linear ramps) violates on this arm (cached)."""
        cached: tuple[Violation, ...] | None = getattr(self, "_seed_broken", None)
        if cached is None:
            cached = limits.limit_violations(self, self.seed_x(), "linear")
            self._seed_broken = cached
        return cached
