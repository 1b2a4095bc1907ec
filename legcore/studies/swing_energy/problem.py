"""``swing_energy`` — seed 000: GA energy optimisation of a walking-robot leg's transfer phase.

Calderón, Bedolla & Szwedowicz (2015). One leg swings freely (open chain) from a start to an
end configuration in ``T`` = 3 s. The seed's leg is ``calderon_leg`` (3 DOF: hip yaw + two
pitch joints, seed 000 Table 1); the study runs on any leg chain of 2–6 revolute joints — a
serial leg, or one leg of a legged robot (``leg``), its foot the chain's end frame or the frame
named by ``foot_frame`` (:mod:`legcore.studies.swing_energy.setup`). What depends on the leg
(which leg, its start and end — a step in body axes from a nominal stance —, the link weights,
the search range, the baseline's apex, the obstacle's size) is derived from it
(:mod:`legcore.studies.swing_energy.defaults`); on seed 000's own leg the paper's values come
from its preset (:mod:`legcore.studies.swing_energy.preset`). See ``docs/studies.md (seed
000)`` for the paper's tables beside ours.

Genes
    ``x`` (n·K_via,) rad for a leg of n joints, via-point-major (``x[n j + i]`` belongs to joint
    ``i`` at intermediate via point ``j``, K_via = 10); every entry is an integer gene ``k``
    times the control resolution (0.00174 rad), and every via point it decodes to is a multiple
    of the resolution too, as are the start and end configurations (unless ``exact_ends``) —
    every trajectory is reachable by the controller.
    Two encodings (``encoding``):

    - ``"deviation"`` (default): the via point is the coordinated motion's via point (on the
      grid) plus the gene's excess over a dead band, ``v = c + sign(k)·max(|k| − D, 0)`` steps,
      with ``D = dead_band × W`` and ``|v − c| ≤ W = search_range`` per joint. With
      ``lift_only`` the two pitch joints deviate only in the direction that lifts the foot (the
      sign of ∂z_foot/∂q_i at the start; below the coordinated motion the foot would enter the
      ground); the yaw joint deviates both ways. Default W = (0.05, 0.3, 0.4) rad (the knee's
      range is larger: its lever arm to the foot is 2/3 of the hip pitch's), D = 2 W.
    - ``"absolute"``: the gene *is* the via-point angle, ``v = k`` steps, in the tube
      ``c ± W`` around the coordinated motion (one-sided for the lifting joints with
      ``lift_only``) — the seed's literal coding.

    The tube's centre ``c`` (``tube``) is the coordinated motion (seed 000), or the shortest
    foot path that clears the ground and obstacles (the Shankar & Kaur baseline's via points,
    feasible by construction): the default when the coordinated motion itself violates them — a
    leg's forward step, whose joint-space straight line dips the foot into the ground (14, 26
    and 18 mm on the derived steps of Solo12, ANYmal B and Go1). Around the coordinated motion
    seed 000's GA (100 × 100, penalty 300 /m) ends infeasible on 3 of those 9 runs (3 seeds ×
    3 legs) and needs 4–48 generations on the others; around the shortest path it is feasible
    from generation 2 on all 9. ``lift_only`` then defaults to false (a lowering deviation is
    refused by the ground constraint, not by the coding).

    Why "deviation": with absolute genes the seed's GA (fresh-value mutation, one-gene blend)
    cannot make a joint exactly still — f_d and f_a reward stillness only when all ten genes of
    the joint agree — and at 100 × 100 it ends at a score ≈ 2.4 (0.2–0.4 J) in both cases (10
    seeds). With the dead band an unmutated gene reproduces the coordinated motion, a fresh gene
    does so with probability 2/3, and the GA reaches 9.68 (flat, 10/10 seeds) / 7.50 (box, 8/10
    seeds) — see ``docs/studies.md (seed 000)``.

Trajectory
    The joint trajectory passes through start, the K_via via points and end at the equally spaced
    times ``t_j = j T / (K_via + 1)``: a C² cubic spline, clamped (q̇ = 0 at both ends) —
    :class:`~legcore.trajectories.ViaPointSpline` ``kind="cubic"`` (the seed does not name its
    interpolation; the cubic is the lowest order with continuous acceleration, which eq 5 needs,
    and its jerk is finite). It is sampled every ``dt`` (0.01 s → K = 301 samples). The spline is
    linear in the via points, so the population is evaluated as one matrix product
    (:func:`~legcore.studies.swing_energy.geometry.via_basis`).

Objective (seed eqs 1–5), to MAXIMISE, best = 10 (reported as ``score``; F = −score)::

    score = w1 f_d + w2 f_a,     w1 = w2 = 5
    f_d = Σ_i w_{d,i} r(θ_{i,min}, θ_{i,T}),   θ_{i,min} = |q_{i,end} − q_{i,start}|   (eqs 2–3)
                                                θ_{i,T}   = Σ_k |q_{i,k} − q_{i,k−1}|     (eq 4)
    f_a = Σ_i w_{a,i} r(AcC_{i,max}, Ac_{i,max}),  Ac = max_k |q̈_{i,k}|                  (eq 5)
    r(a, b) = min(1, (a + ε) / (b + ε)),   w_d = w_a = (0.25, 0.5, 0.25)

- θ_{i,T} is summed over the K time samples (the "divisions" of eq 4), so spline overshoot
  between via points counts as motion.
- AcC (the "coordinated trajectory between the initial and final positions"): the rest-to-rest
  cubic ``q_s + Δq (3τ² − 2τ³)`` (the spline through no intermediate point: all joints start and
  stop together), characterised like every candidate — its values at the via-point times rounded
  to the grid, through the same spline. AcC_1 = 0.492 rad/s² (the exact cubic's 6|Δq|/T² is
  0.430; rounding the via points adds the rest), and for the joint that moves 2 steps the goal
  is the grid staircase's 0.052 rad/s², which a candidate can reach (the exact cubic's
  0.0023 rad/s² cannot be reached on the grid). The coordinated motion therefore scores
  f_a = 1 and the best score 10 is attainable, as the seed intends.
- ``min(1, ·)``: the seed's goal programming ("the maximum value of f_a and f_d is one"). f_d ≤ 1
  anyway; for f_a, a trajectory whose peak acceleration is below the coordinated one meets the
  goal and gets 1.
- ε (``ratio_eps`` resolution steps; 1 by default; ε_d = ratio_eps·resolution,
  ε_a = ratio_eps·6·resolution/T²) handles a joint that does not move: 0/0 → 1 (still joint =
  goal met). With ε = 0 the ratios are exactly eqs 2 and 5 with 0/0 := 1, but a joint whose start
  and end coincide then scores 0 for *any* motion, however small, and the GA has no slope towards
  keeping it still; ε gives it one (a joint that moves one step out and back scores 1/3). For
  joint 1 (371 steps) ε changes the ratio by < 0.3 %.

Constraints (G ≤ 0)
    ``ground``: every joint origin and the foot stay above the ground (the plane of the lower of
    the start/end feet) minus ``ground_tolerance`` (1 mm) — G is the depth below it (m).
    ``obstacle``: the box (60 × 40 × 26 mm by default, length along the step, on the ground,
    centred on the midpoint of the start→end foot chord), grown by ``margin`` (2 mm), is entered
    by no link segment (hip→knee→foot, tested exactly by the slab method at every sample) — G is the
    penetration depth (m, :func:`~legcore.studies.swing_energy.geometry.chain_clearance`).
    The default optimiser handles them with a static penalty of 300 per metre (1 mm of
    penetration costs 0.3 score points): with Deb's feasibility rule the GA settles on the first
    feasible (hip-pitch) lift and never finds the knee lift the score prefers.

Start and end of seed 000's leg (derived; the seed gives neither, see the docs for the fit;
its preset's ``q_start``/``q_end``)
    start = (−185, 384, −782) steps, end = (186, 384, −780) steps of 0.00174 rad, i.e.
    q_start = (−0.3219, 0.6682, −1.3607) rad, q_end = (0.3236, 0.6682, −1.3572) rad.
    Joint 1 travels 371 steps = 0.6455 rad (Tables 2–5: 0.6458 = 37.0°); joint 3 differs by
    2 steps so that the minimum total displacement is 0.6490 rad (Table 3: 0.6493); the posture
    (femur 38.3° up, shank 39.7° below horizontal) reproduces Table 2's static torques
    (0.1767 / 0.0861 N·m vs 0.1765 / 0.0862) and the parabolic baseline's joint travel (1.19 /
    0.57 rad vs 1.2007 / 0.5655); the feet are 0.152 m apart (baseline step 0.156 m) and the
    pure-yaw foot arc is 0.1546 m (Table 3 D = 0.1532 m).

Baselines (``baseline_solutions``): the parabolic swing (Calderón 2008) and the shortest foot
path (Shankar & Kaur 2011) are constructions; minimum θ_T (Tian & Collins 2004), the
multi-criteria sum (Solteiro 2007) and minimum energy (Pérez 2010) are this GA with that
criterion in place of the score (``baseline_generations``, fixed ``baseline_seed``) — see
:mod:`legcore.studies.swing_energy.baselines`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore.chain_points import chain_points
from legcore.dynamics import inverse_dynamics
from legcore.energy import mechanical_energy
from legcore.kinematics import fk, jacobian
from legcore.problems.base import Problem
from legcore.robots.legged import LeggedRobot
from legcore.studies.study import Solution, StudyProblem, Violation
from legcore.studies.swing_energy import decode
from legcore.studies.swing_energy.defaults import ik_reference
from legcore.studies.swing_energy.geometry import (
    chain_clearance,
    travel_and_peak,
    via_basis,
)
from legcore.studies.swing_energy.params import (
    BASELINES,
    RESOLUTION,
    BoxSpec,
    Obstacle,
    Params,
)
from legcore.studies.swing_energy.setup import boxes, configuration, swing_leg
from legcore.trajectories import ViaPointSpline, time_grid

__all__ = [
    "BASELINES",
    "CRITERIA",
    "RESOLUTION",
    "BoxSpec",
    "Obstacle",
    "Params",
    "SwingEnergyProblem",
]

FloatArray = NDArray[np.float64]

#: What a problem minimises: the seed's score (as −score) or one literature criterion.
CRITERIA = ("score", "theta_total", "foot_distance", "multi_criteria", "energy")

# Values below these are exact zeros (float noise of the spline basis): rad, rad/s².
_ZERO_THETA = 1e-12
_ZERO_ACC = 1e-9
_BASELINE_CACHE: dict[str, dict[str, Solution]] = {}


class SwingEnergyProblem(StudyProblem):
    """Seed 000 swing-phase problem on any leg (see the module docstring).

    Args:
        robot: a serial leg of 2–6 revolute joints (``calderon_leg`` by default), or a legged
            robot whose leg ``params.leg`` swings.
        params: the study :class:`Params`, concrete: fields left to the robot (None) are
            derived by :func:`~legcore.studies.swing_energy.study.build` (the preset on seed
            000's leg, then :func:`~legcore.studies.swing_energy.defaults.derive`).
        criterion: what F is — ``"score"`` (F = −score, the seed's GA) or a baseline criterion
            ``"theta_total"`` (rad), ``"foot_distance"`` (m), ``"energy"`` (J),
            ``"multi_criteria"`` (dimensionless, see ``swing_energy_baselines``).
        refs: normalisers of the ``multi_criteria`` terms (``swing_energy_baselines``).

    Attributes (all SI, n joints): ``robot`` the swinging chain; ``n_joints``;
    ``q_start``/``q_end`` (n,) rad, ``start_steps``/``end_steps`` (n,) int, ``t`` (K,) s,
    ``t_via`` (K_via + 2,) s, ``foot_start``/``foot_end`` (3,) m (leg base frame), ``z_ground``
    m, ``boxes`` (the obstacles, without margin) and ``margins`` (m), ``box`` (the first box or
    None), ``acc_coordinated`` AcC (n,) rad/s².
    """

    def __init__(
        self,
        robot: Any,
        params: Params,
        criterion: str = "score",
        refs: dict[str, float] | None = None,
    ) -> None:
        if incomplete(robot, params):
            raise ValueError("params: robot-relative fields are unset (None); build the problem "
                             "with legcore.studies.swing_energy.study.build, which derives them")
        self.source = robot  # the robot as given (a legged robot, or the serial leg)
        self.robot_name = str(getattr(robot, "name", ""))
        #: the leg's hip (4×4, body frame) when it is a leg of a legged robot whose leg frames
        #: have the body's axes (the scene is then drawn on the body); None otherwise
        self.hip: NDArray[np.float64] | None = None
        if isinstance(robot, LeggedRobot) and params.leg in {g.name for g in robot.legs}:
            hip = np.asarray(robot.leg(str(params.leg)).hip, dtype=float)
            self.hip = hip if np.allclose(hip[:3, :3], np.eye(3)) else None
        robot, self.label = swing_leg(robot, params)
        g = robot.chain.gravity
        if not np.allclose(g / max(float(np.linalg.norm(g)), 1e-300), [0.0, 0.0, -1.0],
                           atol=1e-6):
            raise ValueError(f"robot: swing_energy needs the leg's base frame with z up (gravity "
                             f"along -z); {self.label} has gravity {g.round(4).tolist()}")
        n = robot.nq
        if not 2 <= n <= 6:
            raise ValueError(f"robot: swing_energy needs a leg of 2–6 joints; {self.label} has {n}")
        self.n_joints = n
        if criterion not in CRITERIA:
            raise ValueError(f"criterion: unknown {criterion!r}; expected one of {CRITERIA}")
        if criterion == "multi_criteria" and refs is None:
            raise ValueError("refs: the multi_criteria criterion needs its normalisers")
        self.robot = robot
        # A URDF leg's link frames sit at its joints: its foot is only in the tool frame.
        frames_ = robot.model.frames
        tool, last = frames_[robot.tool_frame], frames_[robot.link_frames[-1]]
        self._foot_is_last_frame = bool(
            tool.parentJoint == last.parentJoint and tool.placement.isApprox(last.placement, 1e-12)
        )
        self.params = params
        self.criterion = criterion
        self.refs = dict(refs or {})
        res = float(params.resolution)
        self.res = res

        # a given foot position is solved on the leg's own knee branch (defaults.ik_reference)
        ref = (ik_reference(self.source, params, robot) if params.foot_start is not None
               else robot.home)
        exact = bool(params.exact_ends)
        self.q_start, self.start_steps = configuration(
            robot, "start", params.q_start, params.foot_start, ref, res, exact)
        self.q_end, self.end_steps = configuration(
            robot, "end", params.q_end, params.foot_end, self.q_start, res, exact)
        self.w_d = np.asarray(params.per_joint("w_d", n), dtype=float)
        self.w_a = np.asarray(params.per_joint("w_a", n), dtype=float)
        search_range = np.asarray(params.per_joint("search_range", n), dtype=float)

        self.n_via = int(params.n_via)
        self.t = time_grid(params.T, params.dt)
        self.t_via = np.linspace(0.0, params.T, self.n_via + 2)
        self.n_samples = int(self.t.shape[0])
        self._N = via_basis(self.t_via, self.t)  # (4, K, J)

        # The coordinated start->end motion: the rest-to-rest cubic through no intermediate
        # point, characterised like every candidate (its via points on the grid, same spline).
        ends = np.stack([self.q_start, self.q_end])[None]
        coord = ViaPointSpline(np.array([0.0, params.T]), ends)
        self.q_coordinated_via = coord.evaluate(self.t_via[1:-1]).q[0]  # (n_via, n)
        self.coord_steps = np.rint(self.q_coordinated_via / res).astype(np.int64)  # (n_via, n)
        self.theta_min = np.abs(self.q_end - self.q_start)

        feet = fk(robot, np.stack([self.q_start, self.q_end]))[:, :3, 3]
        self.foot_start, self.foot_end = feet[0].copy(), feet[1].copy()
        z_feet = float(min(feet[0, 2], feet[1, 2]))
        if params.ground_height is None:
            self.z_ground = z_feet
        elif params.ground and z_feet < params.ground_height - params.ground_tolerance:
            raise ValueError(f"ground_height: {params.ground_height} m is above the start or "
                             f"end foot (z = {z_feet:.4g} m)")
        else:
            self.z_ground = float(params.ground_height)
        self.boxes, self.margins = boxes(params.box, params.obstacles, self.foot_start,
                                         self.foot_end, self.z_ground)
        self.box = self.boxes[0] if self.boxes else None
        self.margin = self.margins[0] if self.margins else 0.0

        self.eps_d = params.ratio_eps * res
        self.eps_a = params.ratio_eps * 6.0 * res / params.T**2

        # Search space (see the module docstring, "Genes").
        self.lift_sign = self._lift_signs()
        self.range_steps = np.rint(search_range / res).astype(np.int64)
        self.dead_steps = np.rint(params.dead_band * self.range_steps).astype(np.int64)
        self.steps_min = np.ceil(robot.q_min / res - 1e-9).astype(np.int64)
        self.steps_max = np.floor(robot.q_max / res + 1e-9).astype(np.int64)
        # the tube's centre (params.tube): the coordinated motion for now; a swing that clears
        # the ground is decoded by this problem, so it is set once the problem is built
        self.centre_steps = self.coord_steps
        #: what the tube is centred on: "coordinated" or "shortest"
        self.tube = "coordinated"
        lo, hi = self._gene_box()
        n_constr = int(params.ground) + int(bool(self.boxes))
        self.constraint_names = tuple(
            c for c, on in (("ground", params.ground), ("obstacle", bool(self.boxes))) if on
        )
        names = {"score": ("neg_score",)}
        self.objective_names = names.get(criterion, (criterion,))
        super().__init__(n * self.n_via, 1, n_constr, xl=lo.ravel() * res, xu=hi.ravel() * res,
                         resolution=res, name=f"swing_energy[{criterion}]")
        (qdd_c,) = self.trajectories(self.coordinated_x()[None], (2,))
        self.acc_coordinated = np.max(np.abs(qdd_c[0]), axis=0)
        if params.tube == "shortest":
            self._centre_on_shortest()
        # load the evaluation's numba kernels now: the first evaluate() is measured by
        # legcore.memory (tracemalloc) and must see arrays, not numba's cache loader
        self._evaluate(self.coordinated_x()[None])

    def _centre_on_shortest(self) -> None:
        """Centre the search tube on the shortest foot path that the decoded trajectory keeps
        feasible (:func:`~legcore.studies.swing_energy.baselines.min_distance_via`, on the grid)
        and rebuild the gene bounds; when there is none (no path raised by up to 50 mm clears
        them) the tube stays around the coordinated motion (``tube`` says which)."""
        from legcore.studies.swing_energy.baselines import min_distance_via

        via = min_distance_via(self)
        if via is None:  # none within 50 mm: the search stays around the coordinated motion
            return
        self.tube = "shortest"
        self.centre_steps = np.rint(via / self.res).astype(np.int64)
        lo, hi = self._gene_box()
        self.xl = lo.ravel() * self.res
        self.xu = hi.ravel() * self.res
        self.xl.flags.writeable = False
        self.xu.flags.writeable = False

    # ------------------------------------------------------------------ trajectories
    def _lift_signs(self) -> NDArray[np.int64]:
        """+1/−1: the direction in which each joint lifts the foot at the start (sign of
        ∂z_foot/∂q_i); 0 for a joint that does not (the hip yaw)."""
        dz = jacobian(self.robot, self.q_start)[2]
        return np.where(np.abs(dz) > 1e-3, np.sign(dz), 0.0).astype(np.int64)

    def _gene_box(self) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """Integer gene bounds (n_via, n) of the chosen encoding."""
        p = self.params
        shape = (self.n_via, self.n_joints)
        W = np.broadcast_to(self.range_steps, shape)
        one_sided = np.broadcast_to((self.lift_sign != 0) & bool(p.lift_only), shape)
        sgn = np.broadcast_to(np.where(self.lift_sign == 0, 1, self.lift_sign), shape)
        if p.encoding == "absolute":
            c = self.centre_steps
            lo = np.where(one_sided & (sgn > 0), c, c - W)
            hi = np.where(one_sided & (sgn < 0), c, c + W)
            lo = np.clip(lo, self.steps_min, self.steps_max)
            hi = np.clip(hi, self.steps_min, self.steps_max)
            return lo, np.maximum(hi, lo)
        reach = np.broadcast_to(self.dead_steps, shape) + W
        lo = np.where(one_sided & (sgn > 0), 0, -reach)
        hi = np.where(one_sided & (sgn < 0), 0, reach)
        return lo, hi

    def free_start(self) -> tuple[str, FloatArray] | None:
        """``deviation`` coding: all-zero genes decode to the tube's centre (the coordinated
        motion, or the shortest foot path), a solution the coding gives without search (random
        genes fall in its dead band with probability ⅔)."""
        if self.params.encoding == "absolute":
            return None
        what = "shortest foot path" if self.tube == "shortest" else "coordinated motion"
        return f"the {what} (all genes 0)", np.zeros(self.n_var)

    def via_steps(self, X: FloatArray) -> NDArray[np.int64]:
        """Intermediate via points (B, n_via, n) in resolution steps of decision vectors X.

        ``absolute``: the gene itself. ``deviation``: the tube's centre (the coordinated via
        point, or the shortest foot path's) plus the gene's excess over the dead band,
        ``sign(g) · max(|g| − D, 0)``; clipped to the joint limits.
        """
        G = np.rint(np.asarray(X, dtype=float).reshape(-1, self.n_via, self.n_joints) / self.res)
        G = G.astype(np.int64)
        if self.params.encoding == "absolute":
            V = G
        else:
            V = self.centre_steps + np.sign(G) * np.maximum(np.abs(G) - self.dead_steps, 0)
        return np.clip(V, self.steps_min, self.steps_max)

    def encode(self, via: FloatArray) -> FloatArray:
        """Decision vector (n n_via,) rad whose via points are ``via`` (n_via, n) rad (rounded
        to the grid); the inverse of :meth:`via_steps` (may lie outside the GA's bounds)."""
        V = np.rint(np.asarray(via, dtype=float).reshape(self.n_via, self.n_joints) / self.res)
        V = V.astype(np.int64)
        if self.params.encoding == "absolute":
            G = V
        else:
            d = V - self.centre_steps
            G = np.where(d == 0, 0, d + np.sign(d) * self.dead_steps)
        return (G * self.res).ravel()

    def via_points(self, X: FloatArray) -> FloatArray:
        """All J = K_via + 2 via points (B, J, n) rad of decision vectors ``X`` (B, n K_via)."""
        return self.with_ends(self.via_steps(X) * self.res)

    def with_ends(self, V: np.ndarray) -> FloatArray:
        """Intermediate via points V (B, K_via, n) rad → all J = K_via + 2 (start and end added).
        """
        B = V.shape[0]
        return np.concatenate(
            [np.broadcast_to(self.q_start, (B, 1, self.n_joints)), V,
             np.broadcast_to(self.q_end, (B, 1, self.n_joints))],
            axis=1,
        )

    def trajectories(
        self, X: FloatArray, orders: tuple[int, ...] = (0, 1, 2, 3)
    ) -> list[FloatArray]:
        """Sampled q, q̇, q̈, jerk (the derivative ``orders`` asked for), each (B, K, n).

        Relative to the start (``q_start + N·(V − q_start)``) so that a joint whose via points
        all equal its start value is exactly constant (no float noise)."""
        return self.via_trajectories(self.via_points(X), orders)

    def via_trajectories(
        self, V: FloatArray, orders: tuple[int, ...] = (0, 1, 2, 3)
    ) -> list[FloatArray]:
        """As :meth:`trajectories`, from all J via points V (B, J, n) rad (on the grid or not)."""
        V = V - self.q_start
        out = []
        for d in orders:
            y = self._N[d] @ V
            out.append(y + self.q_start if d == 0 else y)
        return out

    def genes(self, x: FloatArray) -> NDArray[np.int64]:
        """Integer genes (n_via, n) of a decision vector (x / resolution, rounded)."""
        x = np.asarray(x, dtype=float).reshape(self.n_via, self.n_joints)
        return np.rint(x / self.res).astype(np.int64)

    # ------------------------------------------------------------------ criteria
    def score_parts(self, q: FloatArray, qdd: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(f_d, f_a) per trajectory (B,) from q, q̈ (B, K, n) — seed eqs 2–5 (module docstring)."""
        theta, acc = travel_and_peak(q, qdd)  # Σ_k |Δq|, max_k |q̈| (one numba pass)
        theta = np.where(theta < _ZERO_THETA, 0.0, theta)
        acc = np.where(acc < _ZERO_ACC, 0.0, acc)
        r_d = _ratio(self.theta_min, theta, self.eps_d)
        r_a = _ratio(self.acc_coordinated, acc, self.eps_a)
        return r_d @ self.w_d, r_a @ self.w_a

    def score(self, q: FloatArray, qdd: FloatArray) -> FloatArray:
        """Seed 000 objective F_o = w1 f_d + w2 f_a (B,), to maximise (best = w1 + w2 = 10)."""
        f_d, f_a = self.score_parts(q, qdd)
        return self.params.w1 * f_d + self.params.w2 * f_a

    def energy(self, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> FloatArray:
        """Mechanical energy Σ_i ∫|τ_i q̇_i| dt (B,) J, τ by batched RNEA (gravity −z)."""
        tau = inverse_dynamics(self.robot, q, qd, qdd)
        return mechanical_energy(qd, tau, self.t).total

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        return self.evaluate_via(self.via_points(X))

    def evaluate_via(self, V: FloatArray) -> tuple[FloatArray, FloatArray | None]:
        """(F (B, 1), G (B, n_constr) or None) of the trajectories through all J via points
        V (B, J, n) rad — the continuous decode (off-grid via points allowed) behind
        ``_evaluate``, which passes the via points of integer genes."""
        c = self.criterion
        need_pts = self.n_constr > 0 or c in ("foot_distance", "multi_criteria")
        if c in ("energy", "multi_criteria"):
            q, qd, qdd = self.via_trajectories(V, (0, 1, 2))
        else:
            q, qdd = self.via_trajectories(V, (0, 2))
        P = self.chain_points(q) if need_pts else None  # (B, K, M, 3)
        if c == "score":
            F = -self.score(q, qdd)
        elif c == "theta_total":
            F = np.sum(np.abs(np.diff(q, axis=-2)), axis=(-2, -1))
        elif c == "energy":
            F = self.energy(q, qd, qdd)
        else:
            assert P is not None
            foot = P[:, :, -1]
            step = np.linalg.norm(np.diff(foot, axis=-2), axis=-1)
            D = step.sum(axis=-1)
            if c == "foot_distance":
                F = D
            else:
                from legcore.studies.swing_energy.baselines import multi_criteria

                v_foot = np.max(step / np.diff(self.t), axis=-1)
                F = multi_criteria(self.refs, q=q, qd=qd, D=D, v_foot=v_foot,
                                   E=self.energy(q, qd, qdd))
        G = self._constraints(P) if self.n_constr else None
        return F[:, None], G

    def chain_points(self, q: FloatArray) -> FloatArray:
        """Points along the leg (..., M, 3), m, for configurations ``q`` (..., n): the base and
        link-frame origins, then the foot (the robot's tool frame) unless the last link frame
        is already the foot (a standard-DH leg). The foot is always ``[..., -1, :]``.
        Positions only (no 4×4 poses), C-contiguous: :func:`legcore.chain_points.chain_points`."""
        return chain_points(self.robot, q, tool=not self._foot_is_last_frame)

    def _constraints(self, P: FloatArray | None) -> FloatArray:
        """G (B, n_constr) from the chain points P (B, K, M, 3): ground depth, box penetration
        (m)."""
        assert P is not None
        if self.boxes:  # all boxes, grown by their margins, in one pass over P
            centers = np.array([box.center for box in self.boxes], dtype=float)
            halves = np.array([np.asarray(box.half_size) + margin
                               for box, margin in zip(self.boxes, self.margins, strict=True)])
            depth, z_min = chain_clearance(P, centers, halves)
        else:
            depth, z_min = chain_clearance(P)
        cols = []
        if self.params.ground:
            cols.append(self.z_ground - self.params.ground_tolerance - z_min)
        if self.boxes:
            cols.append(depth)
        return np.stack(cols, axis=1)

    def violations(self, x: FloatArray) -> tuple[Violation, ...]:
        """What ``x`` violates, in metres: ``ground`` (amount: how far the lowest joint or the
        foot dips below the ground beyond its tolerance; the text says the whole dip) and
        ``obstacle`` (how deep a link segment enters a box grown by its margin)."""
        _, G = self.evaluate(np.asarray(x, dtype=float)[None, :])
        if G is None:
            return ()
        out = []
        for name, g in zip(self.constraint_names, G[0], strict=True):
            if g <= 0.0:
                continue
            if name == "ground":
                tol = self.params.ground_tolerance
                text = (f"the leg dips {g + tol:.3g} m below the ground (z = "
                        f"{self.z_ground:.4g} m): {g:.3g} m more than its {tol:.3g} m tolerance")
            else:
                text = f"a link enters an obstacle box (grown by its margin) {g:.3g} m deep"
            out.append(Violation(str(name), float(g), "m", text))
        return tuple(out)

    # ------------------------------------------------------------------ decoding
    def solution(self, x: FloatArray, label: str | None = None) -> Solution:
        """The full decoded trajectory of ``x`` with the seed's Table 2/3 metrics
        (:func:`legcore.studies.swing_energy.decode.solution`)."""
        return decode.solution(self, x, label)

    def relaxation(self) -> Any:
        """Continuous relaxation for :func:`legcore.optimizers.refine.refine`: z = the
        intermediate via points (n_via·n,) rad, anywhere in the search tube the genes reach
        (bounds: the via points of the gene bounds), evaluated off the grid by
        :meth:`evaluate_via`; ``lower`` rounds them back onto the grid (:meth:`encode`)."""
        from legcore.optimizers.refine import Relaxation

        shape = (-1, self.n_via, self.n_joints)

        def evaluate(Z: FloatArray) -> tuple[FloatArray, FloatArray]:
            F, G = self.evaluate_via(self.with_ends(np.asarray(Z, dtype=float).reshape(shape)))
            return self.check_output(F.shape[0], F, G)

        def lift(x: FloatArray) -> FloatArray:
            return np.asarray(self.via_steps(np.asarray(x)[None]) * self.res, dtype=float).ravel()

        return Relaxation(xl=lift(self.xl), xu=lift(self.xu), evaluate=evaluate, lift=lift,
                          lower=lambda z: self.snap(self.encode(z)[None])[0],
                          step=np.full(self.n_var, self.res))

    def coordinated_x(self) -> FloatArray:
        """Decision vector of the coordinated start→end motion (its via points on the grid)."""
        return self.encode(self.coord_steps * self.res)

    # ------------------------------------------------------------------ baselines
    def variant(self, criterion: str, refs: dict[str, float] | None = None) -> SwingEnergyProblem:
        """The same leg, start, end and parameters with ``criterion`` as F (a baseline's
        problem; ``refs``: the ``multi_criteria`` normalisers)."""
        return type(self)(self.source, self.params, criterion=criterion, refs=refs)

    def companions(self) -> list[tuple[Problem, int]]:
        """The baseline GAs ``finalize`` runs (one per GA criterion asked for), each with the
        baseline population: what :mod:`legcore.memory` sizes the job by besides its own."""
        from legcore.studies.swing_energy.baselines import MULTI_TERMS, ga_baseline_criteria

        pop = int(self.params.baseline_pop_size)
        refs = dict.fromkeys(MULTI_TERMS, 1.0)  # placeholders: same arrays as the real ones
        return [(self.variant(c, refs), pop) for c in ga_baseline_criteria(self.params)]

    def baseline_solutions(self) -> dict[str, Solution]:
        """The seed's comparison trajectories, decoded like the optimum.

        They depend only on the robot and the study parameters (not on the job's seed), so they
        are computed once per process for each (robot, params): a sweep over seeds or optimiser
        settings reuses them.
        """
        key = (self.robot.spec.model_dump_json() + str(self.robot.tool_frame)
               + self.params.model_dump_json())
        cached = _BASELINE_CACHE.get(key)
        if cached is None:
            from legcore.studies.swing_energy.baselines import compute_baselines

            cached = compute_baselines(self)
            if len(_BASELINE_CACHE) >= 16:
                _BASELINE_CACHE.pop(next(iter(_BASELINE_CACHE)))
            _BASELINE_CACHE[key] = cached
        return dict(cached)

    def baselines(self) -> dict[str, np.ndarray]:
        return {k: np.asarray(v.x) for k, v in self.baseline_solutions().items() if v.x is not None}

    def extras(self, front_X: FloatArray, front_F: FloatArray) -> dict[str, Any]:
        """Study-level facts: start/end, AcC, the obstacle, and the energy comparison
        (:func:`legcore.studies.swing_energy.decode.extras`)."""
        return decode.extras(self, front_X)

def _ratio(num: FloatArray, den: FloatArray, eps: float) -> FloatArray:
    """min(1, (num + ε)/(den + ε)), with 0/0 := 1 (a joint that does not move meets its goal)."""
    n = num + eps
    d = den + eps
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(d > 0.0, n / np.where(d > 0.0, d, 1.0), 1.0)
    return np.minimum(r, 1.0)


def incomplete(robot: Any, params: Params) -> bool:
    """True when ``params`` leaves a robot-relative field to the robot (None)."""
    box = params.box
    return (
        (isinstance(robot, LeggedRobot) and params.leg is None)
        or any(getattr(params, k) is None
               for k in ("w_d", "w_a", "search_range", "step_height", "exact_ends", "tube",
                         "lift_only"))
        or (params.q_start is None and params.foot_start is None)
        or (params.q_end is None and params.foot_end is None)
        or (box is not None and None in (box.length, box.width, box.height, box.margin))
    )
