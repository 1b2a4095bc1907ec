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
preset; with a speed profile always): every candidate is also checked just before each
speed-ramp boundary and on both sides of each segment join
(:meth:`PathTrackingProblem.edge_times`: q̈ jumps there, and the regular samples only approach
the one-sided limits), a candidate within a few % of a limit again on ``limit_check`` × K
samples (the larger peaks count), and
:meth:`PathTrackingProblem.violations` reports every limit the decoded motion breaks on that
dense resampling (which joint, by how much, in its units).

With ``speeds="profile"`` the decision variables are instead the tool's speed at knots along
the path (:mod:`legcore.studies.path_tracking.encodings`), an encoding that can represent the
time-optimal profile; the population then starts from TOPP-RA's profile on those knots.

Baselines: ``time_optimal`` — the physical minimum: TOPP-RA's time-optimal profile of the same
joint path under the same limits, on a fine grid, tightened until it holds them on a dense
resampling (:mod:`legcore.studies.path_tracking.optimal`), for every task; ``seed`` — the
paper's own law (V = 10 cm/s on every segment, t_a = t_d = 3 s: segment times 4.6416 / 4 /
3.1416 / 5.5 s, profiles accel · constant · constant · decel; on another arm the same law
with the derived reference speed V), and ``seed_max_V`` — the same scheme at the largest
single V that satisfies every constraint. The front's % changes are computed against the seed
law only when it is feasible (else None, with the reason).

Defaults relative to the arm (the path scaled to its reach, placed where it is well
conditioned, a tool orientation it holds): :mod:`legcore.studies.path_tracking.defaults`;
seed 004's own settings: :mod:`legcore.studies.path_tracking.preset`.
"""

from __future__ import annotations

from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore.dynamics import inverse_dynamics
from legcore.energy import mechanical_energy
from legcore.robots.capabilities import Needs
from legcore.robots.model import Robot
from legcore.studies.path_tracking import baselines, decode, limits, optimal
from legcore.studies.path_tracking.contract import PhysicalMinimum
from legcore.studies.path_tracking.encodings import SegmentSpeeds, SpeedProfile, profile_knots
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
from legcore.studies.path_tracking.timelaw import RampShape, TimeLaw
from legcore.studies.study import Solution, StudyProblem
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
    n > 1; ``speeds="single"``: (V, t_a, t_d); ``speeds="profile"``: (v_1 … v_{M−1}), the
    speeds at the interior ``knots``. m/s and s. ``encoding`` turns them into time laws;
    ``variable_names`` lists them; ``constraint_names`` the columns of G. ``joints``: the
    arm's joints along the path (:class:`~legcore.studies.path_tracking.joints.JointPath`);
    ``qdd_max`` (n,) rad/s²; ``V_max``: the upper bounds of the speeds in the decision box.
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
        self.joints: JointPath = joint_path(robot, self.path, self.tool, rest)
        check_slowest_speed(self.joints, self.path, robot, params.V_bounds[0])
        #: the trapezoid coding of the seed's law (the problem's own with a ``speeds`` of
        #: ``per_segment`` or ``single``)
        self.trapezoid = SegmentSpeeds(self.path.lengths, params.speeds == "single",
                                       params.ramp)
        self.encoding: SegmentSpeeds | SpeedProfile
        if params.speeds == "profile":
            self.encoding = SpeedProfile(self.path.lengths,
                                         profile_knots(self.path.lengths,
                                                       params.profile_intervals))
            caps = optimal.knot_speed_caps(self, self.encoding.knots)
            xl, xu = self.encoding.bounds(params.V_bounds[0], caps)
        else:
            self.encoding = self.trapezoid
            xl, xu = self.trapezoid.bounds(
                params.V_bounds[0], speed_caps(self.joints, robot.qd_max, params.V_bounds),
                params.ramp_bounds)
        names = self.encoding.variable_names
        #: the limits are checked between samples (``params.limit_check``; a speed profile
        #: always: its acceleration jumps at every knot, and it has no paper's numbers to keep)
        self.limit_check = (params.limit_check if params.speeds != "profile"
                            else max(params.limit_check, limits.DENSE_CHECK))
        self.variable_names: tuple[str, ...] = names
        self.V_max = np.array(xu[: len(xu) if params.speeds == "profile" else
                                 (1 if params.speeds == "single" else self.n_seg)])
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
        """(B, n_var) → segment speeds V (B, n) m/s, t_a, t_d, t_b (B,) s (the trapezoid
        encodings only)."""
        if not isinstance(self.encoding, SegmentSpeeds):
            raise ValueError("speeds: a speed profile has no segment speeds")
        return self.encoding.split(X)

    def seed_law(self, V: FloatArray | float | None = None) -> TimeLaw:
        """The seed's law (linear ramps; t_b irrelevant at equal speeds) at one speed ``V``
        on every segment (default ``params.V``; an array: one law per value)."""
        p = self.params
        assert p.V is not None
        Vs = np.atleast_1d(np.asarray(p.V if V is None else V, dtype=float))
        X = np.stack([self.trapezoid.x_of(float(v), p.t_a, p.t_d, p.ramp_bounds[0])
                      for v in Vs])
        return self.trapezoid.law(X, "linear")

    def seed_x(self, V: float | None = None) -> FloatArray:
        """The seed's law as a decision vector: one speed ``V`` (default ``params.V``) on every
        segment, ``params.t_a``/``t_d``; t_b (irrelevant at equal speeds) = its lower bound.
        For a speed profile: the seed's speeds at the knots (its ramps interpolated)."""
        if isinstance(self.encoding, SpeedProfile):
            return self.encoding.x_of(self.seed_law(V))[0]
        p = self.params
        assert p.V is not None
        return self.encoding.x_of(p.V if V is None else V, p.t_a, p.t_d, p.ramp_bounds[0])

    def time_law(self, X: FloatArray, shape: RampShape | None = None) -> TimeLaw:
        """The arc-length laws of a batch (``shape`` overrides ``params.ramp``)."""
        return self.encoding.law(X, shape)

    # ------------------------------------------------------------------ batch simulation
    def simulate(
        self, X: FloatArray | TimeLaw, shape: RampShape | None = None, full: bool = True,
        samples: int | None = None, extra_times: bool = False,
    ) -> dict[str, Any]:
        """Whole-batch motion of decision vectors ``X`` (or of time laws): ``t`` (B, K) s,
                tool ``p``/``pd``/``pdd``/``pddd`` (B, K, 3), ``q``/``qd``/``qdd``/``jerk``/``tau``
        (B, K, n), ``law``, ``E`` (B,) J, ``E_joint``
        (B, n) J, ``T`` (B,) s, and ``G`` (B, n_constr) on these K samples (``samples``,
        default ``n_samples``; with ``extra_times`` also the instants just before every
        phase boundary and just before and after every segment join, where q̈ jumps:
        :meth:`edge_times`). ``full=False`` (the evaluation): no tool path, and
        ``E``/``E_joint`` only when an objective is the energy. The joints by one numba pass
        (``compose_ppoly``), equal to ``compose_time_law(self.joints.derivatives(σ),
        σ-derivatives)``."""
        law = X if isinstance(X, TimeLaw) else self.time_law(X, shape)
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

    def objectives(self, sim: dict[str, Any]) -> FloatArray:
        """F (B, n_obj) of a simulation (:meth:`simulate`): the cycle time T s and/or energy E J."""
        key = {"time": "T", "energy": "E"}
        return np.stack([sim[key[name]] for name in self.objective_names], axis=1)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        sim = self.simulate(X, full=False)
        G = sim["G"]
        if self.limit_check > 1:
            G = self.dense_limits(X, G, self.limit_check)
        return self.objectives(sim), G

    def edge_times(self, law: TimeLaw) -> FloatArray:
        """(B, E) instants where the joint accelerations jump (:func:`.limits.edge_times`)."""
        return limits.edge_times(self, law)

    def dense_limits(self, X: FloatArray | TimeLaw, G: FloatArray, factor: int,
                     shape: RampShape | None = None, every: bool = False) -> FloatArray:
        """G with the limits checked on a resampling ``factor`` × denser
        (:func:`.limits.dense_limits`)."""
        return limits.dense_limits(self, X, G, factor, shape, every)

    # ------------------------------------------------------------------ decoding
    def solution(self, x: FloatArray, shape: RampShape | None = None) -> Solution:
        """One decision vector decoded: the full Motion, metrics, per-joint table, extras."""
        x = np.asarray(x, dtype=float).reshape(1, -1)
        if x.shape[1] != self.n_var:
            raise ValueError(f"x: expected {self.n_var} values {self.variable_names}, "
                             f"got {x.shape[1]}")
        return self.decode_law(self.time_law(x, shape), x[0], self.encoding.metrics(x[0]), shape)

    def decode_law(self, law: TimeLaw, x: FloatArray | None = None,
               encoded: dict[str, float] | None = None, shape: RampShape | None = None
               ) -> Solution:
        """The Solution of one time ``law`` (B = 1): of the decision vector ``x`` when it has
        one in this problem's encoding (else None: a baseline of another form), ``encoded``
        what its own parameters say (t_a, V_k, …: put into the metrics)."""
        return decode.decode_law(self, law, x, encoded, shape)

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
        ramps) satisfies every constraint (:func:`.baselines.seed_max_V`)."""
        return baselines.seed_max_V(self)

    @cached_property
    def time_optimal(self) -> PhysicalMinimum | None:
        """The physical minimum: TOPP-RA's profile on a fine grid, holding every limit on a
        dense resampling (:func:`.optimal.physical_minimum`); None when none exists."""
        return optimal.physical_minimum(self)

    def baseline_solutions(self) -> dict[str, Solution]:
        """``time_optimal``: the physical minimum (TOPP-RA); ``seed``: the paper's law;
        ``seed_max_V``: the same scheme at the fastest feasible V (:mod:`.baselines`)."""
        return baselines.baseline_solutions(self)

    def reference_optimum(self) -> dict[str, Any] | None:
        """For a ``time`` objective: the physical minimum's cycle time, the value no time law
        can beat on this path under these limits (:func:`.baselines.reference_optimum`)."""
        return baselines.reference_optimum(self)

    def initial_points(self) -> FloatArray | None:
        """With a speed profile: TOPP-RA's profile on the knots (limits holding on a dense
        resampling), slower copies of it, and the seed law on the knots — where the
        population starts (None for the trapezoid encodings: a uniform random start)."""
        return self._starts if isinstance(self.encoding, SpeedProfile) else None

    @cached_property
    def _starts(self) -> FloatArray:
        return optimal.initial_points(self)

    def free_start(self) -> tuple[str, FloatArray] | None:
        """With a speed profile: the time-optimal profile on the knots, which the population
        starts from (no search needed to get it)."""
        x = self.initial_points()
        if x is None:
            return None
        return "the time-optimal profile on the knots (TOPP-RA)", x[0]

    def extras(self, front_X: FloatArray, front_F: FloatArray) -> dict[str, Any]:
        """The front in readable form with the % change of each objective against the seed
        law — only when that law is feasible on this arm (else None, and
        ``change_pct_reason`` says which limits it breaks) — and the physical minimum."""
        return baselines.extras(self, front_X, front_F)

    def seed_violations(self) -> tuple[Violation, ...]:
        """What the seed law (linear ramps) violates on this arm (cached)."""
        cached: tuple[Violation, ...] | None = getattr(self, "_seed_broken", None)
        if cached is None:
            cached = limits.limit_violations(self, self.seed_law())
            self._seed_broken = cached
        return cached
