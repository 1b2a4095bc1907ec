"""``path_placement`` — seed 001 as a task: place a tool path where an arm of ≥ 6 joints runs it
with the least energy and the best manipulability (Heuristic Kalman Algorithm by default).

A Cartesian path with tool orientations (:mod:`legcore.studies.path_placement.paths`: the
built-in ``pan`` and ``jar`` paths or CSV text) is translated so that its anchor point (its first
point, as in the paper, or its centroid) lies at the point p(x) of a placement region
(:mod:`legcore.studies.path_placement.region`: a sphere, a spherical shell — x = (R, γ, φ),
seed 001's eq 5 — or a box, x = (x, y, z); the seed's simplified spherical workspace, eqs 1–5,
is the preset's shell); the tool orientations are kept ("conservando la orientación de la
herramienta"). For a whole population at once:

1. every path point → IK (:mod:`legcore.studies.path_placement.joints`): the PUMA-type closed
   form's 8 branches (seed 001's arm), or the batched numerical IK along the path from each
   start posture (any other arm); one continuous joint trajectory per branch, unreachable
   points filled from their reachable neighbours (and penalised, see below);
2. time grid: the path's own time stamps (``timing="path"``), or each segment stretched so that
   no joint exceeds ``speed_fraction·q̇_max`` (``timing="joint_limited"``: the duration then
   depends on the placement, as in the paper's Tables 2–3);
3. ``q̇, q̈`` by finite differences (second order inside, as ``numpy.gradient``); torques by
   batched RNEA with motor friction (:func:`legcore.dynamics.inverse_dynamics`); energy:
   electrical of the DC motors (:func:`legcore.energy.electrical_energy`, eqs 9–14) where motor
   data exist, else mechanical Σ ∫|τ_i q̇_i| dt (``energy``; the result says which);
   manipulability ``w`` averaged over the points (eqs 6–8, ``w_A |sin θ5|``, on a PUMA-type
   arm; Yoshikawa's sqrt(det J Jᵀ) on any other — the same number on a 6R arm);
4. cost (eq 15) ``J = PC·C/(P_n t) + PM·(1 − w_p/w_M)`` with ``C/(P_n t)`` = mean power /
   nominal power, ``PM = 1 − PC``; the penalty term ``ϖ Σ max(g_i, 0)`` of eq 15 is the
   optimiser's (HKA ``penalty`` = ϖ) over the 2n + 1 constraints ``G``:

   - ``g_1..g_n`` joint position: the largest excursion of joint i beyond its limits over the
     path, as a fraction of its range (negative: the smallest margin); a path point the arm
     cannot reach adds ``1 + 10·(fraction of unreachable points)`` to each of them;
   - ``g_n+1..g_2n`` joint speed: ``max_k |q̇_ik| / q̇_max,i − 1``;
   - on an arm with torque limits (every joint's finite), joint torque:
     ``max_k |τ_ik| / τ_max,i − 1`` (not on the seed's PUMA 560, which gives none);
   - last, nominal power: peak total power / P_n − 1;
5. the branch of each candidate is the best of its branches for the whole path: least total
   constraint violation, then least J (``branch="best"``); or one named closed-form branch.

Reported per solution (:mod:`legcore.studies.path_placement.report`): energy, mean
manipulability, duration, J, the constraints, and the % change against the ORIGINAL placement
(the ``original`` baseline) — only when that placement is feasible (else NaN, and
``extra.change_pct_reason`` says why). :meth:`PathPlacementProblem.violations` names what an
infeasible placement breaks: the % of the path out of reach, each joint's position, speed and
torque limit and the nominal power, in their units. Seed 001 Figure 8:
:mod:`legcore.studies.path_placement.initialisation`.

Defaults relative to the arm (the path scaled to its reach, a well-conditioned region, a
reachable and feasible original placement, the nominal power from its limits):
:mod:`legcore.studies.path_placement.defaults`; seed 001's settings on the PUMA 560:
:mod:`legcore.studies.path_placement.preset`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.dynamics import inverse_dynamics
from legcore.energy import electrical_energy, integrate
from legcore.ik.puma560 import BRANCH_NAMES
from legcore.manipulability import manipulability, manipulability_split
from legcore.robots.capabilities import Needs
from legcore.robots.model import Robot
from legcore.studies.path_placement import report
from legcore.studies.path_placement.joints import gradient, placed_path_joints
from legcore.studies.path_placement.manipulability import max_manipulability
from legcore.studies.path_placement.params import (
    CONSTRAINT_NAMES,
    PAPER,
    PUMA560_NOMINAL_POWER_KW,
    Params,
    constraint_names,
)
from legcore.studies.path_placement.region import (
    Region,
    SphericalWorkspace,
    is_puma_type,
    reach_shell,
    region_of,
    simplified_workspace,
)
from legcore.studies.study import Solution, StudyProblem
from legcore.studies.task import Violation

__all__ = [
    "CONSTRAINT_NAMES",
    "NEEDS",
    "PAPER",
    "PUMA560_NOMINAL_POWER_KW",
    "Params",
    "PathPlacementProblem",
    "SphericalWorkspace",
    "max_manipulability",
    "simplified_workspace",
]

FloatArray = NDArray[np.float64]

#: What the study needs from a robot: a serial arm of at least 6 actuated joints (a tool pose
#: has 6 coordinates). Motor data are optional (electrical energy where they exist).
NEEDS = Needs(serial=True, min_joints=6)

# Samples (candidates × branches × path points) per chunk of a batch evaluation (memory bound).
_CHUNK_SAMPLES = 160_000
# Constraint excess per unreachable path: 1 + this × fraction of unreachable points.
_UNREACHABLE_SLOPE = 10.0
# Objective / constraint value that replaces a non-finite one.
_NONFINITE_PENALTY = 1e6


@dataclass(frozen=True, eq=False)
class _Batch:
    """Per-branch results of a batch of B candidates over nb IK branches.

    Shapes: scalars (B, nb); ``G`` (B, nb, 2n + 1); with ``detail`` the signals (B, nb, K, n).
    """

    J: FloatArray
    G: FloatArray
    cv: FloatArray
    energy: FloatArray
    mean_w: FloatArray
    duration: FloatArray
    peak_power: FloatArray
    unreachable: FloatArray
    detail: dict[str, NDArray[Any]] | None = None


class PathPlacementProblem(StudyProblem):
    """Minimise eq 15 over the placement ``x`` (3,) of a tool path in a region.

    ``F`` (B, 1) = ``PC·P̄/P_n + PM·(1 − w_p/w_M)``; ``G`` (B, 2n + 1), see the module docstring.
    Attributes: ``robot``, ``params``, ``path`` (:class:`ToolPath` at its original location),
    ``workspace`` (the region: :class:`SphericalWorkspace` or ``BoxRegion``), ``w_max`` (m³),
    ``P_n`` (W), ``x_original`` (3,), ``anchor`` (3,) m (the path point that is placed),
    ``closed_form`` (the PUMA-type fast path), ``energy_kind`` ("electrical"/"mechanical"),
    ``branch_names`` and ``constraint_names``.
    """

    objective_names = ("J",)

    def __init__(self, robot: Robot, params: Params) -> None:
        if not isinstance(robot, Robot) or robot.nq < 6:
            raise ValueError(
                f"robot: path_placement needs a serial arm of ≥ 6 actuated joints; robot "
                f"{getattr(robot, 'name', robot)} has {getattr(robot, 'nq', 'no serial chain')}"
            )
        self.robot = robot
        self.params = params
        self.path = params.tool_path()
        self.closed_form = is_puma_type(robot)
        has_motors = bool(robot.motors.electrical.any())
        if params.energy == "electrical" and not has_motors:
            raise ValueError(
                f"robot: path_placement with energy 'electrical' needs motor data (Kt, Ke, R) on "
                f"some joint; robot {robot.name} has none (use energy 'mechanical' or 'auto')"
            )
        self.energy_kind = ("electrical" if params.energy == "electrical"
                            or (params.energy == "auto" and has_motors) else "mechanical")
        if params.region is not None:
            self.workspace: Region = region_of(params.region, robot)
        else:
            self.workspace = simplified_workspace(robot) if self.closed_form else reach_shell(robot)
        self.w_max = (float(params.max_manipulability) if params.max_manipulability is not None
                      else max_manipulability(robot)[0])
        if params.nominal_power_kw is None:
            raise ValueError("nominal_power_kw: not set (derived from the robot by Study.task)")
        self.P_n = 1000.0 * params.nominal_power_kw
        p = self.path.p
        self.anchor = p[0].copy() if params.anchor == "first" else p.mean(axis=0)
        self.x_original = (np.asarray(params.original, dtype=float) if params.original is not None
                           else self.workspace.coords(self.anchor))
        n = robot.nq
        starts = [robot.home] if params.postures is None else [
            np.asarray(s, dtype=float) for s in params.postures]
        for i, s in enumerate(starts):
            if s.shape != (n,):
                raise ValueError(f"postures.{i}: {s.size} values for the {n} joints of "
                                 f"{robot.name}")
            if not robot.within_limits(s, tol=0.0):
                raise ValueError(f"postures.{i}: outside the joint limits of {robot.name}")
        self.starts = np.stack(starts)
        if self.closed_form:
            self.branches: tuple[int, ...] = (tuple(range(len(BRANCH_NAMES)))
                                              if params.branch == "best"
                                              else (BRANCH_NAMES.index(params.branch),))
            self.branch_names = tuple(BRANCH_NAMES[b] for b in self.branches)
        elif params.branch != "best":
            raise ValueError(
                f"branch: the named branches are those of the PUMA-type closed form; "
                f"{robot.name} is solved numerically (one branch per start posture): use 'best'"
            )
        else:
            self.branches = tuple(range(len(starts)))
            self.branch_names = tuple(f"posture {i}" for i in self.branches)
        #: the joint torques are constrained on an arm whose every joint has a torque limit
        self.torque = bool(np.all(np.isfinite(robot.tau_max)))
        self.constraint_names = constraint_names(n, self.torque)
        self.n_samples = self.path.n_points * len(self.branches)
        ws = self.workspace
        super().__init__(3, 1, len(self.constraint_names), xl=ws.xl, xu=ws.xu,
                         name=f"path_placement[{self.path.name}]")

    # ------------------------------------------------------------------ core
    def placed_poses(self, X: ArrayLike) -> FloatArray:
        """Tool poses (B, K, 4, 4) of the path placed at each row of ``X`` (B, 3)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        shift = self.workspace.point(X) - self.anchor  # (B, 3)
        T = np.broadcast_to(self.path.T, (X.shape[0], *self.path.T.shape)).copy()
        T[:, :, :3, 3] += shift[:, None, :]
        return T

    def _power(self, qd: FloatArray, tau: FloatArray, t: FloatArray) -> tuple[
        FloatArray, FloatArray, FloatArray, FloatArray | None
    ]:
        """(power per joint (…, K, n) W, total power (…, K) W, energy (…) J, currents or None)
        of the chosen energy kind."""
        if self.energy_kind == "electrical":
            el = electrical_energy(qd, tau, t, self.robot, regenerative=self.params.regenerative)
            P_total = np.sum(np.where(el.joints, el.power, 0.0), axis=-1)
            return el.power, P_total, el.total, el.current
        power = np.abs(tau * qd)
        P_total = power.sum(axis=-1)
        return power, P_total, integrate(power, t).sum(axis=-1), None

    def _manipulability(self, q: FloatArray) -> FloatArray:
        if self.closed_form:
            return manipulability_split(self.robot, q)[0]
        return manipulability(self.robot, q)

    def _batch(self, X: FloatArray, detail: bool = False) -> _Batch:
        robot, prm = self.robot, self.params
        B = X.shape[0]
        K = self.path.n_points
        nb = len(self.branches)
        T = self.placed_poses(X)
        q, ok = placed_path_joints(robot, T, closed_form=self.closed_form,
                                   branches=self.branches, starts=self.starts,
                                   rest=self.starts[0])
        unreach = 1.0 - ok.mean(axis=-1)  # (B, nb)
        # time grid
        if prm.timing == "path":
            t: FloatArray = self.path.t
        else:
            dt_path = np.diff(self.path.t)
            dq = np.abs(np.diff(q, axis=-2)) / (prm.speed_fraction * robot.qd_max)
            dt = np.maximum(dt_path, dq.max(axis=-1))  # (B, nb, K-1)
            t = np.concatenate([np.zeros((B, nb, 1)), np.cumsum(dt, axis=-1)], axis=-1)
        qd = gradient(q, t)
        qdd = gradient(qd, t)
        tau = inverse_dynamics(robot, q, qd, qdd, friction=prm.friction)
        power, P_total, energy, current = self._power(qd, tau, t)
        duration = t[..., -1] - t[..., 0] if np.ndim(t) > 1 else np.full((B, nb), t[-1] - t[0])
        w = self._manipulability(q)  # (B, nb, K)
        mean_w = w.mean(axis=-1)
        PC = prm.energy_weight
        J = PC * energy / (self.P_n * duration) + (1.0 - PC) * (1.0 - mean_w / self.w_max)
        # constraints (B, nb, 2n + 1)
        span = robot.q_max - robot.q_min
        excess = np.maximum(robot.q_min - q, q - robot.q_max).max(axis=-2) / span  # (B, nb, n)
        pen = np.where(unreach > 0.0, 1.0 + _UNREACHABLE_SLOPE * unreach, 0.0)[..., None]
        g_pos = np.where(pen > 0.0, np.maximum(excess, 0.0) + pen, excess)
        g_vel = np.abs(qd).max(axis=-2) / robot.qd_max - 1.0
        g_pow = P_total.max(axis=-1) / self.P_n - 1.0
        parts = [g_pos, g_vel]
        if self.torque:
            parts.append(np.abs(tau).max(axis=-2) / robot.tau_max - 1.0)
        G = np.concatenate([*parts, g_pow[..., None]], axis=-1)
        cv = np.maximum(G, 0.0).sum(axis=-1)
        extra = None
        if detail:
            extra = {
                "t": np.broadcast_to(t, (B, nb, K)),
                "q": q, "qd": qd, "qdd": qdd, "tau": tau, "power": power,
                "P_total": P_total, "w": w, "ok": ok,
                "T": np.broadcast_to(T[:, None], (B, nb, K, 4, 4)),
            }
            if current is not None:
                extra["current"] = current
        return _Batch(J, G, cv, energy, mean_w, duration, P_total.max(axis=-1), unreach, extra)

    @staticmethod
    def _select(b: _Batch) -> NDArray[np.int64]:
        """Per candidate, the branch (index into the batch's branches) with the least total
        constraint violation, then the least J."""
        cv = np.round(b.cv, 12)
        order = np.lexsort((b.J, cv), axis=-1)
        return order[..., 0]

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        B = X.shape[0]
        per = max(1, _CHUNK_SAMPLES // self.n_samples)
        F = np.empty((B, 1))
        G = np.empty((B, self.n_constr))
        for s in range(0, B, per):  # chunks of candidates (memory bound), each one batched call
            b = self._batch(X[s:s + per])
            i = self._select(b)
            rows = np.arange(i.shape[0])
            F[s:s + per, 0] = b.J[rows, i]
            G[s:s + per] = b.G[rows, i]
        # never hand a worker NaN/inf (e.g. from a degenerate user path): a large finite violation
        G = np.where(np.isfinite(G), G, _NONFINITE_PENALTY)
        F = np.where(np.isfinite(F), F, _NONFINITE_PENALTY)
        return F, G

    # ------------------------------------------------------------------ reporting
    def _detail(self, x: ArrayLike) -> dict[str, Any]:
        """Everything about one placement ``x`` (3,) with its chosen branch."""
        x = np.asarray(x, dtype=float).reshape(1, 3)
        b = self._batch(x, detail=True)
        i = int(self._select(b)[0])
        assert b.detail is not None
        d: dict[str, Any] = {k: np.asarray(v[0, i]) for k, v in b.detail.items()}
        d.update(
            x=x[0],
            branch_index=self.branches[i],
            branch=self.branch_names[i],
            J=float(b.J[0, i]),
            G=b.G[0, i],
            cv=float(b.cv[0, i]),
            energy=float(b.energy[0, i]),
            mean_w=float(b.mean_w[0, i]),
            duration=float(b.duration[0, i]),
            peak_power=float(b.peak_power[0, i]),
            unreachable=float(b.unreachable[0, i]),
            branch_table=[
                {"branch": name, "J": float(b.J[0, j]), "cv": float(b.cv[0, j])}
                for j, name in enumerate(self.branch_names)
            ],
        )
        return d

    def metrics_of(self, x: ArrayLike) -> dict[str, float]:
        """The scalar metrics of placement ``x`` (3,), no comparison with the original
        (:func:`legcore.studies.path_placement.report.metrics`)."""
        return report.metrics(self, self._detail(x))

    def solution(self, x: FloatArray) -> Solution:
        x = np.asarray(x, dtype=float)
        if x.shape != (3,):
            raise ValueError(f"x: expected {self.workspace.variable_names} of shape (3,), "
                             f"got {x.shape}")
        if not np.all(np.isfinite(x)):
            raise ValueError("x: must be finite")
        return report.solution(self, x, self._detail(x), self._original_metrics(),
                               self._original_violations())

    def _original_metrics(self) -> dict[str, float]:
        cached = getattr(self, "_orig_cache", None)
        if cached is None:
            cached = self.metrics_of(self.x_original)
            self._orig_cache = cached
        return cached

    def _original_violations(self) -> tuple[Violation, ...]:
        """What the original placement violates (cached): the % changes need it feasible."""
        cached: tuple[Violation, ...] | None = getattr(self, "_orig_broken", None)
        if cached is None:
            cached = self.violations(self.x_original)
            self._orig_broken = cached
        return cached

    def baseline_solutions(self) -> dict[str, Solution]:
        return {"original": self.solution(self.x_original)}

    def violations(self, x: FloatArray) -> tuple[Violation, ...]:
        """What placement ``x`` (3,) breaks, in words and units: the share of the path out of
        reach (%), each joint beyond its position limits (rad), over its speed (rad/s) or
        torque (N·m) limit, and the peak power over P_n (W)."""
        return report.violations(self, self._detail(np.asarray(x, dtype=float)))

    def free_start(self) -> tuple[str, FloatArray] | None:
        """The path where it is written (no search needed to get it)."""
        return "the original placement", np.asarray(self.x_original, dtype=float)

    def extras(self, front_X: FloatArray, front_F: FloatArray) -> dict[str, Any]:
        return {
            "workspace": self.workspace.as_dict(),
            "w_M": self.w_max,
            "P_n_W": self.P_n,
            "x_original": self.x_original.tolist(),
            "original_feasible": self._original_metrics()["feasible"] == 1.0,
            "energy_kind": self.energy_kind,
            "path": {"name": self.path.name, "points": self.path.n_points,
                     "duration_s": self.path.duration, "length_m": self.path.length},
            "paper": PAPER.get(self.path.name, {}),
        }
