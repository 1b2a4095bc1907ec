"""``path_tracking`` — seed 004: a composite 2D path traced by the 5-DOF arm, tool pointing down.

The path is a chain of lines and arcs in a plane (default: seed 004's capsule — two 10 cm
semicircles and two 40 cm lines on the plane z = 0.50 m, its fig. 14). The tool runs it with a
time law whose decision variables are the cruise speed of every segment (or one speed for all),
the start/stop ramp times t_a, t_d and the blend time t_b of the speed changes between segments
(:mod:`legcore.problems.path_tracking_timelaw`). For a whole population at once the problem

1. builds every candidate's arc-length law σ(t) and samples it at K = ``n_samples`` instants
   evenly spread over its own duration;
2. evaluates the path and its σ-derivatives there and composes tool position, velocity,
   acceleration and jerk (B, K, 3);
3. solves the closed-form IK of the arm with the tool pointing down (``kinematics.ik``, family
   ``arm5_down``) for all B·K points in one call and differentiates it exactly
   (:func:`~legcore.problems.path_tracking_kin.arm5_down_rates`) → q, q̇, q̈, q⃛ (B, K, 5);
4. computes the joint torques by RNEA in one call (``dynamics.inverse_dynamics``) and the
   mechanical energy E = Σ_i ∫ |τ_i q̇_i| dt (``energy.mechanical_energy``, trapezoid).

Objectives (minimised, ``objective``): ``"time"`` — cycle time T (s); ``"energy"`` — E (J);
``"energy_time"`` — both (T, E). Constraints G ≤ 0 over all samples: joint speeds
``max|q̇_i| / q̇_max,i − 1``, joint torques ``max|τ_i| / τ_max,i − 1``, ramps fitting inside
their segments ``max_k fit_k − 1``, and with ``T_max`` the cycle time ``T / T_max − 1``.

Baselines: ``seed`` — the paper's own law (V = 10 cm/s on every segment, t_a = t_d = 3 s:
segment times 4.6416 / 4 / 3.1416 / 5.5 s, profiles accel · constant · constant · decel), and
``seed_max_V`` — the same scheme at the largest single V that satisfies every constraint.
"""

from __future__ import annotations

import math
from functools import cached_property
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator

from legcore import kinematics
from legcore.dynamics import inverse_dynamics
from legcore.energy import mechanical_energy
from legcore.ik.arm5 import arm5_geometry
from legcore.joint_metrics import joint_metrics
from legcore.problems.base import constraint_violation
from legcore.problems.path_tracking_kin import ArcLengthPath, arm5_down_rates
from legcore.problems.path_tracking_timelaw import RampShape, TimeLaw, build_time_law
from legcore.problems.study import Motion, Solution, Study, StudyParams, StudyProblem
from legcore.robots.model import Robot
from legcore.trajectories.paths import JOIN_TOL, Arc, Line, Plane
from legcore.trajectories.sampling import compose_time_law

__all__ = ["ArcSegment", "LineSegment", "Params", "PathTrackingProblem", "STUDY", "build"]

FloatArray = NDArray[np.float64]
Finite = Annotated[float, Field(allow_inf_nan=False)]
Point2 = tuple[Finite, Finite]
Point3 = tuple[Finite, Finite, Finite]

#: Seed 004 §V in SI: the capsule's segments in plane coordinates (m, rad).
SEED_SEGMENT_TIMES = (1.5 + math.pi, 4.0, math.pi, 5.5)  # s: 4.6416, 4, 3.1416, 5.5
SEED_V, SEED_T_A, SEED_T_D = 0.10, 3.0, 3.0  # m/s, s, s

_MIN_RADIUS = 1e-3  # m: wrist distance from the base axis below which the path is singular
_MIN_SIN_ELBOW = 1e-3  # |sin θ3| below which the elbow is (nearly) straight or folded
_CHECK_POINTS = 400  # IK points per segment checked when the problem is built
_RAMP_SAMPLES = 10  # time samples at least inside every speed ramp


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class LineSegment(_Strict):
    """Straight segment from ``start`` to ``end`` (plane coordinates u, v in m; seed eq 14)."""

    type: Literal["line"] = "line"
    start: Point2
    end: Point2

    @model_validator(mode="after")
    def _length(self) -> LineSegment:
        if math.dist(self.start, self.end) <= 1e-9:
            raise ValueError("start and end must differ (a line needs a length > 0)")
        return self

    def curve(self) -> Line:
        return Line(np.array(self.start), np.array(self.end))


class ArcSegment(_Strict):
    """Arc about ``center`` (u, v m) of radius ``r`` (m) from angle ``beta`` sweeping ``phi``
    (rad, > 0 counter-clockwise about the plane normal; seed eq 17)."""

    type: Literal["arc"] = "arc"
    center: Point2
    r: Finite = Field(gt=0.0)
    beta: Finite
    phi: Finite = Field(ge=-2.0 * math.pi, le=2.0 * math.pi)

    @model_validator(mode="after")
    def _sweep(self) -> ArcSegment:
        if abs(self.phi) < 1e-9:
            raise ValueError("phi must be non-zero (an arc needs a sweep)")
        return self

    def curve(self) -> Arc:
        return Arc(np.array(self.center), self.r, self.beta, self.phi)


PathSegment = Annotated[LineSegment | ArcSegment, Field(discriminator="type")]

CAPSULE: tuple[LineSegment | ArcSegment, ...] = (
    ArcSegment(center=(0.20, 0.30), r=0.10, beta=-math.pi / 2, phi=math.pi),
    LineSegment(start=(0.20, 0.40), end=(-0.20, 0.40)),
    ArcSegment(center=(-0.20, 0.30), r=0.10, beta=math.pi / 2, phi=math.pi),
    LineSegment(start=(-0.20, 0.20), end=(0.20, 0.20)),
)


class Params(StudyParams):
    """Parameters of the ``path_tracking`` study (defaults: seed 004's own settings).

    - ``segments``: the path, consecutive lines/arcs in plane coordinates (m, rad); default the
      seed's capsule (arcs r = 0.10 m about (±0.20, 0.30) m, lines at v = 0.40 and 0.20 m,
      counter-clockwise from (0.20, 0.20) m). Each segment must start where the previous ends.
    - ``plane_origin``, ``plane_e1``, ``plane_e2``: the plane in the world (m; orthonormal axes);
      default the horizontal plane z = 0.50 m ("a una altura de 50cm").
    - ``objective``: ``"time"`` (T), ``"energy"`` (E) or ``"energy_time"`` (both).
    - ``speeds``: ``"per_segment"`` (one cruise speed per segment + t_a, t_d, t_b) or
      ``"single"`` (one speed, t_a, t_d — the seed's scheme).
    - ``ramp``: speed-ramp shape, ``"linear"`` (the seed's trapezoid) or ``"cubic"``.
    - ``V``, ``t_a``, ``t_d``: the seed's law (m/s, s, s) used as the ``seed`` baseline.
    - ``V_bounds`` (m/s), ``ramp_bounds`` (s, for t_a, t_d, t_b): the decision box.
    - ``T_max``: optional cycle-time cap (s), a constraint.
    - ``n_samples``: time samples per candidate trajectory (evaluation and decoding).
    - ``branch``: IK branch of the arm (``"front-up"``: elbow up, facing the path).
    - ``tool_yaw``: None keeps joint 5 at 0 (the paper); a heading (rad) holds the tool's x axis
      fixed in the world (joint 5 then turns with the base).
    """

    kind: Literal["path_tracking"] = "path_tracking"
    segments: tuple[PathSegment, ...] = Field(default=CAPSULE, min_length=1, max_length=64)
    plane_origin: Point3 = (0.0, 0.0, 0.50)
    plane_e1: Point3 = (1.0, 0.0, 0.0)
    plane_e2: Point3 = (0.0, 1.0, 0.0)
    objective: Literal["time", "energy", "energy_time"] = "time"
    speeds: Literal["per_segment", "single"] = "per_segment"
    ramp: Literal["linear", "cubic"] = "linear"
    V: Finite = Field(default=SEED_V, gt=0.0)
    t_a: Finite = Field(default=SEED_T_A, gt=0.0)
    t_d: Finite = Field(default=SEED_T_D, gt=0.0)
    V_bounds: tuple[Finite, Finite] = (0.01, 1.0)
    ramp_bounds: tuple[Finite, Finite] = (0.005, 5.0)
    T_max: Finite | None = Field(default=None, gt=0.0)
    n_samples: int = Field(default=400, ge=20, le=20_000)
    branch: Literal["front-up", "front-down", "back-up", "back-down"] = "front-up"
    tool_yaw: Finite | None = None

    @model_validator(mode="after")
    def _check(self) -> Params:
        for name in ("V_bounds", "ramp_bounds"):
            lo, hi = getattr(self, name)
            if not 0.0 < lo <= hi:
                raise ValueError(f"{name}: need 0 < lower <= upper, got ({lo}, {hi})")
        try:
            self.plane()
        except ValueError as exc:
            raise ValueError(f"plane_e1/plane_e2: {exc}") from None
        curves = [s.curve() for s in self.segments]
        for k in range(1, len(curves)):
            gap = float(np.linalg.norm(curves[k - 1].end - curves[k].start))
            if gap > JOIN_TOL:
                raise ValueError(
                    f"segments.{k}: starts {gap:.3g} m away from the end of segments.{k - 1} "
                    f"(at {np.round(curves[k - 1].end, 6).tolist()} m)"
                )
        return self

    def plane(self) -> Plane:
        return Plane(np.array(self.plane_origin), np.array(self.plane_e1), np.array(self.plane_e2))


def _cumulative_trapezoid(y: FloatArray, t: FloatArray) -> FloatArray:
    """∫_0^t y dt (K,) by the trapezoid rule on samples ``y`` (K,) at times ``t`` (K,)."""
    return np.concatenate([[0.0], np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(t))])


class PathTrackingProblem(StudyProblem):
    """Timing of a tool-down path on a 5-DOF ``arm5_down`` arm (see the module docstring).

    Decision vector: ``speeds="per_segment"``: (V_1 … V_n, t_a, t_d[, t_b]) — t_b only when
    n > 1; ``speeds="single"``: (V, t_a, t_d). m/s and s. ``variable_names`` lists them;
    ``constraint_names`` the columns of G.
    """

    def __init__(self, robot: Robot, params: Params) -> None:
        if not isinstance(robot, Robot) or robot.ik_family != "arm5_down" or robot.nq != 5:
            raise ValueError(
                f"robot: path_tracking needs a 5-DOF arm with the tool-pointing-down closed form "
                f"(ik family 'arm5_down', like articulated_5dof), got "
                f"{getattr(robot, 'name', robot)!r} with ik family "
                f"{getattr(robot, 'ik_family', None)!r}"
            )
        self.robot = robot
        self.params = params
        self.geometry = arm5_geometry(robot.spec)
        self.path = ArcLengthPath(tuple(s.curve() for s in params.segments), params.plane())
        self.n_seg = len(params.segments)
        self.heading_fixed = params.tool_yaw is not None
        self.n_samples = params.n_samples
        n = self.n_seg
        if params.speeds == "single":
            names = ["V", "t_a", "t_d"]
        else:
            names = [f"V_{k + 1}" for k in range(n)] + ["t_a", "t_d"] + (["t_b"] if n > 1 else [])
        self.variable_names: tuple[str, ...] = tuple(names)
        n_v = 1 if params.speeds == "single" else n
        xl = [params.V_bounds[0]] * n_v + [params.ramp_bounds[0]] * (len(names) - n_v)
        xu = [params.V_bounds[1]] * n_v + [params.ramp_bounds[1]] * (len(names) - n_v)
        joints = [f"q{i + 1}" for i in range(robot.nq)]
        cons = [f"qd_max.{j}" for j in joints] + [f"tau_max.{j}" for j in joints] + ["ramps_fit"]
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
        self._check_path()

    # ------------------------------------------------------------------ set-up checks
    def _ik(self, p: FloatArray) -> kinematics.IKResult:
        yaw = self.params.tool_yaw
        return kinematics.ik(self.robot, p, branch=self.params.branch, yaw=yaw)

    def _check_path(self) -> None:
        """The path is fixed, so reachability, joint limits and singularities are checked once:
        IK of ``_CHECK_POINTS`` points per segment (``ValueError`` naming the segment)."""
        D = self.path.lengths
        start = np.concatenate([[0.0], np.cumsum(D)[:-1]])
        u = np.linspace(0.0, 1.0, _CHECK_POINTS)
        sigma = (start[:, None] + D[:, None] * u[None, :]).reshape(-1)
        seg = np.repeat(np.arange(self.n_seg), _CHECK_POINTS)
        p = self.path.derivatives(sigma)[0]
        res = self._ik(p)
        name = self.robot.name

        def where(i: int) -> str:
            return f"segments.{seg[i]}: tool point {np.round(p[i], 4).tolist()} m"

        bad = np.flatnonzero(~res.reachable)
        if bad.size:
            raise ValueError(
                f"{where(bad[0])} is out of reach of {name} with the tool pointing down "
                f"(branch {self.params.branch})"
            )
        q = self._unwrap(res.q)
        out = ~self.robot.within_limits(q)
        if out.any():
            i = int(np.flatnonzero(out)[0])
            raise ValueError(
                f"{where(i)} needs q = {np.round(q[i], 4).tolist()} rad, outside the joint "
                f"limits of {name} (branch {self.params.branch})"
            )
        th = q + self.geometry.offset
        X = self.geometry.a2 * np.cos(th[:, 1]) + self.geometry.a3 * np.cos(th[:, 1] + th[:, 2])
        R = np.abs(self.geometry.a1 + X)
        if R.min() < _MIN_RADIUS:
            raise ValueError(
                f"{where(int(np.argmin(R)))} puts the wrist on the base axis of {name} "
                f"(a singularity: joint 1 would need an infinite speed)"
            )
        s3 = np.abs(np.sin(th[:, 2]))
        if s3.min() < _MIN_SIN_ELBOW:
            raise ValueError(
                f"{where(int(np.argmin(s3)))} needs a straight elbow on {name} "
                f"(a singularity at the edge of the workspace)"
            )

    @staticmethod
    def _unwrap(q: FloatArray) -> FloatArray:
        """Joint 1 and joint 5 made continuous along the sample axis (−2)."""
        q = q.copy()
        q[..., 0] = np.unwrap(q[..., 0], axis=-1)
        q[..., 4] = np.unwrap(q[..., 4], axis=-1)
        return q

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
    def simulate(self, X: FloatArray, shape: RampShape | None = None) -> dict[str, Any]:
        """Whole-batch motion: ``t`` (B, K) s, tool ``p``/``pd``/``pdd``/``pddd`` (B, K, 3),
        ``q``/``qd``/``qdd``/``jerk``/``tau`` (B, K, n), ``law``, ``E`` (B,) J, ``E_joint``
        (B, n) J, ``T`` (B,) s, and ``G`` (B, n_constr)."""
        law = self.time_law(X, shape)
        B, K = law.T.shape[0], self.n_samples
        t = law.sample_times(K, _RAMP_SAMPLES)
        sig = law.evaluate(t)  # (4, B, K)
        g = self.path.derivatives(sig[0])  # (4, B, K, 3)
        P = compose_time_law(g.reshape(4, B * K, 3), sig.reshape(4, B * K)).reshape(4, B, K, 3)
        res = self._ik(P[0])
        q = self._unwrap(res.q)
        qd, qdd, jerk = arm5_down_rates(self.geometry, q, P[1], P[2], P[3], self.heading_fixed)
        ok = np.isfinite(q).all() and np.isfinite(qd).all() and np.isfinite(qdd).all()
        if not ok:  # only for a point between the build-time checks: never let NaN escape
            q, qd, qdd, jerk = (np.nan_to_num(a, nan=0.0, posinf=1e6, neginf=-1e6)
                                for a in (q, qd, qdd, jerk))
        tau = inverse_dynamics(self.robot, q, qd, qdd)
        en = mechanical_energy(qd, tau, t)
        r = self.robot
        G = [np.abs(qd).max(axis=1) / r.qd_max - 1.0, np.abs(tau).max(axis=1) / r.tau_max - 1.0,
             (law.fit.max(axis=1) - 1.0)[:, None]]
        if self.params.T_max is not None:
            G.append((law.T / self.params.T_max - 1.0)[:, None])
        Gm = np.concatenate(G, axis=1)
        Gm = np.where(np.isnan(Gm), 1e6, Gm)
        if not ok:
            Gm[~res.reachable.all(axis=1)] = np.maximum(Gm[~res.reachable.all(axis=1)], 1e6)
        return {
            "law": law, "t": t, "p": P[0], "pd": P[1], "pdd": P[2], "pddd": P[3],
            "q": q, "qd": qd, "qdd": qdd, "jerk": jerk, "tau": tau,
            "E": en.total, "E_joint": en.per_joint, "T": law.T, "G": Gm,
        }

    def _objectives(self, sim: dict[str, Any]) -> FloatArray:
        cols = {"time": sim["T"], "energy": sim["E"]}
        return np.stack([cols[name] for name in self.objective_names], axis=1)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        sim = self.simulate(X)
        return self._objectives(sim), sim["G"]

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
            "tau_use_max": float(np.max(jm.tau_max / self.robot.tau_max)),
            "t_a": float(t_a),
            "t_d": float(t_d),
            "t_b": float(t_b),
            "ramp_shrink": float(law.shrink[0]),
        }
        for k in range(self.n_seg):
            metrics[f"T_{k + 1}"] = float(seg_T[k])
            metrics[f"V_{k + 1}"] = float(V[k])
        down = T_tool[:, :3, 2]
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
            "segment_profiles": self._profiles(V),
            "ramp": shape or self.params.ramp,
            "branch": self.params.branch,
            "constraints": dict(zip(self.constraint_names, G.tolist(), strict=True)),
            "energy_per_joint": sim["E_joint"][0].tolist(),
            "tool_down_error": float(np.abs(down - [0.0, 0.0, -1.0]).max()),
            "path_error": float(np.abs(tool - sim["p"][0]).max()),
        }
        objectives = {name: metrics[name] for name in self.objective_names}
        return Solution(x=x[0].copy(), objectives=objectives, metrics=metrics, table=table,
                        motion=motion, extra=extra)

    def _profiles(self, V: FloatArray) -> list[str]:
        """Per segment, its pieces of the speed law: accel/decel at the ends, blend-in/out where
        the cruise speed changes, constant while cruising (seed 004 names its s_k this way)."""
        out = []
        n = self.n_seg
        for k in range(n):
            parts = []
            if k == 0:
                parts.append("accel")
            elif V[k - 1] != V[k]:
                parts.append("blend-in")
            parts.append("constant")
            if k == n - 1:
                parts.append("decel")
            elif V[k + 1] != V[k]:
                parts.append("blend-out")
            out.append(" + ".join(parts))
        return out

    # ------------------------------------------------------------------ baselines
    @cached_property
    def seed_max_V(self) -> float:
        """Largest single V (m/s) for which the seed's scheme (t_a, t_d of ``params``, linear
        ramps) satisfies every constraint; found by two batched scans of the V box."""
        lo, hi = self.params.V_bounds
        best = float("nan")
        for _ in range(3):
            Vs = np.linspace(lo, hi, 41)
            X = np.stack([self.seed_x(v) for v in Vs])
            ok = np.all(self.simulate(X, "linear")["G"] <= 0.0, axis=1)
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
        """The front in readable form with the % change of each objective against the seed."""
        seed = self._objectives(self.simulate(self.seed_x()[None, :], "linear"))[0]
        rows = []
        for x, f in zip(np.atleast_2d(front_X), np.atleast_2d(front_F), strict=True):
            row = {name: float(v) for name, v in zip(self.variable_names, x, strict=True)}
            row |= {name: float(v) for name, v in zip(self.objective_names, f, strict=True)}
            row |= {f"{name}_change_pct": float(100.0 * (v / s - 1.0))
                    for name, v, s in zip(self.objective_names, f, seed, strict=True)}
            rows.append(row)
        rows.sort(key=lambda r: r[self.objective_names[0]])
        return {
            "seed_objectives": dict(zip(self.objective_names, seed.tolist(), strict=True)),
            "seed_max_V": self.seed_max_V,
            "front": rows,
        }


def build(robot: Any, params: Any) -> PathTrackingProblem:
    """``Study.build``: the problem for ``robot`` (an ``arm5_down`` arm) and ``params``."""
    if not isinstance(params, Params):
        params = Params.model_validate(params)
    return PathTrackingProblem(robot, params)


STUDY = Study(
    kind="path_tracking",
    title="Timing of a composite 2D line/arc path on a 5-DOF arm, tool pointing down (seed 004)",
    seed_paper="004",
    params=Params,
    default_robot="articulated_5dof",
    default_optimizer={"kind": "nsga2", "params": {"pop_size": 40}},
    default_generations=60,
    build=build,
    robot_kinds=("serial",),
)
