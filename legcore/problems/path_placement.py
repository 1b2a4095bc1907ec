"""``path_placement`` — seed 001: place a tool path in the workspace of a 6R arm for electrical
energy and manipulability, with the Heuristic Kalman Algorithm.

A Cartesian path with tool orientations (:mod:`legcore.problems.path_placement_paths`: the
built-in ``pan`` and ``jar`` paths or CSV text) is translated so that its anchor point (its first
point, as in the paper, or its centroid) lies at the point ``p(R, γ, φ)`` of the simplified
spherical workspace of a spherical-wrist 6R arm (seed 001 eqs 1–5, :func:`simplified_workspace`);
the tool orientations are kept ("conservando la orientación de la herramienta"). Decision
variables ``x = (R, γ, φ)`` (m, rad, rad). For a whole population at once:

1. every path point → closed-form IK (:func:`legcore.ik.puma560.puma560_ik`, the closed form
   behind :func:`legcore.kinematics.ik` for ``ik_family == "puma560"``), all 8 branches;
2. per branch one continuous joint trajectory: unreachable points filled from their reachable
   neighbours (and penalised, see below), angles unwrapped along the path and shifted by 2π as a
   whole into the joint limits where possible;
3. time grid: the path's own time stamps (``timing="path"``), or each segment stretched so that
   no joint exceeds ``speed_fraction·q̇_max`` (``timing="joint_limited"``: the duration then
   depends on the placement, as in the paper's Tables 2–3);
4. ``q̇, q̈`` by finite differences (second order inside, as ``numpy.gradient``); torques by
   batched RNEA with motor friction (:func:`legcore.dynamics.inverse_dynamics`); electrical
   energy of the DC motors (:func:`legcore.energy.electrical_energy`, eqs 9–14);
   manipulability ``w = w_A |sin θ5|`` (:func:`legcore.kinematics.manipulability_split`,
   eqs 6–8) averaged over the points;
5. cost (eq 15) ``J = PC·C/(P_n t) + PM·(1 − w_p/w_M)`` with ``C/(P_n t)`` = mean electrical
   power / nominal power, ``PM = 1 − PC``; the penalty term ``ϖ Σ max(g_i, 0)`` of eq 15 is the
   optimiser's (HKA ``penalty`` = ϖ) over the 13 constraints ``G``:

   - ``g_1..g_6`` joint position: the largest excursion of joint i beyond its limits over the
     path, as a fraction of its range (negative: the smallest margin); a path point the arm
     cannot reach adds ``1 + 10·(fraction of unreachable points)`` to each of the six;
   - ``g_7..g_12`` joint speed: ``max_k |q̇_ik| / q̇_max,i − 1``;
   - ``g_13`` nominal power: peak total electrical power of the motors / P_n − 1;
6. the branch of each candidate is the best of the 8 for the whole path: least total constraint
   violation, then least J (``branch="best"``); or one named branch for every candidate.

Reported per solution (:meth:`PathPlacementProblem.solution`): energy (J and kWh), mean
manipulability, duration, J, the constraints, and the % change against the ORIGINAL placement
(the path where it is written: the built-in paths' "as drawn" location, or the CSV's
coordinates, or ``original`` in the parameters), which is also the ``original`` baseline.
The decoded ``Motion`` has ``power_kind="electrical"``: the motors' electrical power per joint
(0 on the wrist joints, which have no motor data) and its cumulative integral.

Defaults (PC = 0.5, P_n = 0.4 kW, the HKA settings, the built-in paths and their originals) are
the seed's where it gives them and documented choices otherwise:
docs/studies.md (seed 001).

:func:`compare_initialisations` runs HKA with its original initialisation (eq 16) and with the
seed's modified initialisation (a coarse survey first) over several seeds (seed 001 Figure 8).
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field, model_validator
from scipy.optimize import minimize as scipy_minimize

from legcore.dynamics import inverse_dynamics
from legcore.energy import electrical_energy, integrate, joules_to_kwh
from legcore.ik.puma560 import BRANCH_NAMES, puma560_geometry, puma560_ik
from legcore.kinematics import frames, manipulability_split
from legcore.problems.path_placement_paths import (
    MAX_CSV_CHARS,
    ToolPath,
    builtin_path,
    parse_path_csv,
)
from legcore.problems.study import Motion, Solution, Study, StudyParams, StudyProblem
from legcore.robots.model import Robot

__all__ = [
    "CONSTRAINT_NAMES",
    "PAPER",
    "Params",
    "PathPlacementProblem",
    "STUDY",
    "SphericalWorkspace",
    "build",
    "compare_initialisations",
    "max_manipulability",
    "simplified_workspace",
]

FloatArray = NDArray[np.float64]

CONSTRAINT_NAMES: tuple[str, ...] = (
    *(f"q{i}_limit" for i in range(1, 7)),
    *(f"qd{i}_limit" for i in range(1, 7)),
    "nominal_power",
)

#: The paper's results (seed 001 Tables 2, 3; §3.3): original vs optimised, its units.
PAPER: dict[str, dict[str, Any]] = {
    "pan": {
        "name": "Robotworks",
        "points": 225,
        "iterations": 20,
        "x_opt": (0.61642617, 0.51938117, -2.34115865),
        "time_s": (1.01205355, 0.87839920),
        "energy_kwh": (5.15545e-06, 2.38541e-06),
        "mean_w": (0.05889245, 0.11868260),
        "pct": {"time": 13.21, "energy": 53.73, "w": 50.38},
    },
    "jar": {
        "name": "Tarro Inclinado",
        "points": 413,
        "iterations": 27,
        "x_opt": (0.77493786, 0.438154, -0.05930750),
        "time_s": (1.66888271, 1.65655682),
        "energy_kwh": (2.28492e-05, 1.5657e-05),
        "mean_w": (0.02860888, 0.1060444),
        "pct": {"time": 0.74, "energy": 31.48, "w": 73.02},
    },
}

#: Default nominal power P_n of the PUMA 560 (kW), see ``Params.nominal_power_kw``.
PUMA560_NOMINAL_POWER_KW = 0.4

# Samples (candidates × branches × path points) per chunk of a batch evaluation (memory bound).
_CHUNK_SAMPLES = 160_000
# Constraint excess per unreachable path: 1 + this × fraction of unreachable points.
_UNREACHABLE_SLOPE = 10.0
# Objective / constraint value that replaces a non-finite one.
_NONFINITE_PENALTY = 1e6

BranchName = Literal[
    "best",
    "left-up-noflip",
    "left-up-flip",
    "left-down-noflip",
    "left-down-flip",
    "right-up-noflip",
    "right-up-flip",
    "right-down-noflip",
    "right-down-flip",
]


# ---------------------------------------------------------------------------------------------
# parameters
# ---------------------------------------------------------------------------------------------


class Params(StudyParams):
    """Parameters of the ``path_placement`` study (defaults: seed 001's own settings, where it
    gives them; see docs/studies.md (seed 001) for the chosen ones).

    - ``path``: ``"pan"`` (Robotworks stand-in, 225 points), ``"jar"`` (tilted jar, 413
      points) or ``"csv"`` (the text in ``csv``, see :func:`parse_path_csv`).
    - ``duration`` (s): the path's duration when it has no time stamps (CSV without ``t``;
      for a built-in path it overrides the paper's time).
    - ``timing``: ``"path"`` (the path's time stamps) or ``"joint_limited"`` (segments
      stretched so no joint exceeds ``speed_fraction·q̇_max``; the duration then varies).
    - ``anchor``: the path point placed at ``p(R, γ, φ)``: ``"first"`` (the paper) or
      ``"centroid"``.
    - ``original`` (m, rad, rad): the (R, γ, φ) of the original placement; default: where the
      path is written.
    - ``energy_weight``: PC of eq 15 in [0, 1] (PM = 1 − PC). The paper does not give it.
    - ``nominal_power_kw``: P_n of eq 15 and of constraint 13 (kW).
    - ``max_manipulability``: w_M of eq 15 (m³); default: computed from the robot.
    - ``branch``: ``"best"`` (per candidate, best of the 8 IK branches) or one branch name.
    - ``friction``: motor/gear friction in the torques; ``regenerative``: integrate the signed
      electrical power (eq 14, braking returns energy) or only its positive part per motor.
    """

    kind: Literal["path_placement"] = "path_placement"
    path: Literal["pan", "jar", "csv"] = "pan"
    csv: str | None = Field(default=None, max_length=MAX_CSV_CHARS)
    duration: float | None = Field(default=None, gt=0.0, le=3600.0)
    timing: Literal["path", "joint_limited"] = "path"
    speed_fraction: float = Field(default=1.0, gt=0.0, le=1.0)
    anchor: Literal["first", "centroid"] = "first"
    original: tuple[float, float, float] | None = None
    energy_weight: float = Field(default=0.5, ge=0.0, le=1.0)
    nominal_power_kw: float = Field(default=PUMA560_NOMINAL_POWER_KW, gt=0.0, le=1000.0)
    max_manipulability: float | None = Field(default=None, gt=0.0)
    branch: BranchName = "best"
    friction: bool = True
    regenerative: bool = True

    @model_validator(mode="after")
    def _check(self) -> Params:
        if self.path == "csv":
            if self.csv is None:
                raise ValueError("csv: required when path is 'csv'")
            parse_path_csv(self.csv, self.duration)  # raises ValueError("csv: ...")
        elif self.csv is not None:
            raise ValueError(f"csv: only used with path='csv', not path={self.path!r}")
        if self.original is not None:
            R, gamma, phi = self.original
            if not all(math.isfinite(v) for v in self.original):
                raise ValueError("original: (R, γ, φ) must be finite")
            if R <= 0.0:
                raise ValueError(f"original: R must be > 0 m, got {R}")
            if abs(gamma) > math.pi / 2:
                raise ValueError(f"original: γ must lie in [−π/2, π/2] rad, got {gamma}")
            if abs(phi) > 2 * math.pi:
                raise ValueError(f"original: φ must lie in [−2π, 2π] rad, got {phi}")
        return self

    def tool_path(self) -> ToolPath:
        """The path these parameters describe (at its original location)."""
        if self.path == "csv":
            assert self.csv is not None
            return parse_path_csv(self.csv, self.duration)
        return builtin_path(self.path, self.duration)


# ---------------------------------------------------------------------------------------------
# simplified spherical workspace (eqs 1–5) and maximum manipulability
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class SphericalWorkspace:
    """Seed 001's simplified workspace of a spherical-wrist 6R arm (eqs 1–5).

    A sphere centred at ``origin`` O_s (the end of d1, world frame, m), between the radii
    ``R_min`` (RM_n) and ``R_max`` (RM_y) (m), colatitude γ from ``gamma_up`` (γ_RS = −π/2,
    straight up) to ``gamma_low`` (γ_RI) and azimuth φ in [``phi_low``, ``phi_up``] (the limits
    of joint 1), rad. ``q_far``/``q_near`` (6,) are the configurations RM_y/γ_RI and RM_n were
    measured at; ``base_R`` (3, 3) the rotation of the robot base (axes of eq 5).
    """

    origin: FloatArray
    base_R: FloatArray
    R_min: float
    R_max: float
    gamma_up: float
    gamma_low: float
    phi_low: float
    phi_up: float
    q_far: FloatArray
    q_near: FloatArray

    @property
    def xl(self) -> FloatArray:
        """Lower bounds of (R, γ, φ)."""
        return np.array([self.R_min, self.gamma_up, self.phi_low])

    @property
    def xu(self) -> FloatArray:
        """Upper bounds of (R, γ, φ)."""
        return np.array([self.R_max, self.gamma_low, self.phi_up])

    def point(self, x: ArrayLike) -> FloatArray:
        """Eq 5: world points (..., 3) m of ``x = (R, γ, φ)`` (..., 3)::

            p_x = cos φ |R cos γ|,  p_y = sin φ |R cos γ|,  p_z = −R sin γ + d1
        """
        x = np.asarray(x, dtype=float)
        R, g, f = x[..., 0], x[..., 1], x[..., 2]
        rho = np.abs(R * np.cos(g))
        local = np.stack([np.cos(f) * rho, np.sin(f) * rho, -R * np.sin(g)], axis=-1)
        return self.origin + local @ self.base_R.T

    def coords(self, p: ArrayLike) -> FloatArray:
        """Inverse of :meth:`point`: ``(R, γ, φ)`` (..., 3) of world points ``p`` (..., 3)."""
        d = (np.asarray(p, dtype=float) - self.origin) @ self.base_R
        rho = np.hypot(d[..., 0], d[..., 1])
        R = np.hypot(rho, d[..., 2])
        return np.stack([R, np.arctan2(-d[..., 2], rho), np.arctan2(d[..., 1], d[..., 0])], axis=-1)

    def as_dict(self) -> dict[str, Any]:
        return {
            "origin": self.origin.tolist(),
            "RM_n": self.R_min,
            "RM_y": self.R_max,
            "gamma_RS": self.gamma_up,
            "gamma_RI": self.gamma_low,
            "phi_RI": self.phi_low,
            "phi_RS": self.phi_up,
            "q_far": self.q_far.tolist(),
            "q_near": self.q_near.tolist(),
        }


def _check_arm(robot: Robot) -> None:
    """ValueError unless ``robot`` is a PUMA-type spherical-wrist 6R arm with DC-motor data."""
    if not isinstance(robot, Robot):
        raise ValueError("robot: the path_placement study needs a serial 6R arm")
    if robot.ik_family != "puma560":
        raise ValueError(
            f"robot: the path_placement study needs a PUMA-type spherical-wrist 6R arm with the "
            f"closed-form IK (ik='puma560'); {robot.name!r} has ik={robot.ik_family!r}"
        )
    try:
        puma560_geometry(robot.spec)
    except ValueError as exc:
        raise ValueError(f"robot: {exc}") from None
    if not robot.motors.electrical.any():
        raise ValueError(
            f"robot: {robot.name!r} has no motor with Kt, Ke and R; the electrical energy of "
            f"seed 001 needs them"
        )


def simplified_workspace(robot: Robot) -> SphericalWorkspace:
    """The simplified spherical workspace of a PUMA-type arm, measured by forward kinematics
    at the configurations of seed 001 §2.2 (see the study docs for the sign conventions).

    - ``RM_y`` (eq 1) and ``γ_RI`` (eq 3): wrist centre at θ1 = 0, θ2 = the joint-2 limit that
      points the stretched arm lowest in front of the robot (the paper's θ2S; in the
      roboticstoolbox convention of our PUMA θ2 turns the other way, so it is our lower limit
      −45°), θ3 = the middle of the joint-3 range (the paper prints θ3 = θ3S + θ3I, which
      folds the arm back; (θ3S + θ3I)/2 = −90° is the stretched elbow), θ4..θ6 = (π, 0, 0);
      ``RM_y = sqrt(x² + (z − d1)²)``, ``γ_RI = acos(x / RM_y)``.
    - ``RM_n`` (eq 2, printed with RM_y on its left): θ2 with the upper arm vertical (the
      paper's −90°, our +90°), θ3 = the joint-3 upper limit θ3S.
    - ``γ_RS = −π/2``; ``φ_RI, φ_RS`` = joint 1 limits (eq 4).

    Coordinates are taken in the base frame relative to O_s = base·(0, 0, d1); like eq 1 they
    ignore the shoulder offset (y).
    """
    _check_arm(robot)
    geo = puma560_geometry(robot.spec)
    base = geo.base
    origin_h = base @ np.array([0.0, 0.0, geo.d1, 1.0])
    origin = origin_h[:3]
    base_R = base[:3, :3]
    off = geo.offset
    q_min, q_max = robot.q_min, robot.q_max

    def local(q: FloatArray) -> FloatArray:
        pw = frames(robot, q)[..., 4, :3, 3]  # DH frame 4 origin = wrist centre
        return (pw - origin) @ base_R

    mid3 = 0.5 * (q_min[2] + q_max[2])
    cands = np.array([[0.0, q2, mid3, math.pi, 0.0, 0.0] for q2 in (q_min[1], q_max[1])])
    cands[:, 0] -= off[0]
    loc = local(cands)
    front = loc[:, 0] > 0.0
    order = np.lexsort((loc[:, 2], ~front))  # in front first, then lowest
    q_far = cands[order[0]]
    d_far = loc[order[0]]
    R_max = float(math.hypot(d_far[0], d_far[2]))
    gamma_low = float(math.acos(np.clip(d_far[0] / R_max, -1.0, 1.0)))
    q_near = np.array([-off[0], math.pi / 2 - off[1], q_max[2], math.pi, 0.0, 0.0])
    d_near = local(q_near)
    R_min = float(math.hypot(d_near[0], d_near[2]))
    if not R_min < R_max:
        raise ValueError(f"robot: degenerate simplified workspace (RM_n = {R_min:.4g} m >= "
                         f"RM_y = {R_max:.4g} m)")
    return SphericalWorkspace(
        origin=origin,
        base_R=base_R,
        R_min=R_min,
        R_max=R_max,
        gamma_up=-math.pi / 2,
        gamma_low=gamma_low,
        phi_low=float(q_min[0] + off[0]),
        phi_up=float(q_max[0] + off[0]),
        q_far=q_far,
        q_near=q_near,
    )


_WM_CACHE: weakref.WeakKeyDictionary[Robot, tuple[float, FloatArray]] = weakref.WeakKeyDictionary()


def max_manipulability(robot: Robot) -> tuple[float, FloatArray]:
    """``(w_M, q)``: the largest ``w = w_A |sin θ5|`` (m³) over the joint limits and where.

    A 361 × 361 grid over (θ2, θ3) within their limits (w does not depend on θ1, θ4, θ6, and
    θ5 = ±90° is taken when inside its limits, else the limit nearest it), refined by L-BFGS-B.
    Computed once per robot.
    """
    cached = _WM_CACHE.get(robot)
    if cached is not None:
        return cached
    _check_arm(robot)
    lo, hi = robot.q_min, robot.q_max
    off = np.array([j.offset for j in robot.spec.joints])  # type: ignore[union-attr]
    # θ5 with the largest |sin θ5| inside the limits
    cand5 = np.array([math.pi / 2, -math.pi / 2, lo[4] + off[4], hi[4] + off[4]]) - off[4]
    cand5 = cand5[(cand5 >= lo[4]) & (cand5 <= hi[4])]
    q5 = float(cand5[np.argmax(np.abs(np.sin(cand5 + off[4])))])
    g2, g3 = np.meshgrid(np.linspace(lo[1], hi[1], 361), np.linspace(lo[2], hi[2], 361),
                         indexing="ij")
    q = np.zeros(g2.shape + (6,))
    q[..., 1], q[..., 2], q[..., 4] = g2, g3, q5
    w = manipulability_split(robot, q)[0]
    i = np.unravel_index(int(np.argmax(w)), w.shape)
    q_best = q[i].copy()

    def neg_w(z: FloatArray) -> float:
        qq = q_best.copy()
        qq[1:3] = z
        return -float(manipulability_split(robot, qq)[0])

    res = scipy_minimize(neg_w, q_best[1:3], method="L-BFGS-B",
                         bounds=[(lo[1], hi[1]), (lo[2], hi[2])])
    if -res.fun > w[i]:
        q_best[1:3] = res.x
    w_M = float(manipulability_split(robot, q_best)[0])
    _WM_CACHE[robot] = (w_M, q_best)
    return w_M, q_best


# ---------------------------------------------------------------------------------------------
# batched evaluation helpers
# ---------------------------------------------------------------------------------------------


def _gradient(y: FloatArray, t: FloatArray) -> FloatArray:
    """d y / d t along axis −2 of ``y`` (..., K, n) on the grid ``t`` (K,) or (..., K).

    Second-order central differences inside (non-uniform grid, as ``numpy.gradient``), first
    order at the ends.
    """
    t = np.asarray(t, dtype=float)
    h = np.diff(t, axis=-1)[..., None]  # (..., K-1, 1)
    out = np.empty_like(y)
    h1 = h[..., :-1, :]
    h2 = h[..., 1:, :]
    out[..., 1:-1, :] = (
        h1**2 * y[..., 2:, :] - h2**2 * y[..., :-2, :] + (h2**2 - h1**2) * y[..., 1:-1, :]
    ) / (h1 * h2 * (h1 + h2))
    out[..., 0, :] = (y[..., 1, :] - y[..., 0, :]) / h[..., 0, :]
    out[..., -1, :] = (y[..., -1, :] - y[..., -2, :]) / h[..., -1, :]
    return out


def _fill_unreachable(q: FloatArray, ok: NDArray[np.bool_], home: FloatArray) -> FloatArray:
    """Replace the samples of ``q`` (..., K, n) where ``ok`` (..., K) is False by the nearest
    earlier reachable sample (else the nearest later one; ``home`` if none is reachable)."""
    K = q.shape[-2]
    idx = np.arange(K)
    fwd = np.maximum.accumulate(np.where(ok, idx, -1), axis=-1)
    bwd = np.flip(np.minimum.accumulate(np.flip(np.where(ok, idx, K), axis=-1), axis=-1), axis=-1)
    src = np.where(fwd >= 0, fwd, bwd)
    none = src >= K
    src = np.where(none, 0, src)
    out = np.take_along_axis(q, src[..., None], axis=-2)
    return np.where(none[..., None], home, out)


def _shift_into_limits(q: FloatArray, lo: FloatArray, hi: FloatArray) -> FloatArray:
    """Shift each joint's whole trajectory in ``q`` (..., K, n) by a multiple of 2π so that it
    violates its limits least (ties: closest to the middle of the range)."""
    qmin = q.min(axis=-2)[..., None]  # (..., n, 1)
    qmax = q.max(axis=-2)[..., None]
    ks = 2.0 * math.pi * np.arange(-2, 3, dtype=float)  # (5,)
    lo_ = lo[:, None]
    hi_ = hi[:, None]
    viol = np.maximum(lo_ - (qmin + ks), 0.0) + np.maximum(qmax + ks - hi_, 0.0)
    centre = np.abs(0.5 * (qmin + qmax) + ks - 0.5 * (lo_ + hi_))
    score = np.round(viol, 12) * 1e3 + centre
    k = np.argmin(score, axis=-1)  # (..., n)
    return q + ks[k][..., None, :]


@dataclass(frozen=True, eq=False)
class _Batch:
    """Per-branch results of a batch of B candidates over the 8 (or 1) IK branches.

    Shapes: scalars (B, nb); ``G`` (B, nb, 13); with ``detail`` the signals (B, nb, K, n).
    """

    J: FloatArray
    G: FloatArray
    cv: FloatArray
    energy: FloatArray
    mean_w: FloatArray
    duration: FloatArray
    peak_power: FloatArray
    unreachable: FloatArray
    branches: tuple[int, ...]
    detail: dict[str, FloatArray] | None = None


# ---------------------------------------------------------------------------------------------
# the problem
# ---------------------------------------------------------------------------------------------


class PathPlacementProblem(StudyProblem):
    """Seed 001: minimise eq 15 over the placement ``x = (R, γ, φ)`` of a tool path.

    ``F`` (B, 1) = ``PC·P̄/P_n + PM·(1 − w_p/w_M)``; ``G`` (B, 13), see the module docstring.
    Attributes: ``robot``, ``params``, ``path`` (:class:`ToolPath` at its original location),
    ``workspace`` (:class:`SphericalWorkspace`), ``w_max`` (m³), ``P_n`` (W), ``x_original``
    (3,) and ``anchor`` (3,) m (the path point that is placed).
    """

    objective_names = ("J",)

    def __init__(self, robot: Robot, params: Params) -> None:
        _check_arm(robot)
        self.robot = robot
        self.params = params
        self.path = params.tool_path()
        self.workspace = simplified_workspace(robot)
        self.w_max = (
            float(params.max_manipulability)
            if params.max_manipulability is not None
            else max_manipulability(robot)[0]
        )
        self.P_n = 1000.0 * params.nominal_power_kw
        self.geometry = puma560_geometry(robot.spec)
        p = self.path.p
        self.anchor = p[0].copy() if params.anchor == "first" else p.mean(axis=0)
        self.x_original = (
            np.asarray(params.original, dtype=float)
            if params.original is not None
            else self.workspace.coords(self.anchor)
        )
        if params.branch == "best":
            self.branches: tuple[int, ...] = tuple(range(len(BRANCH_NAMES)))
        else:
            self.branches = (BRANCH_NAMES.index(params.branch),)
        self.n_samples = self.path.n_points * len(self.branches)
        ws = self.workspace
        super().__init__(3, 1, len(CONSTRAINT_NAMES), xl=ws.xl, xu=ws.xu,
                         name=f"path_placement[{self.path.name}]")

    # ------------------------------------------------------------------ core
    def placed_poses(self, X: ArrayLike) -> FloatArray:
        """Tool poses (B, K, 4, 4) of the path placed at each row of ``X`` (B, 3)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        shift = self.workspace.point(X) - self.anchor  # (B, 3)
        T = np.broadcast_to(self.path.T, (X.shape[0], *self.path.T.shape)).copy()
        T[:, :, :3, 3] += shift[:, None, :]
        return T

    def _batch(self, X: FloatArray, detail: bool = False) -> _Batch:
        robot, prm = self.robot, self.params
        B = X.shape[0]
        K = self.path.n_points
        br = np.asarray(self.branches)
        nb = br.size
        T = self.placed_poses(X)
        sol = puma560_ik(T, self.geometry)  # principal values; q (B, K, 8, 6)
        q = np.moveaxis(sol.q[:, :, br, :], 1, 2)  # (B, nb, K, 6)
        ok = np.moveaxis(sol.reachable[:, :, br], 1, 2)  # (B, nb, K)
        unreach = 1.0 - ok.mean(axis=-1)  # (B, nb)
        q = _fill_unreachable(q, ok, robot.home)
        q = np.unwrap(q, axis=-2)
        q = _shift_into_limits(q, robot.q_min, robot.q_max)
        # time grid
        if prm.timing == "path":
            t: FloatArray = self.path.t
        else:
            dt_path = np.diff(self.path.t)
            dq = np.abs(np.diff(q, axis=-2)) / (prm.speed_fraction * robot.qd_max)
            dt = np.maximum(dt_path, dq.max(axis=-1))  # (B, nb, K-1)
            t = np.concatenate([np.zeros((B, nb, 1)), np.cumsum(dt, axis=-1)], axis=-1)
        qd = _gradient(q, t)
        qdd = _gradient(qd, t)
        tau = inverse_dynamics(robot, q, qd, qdd, friction=prm.friction)
        el = electrical_energy(qd, tau, t, robot, regenerative=prm.regenerative)
        P_total = np.sum(np.where(el.joints, el.power, 0.0), axis=-1)  # (B, nb, K) W
        energy = el.total  # (B, nb) J
        duration = t[..., -1] - t[..., 0] if np.ndim(t) > 1 else np.full((B, nb), t[-1] - t[0])
        w = manipulability_split(robot, q)[0]  # (B, nb, K)
        mean_w = w.mean(axis=-1)
        PC = prm.energy_weight
        J = PC * energy / (self.P_n * duration) + (1.0 - PC) * (1.0 - mean_w / self.w_max)
        # constraints (B, nb, 13)
        span = robot.q_max - robot.q_min
        excess = np.maximum(robot.q_min - q, q - robot.q_max).max(axis=-2) / span  # (B, nb, 6)
        pen = np.where(unreach > 0.0, 1.0 + _UNREACHABLE_SLOPE * unreach, 0.0)[..., None]
        g_pos = np.where(pen > 0.0, np.maximum(excess, 0.0) + pen, excess)
        g_vel = np.abs(qd).max(axis=-2) / robot.qd_max - 1.0
        g_pow = P_total.max(axis=-1) / self.P_n - 1.0
        G = np.concatenate([g_pos, g_vel, g_pow[..., None]], axis=-1)
        cv = np.maximum(G, 0.0).sum(axis=-1)
        extra = None
        if detail:
            extra = {
                "t": np.broadcast_to(t, (B, nb, K)),
                "q": q, "qd": qd, "qdd": qdd, "tau": tau, "power": el.power,
                "P_total": P_total, "w": w, "ok": ok, "current": el.current,
                "T": np.broadcast_to(T[:, None], (B, nb, K, 4, 4)),
            }
        return _Batch(J, G, cv, energy, mean_w, duration, P_total.max(axis=-1), unreach,
                      tuple(int(b) for b in br), extra)

    @staticmethod
    def _select(b: _Batch) -> NDArray[np.int64]:
        """Per candidate, the branch (index into the batch's branches) with the least total
        constraint violation, then the least J."""
        cv = np.round(b.cv, 12)
        J = b.J
        order = np.lexsort((J, cv), axis=-1)
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
            branch=BRANCH_NAMES[b.branches[i]],
            J=float(b.J[0, i]),
            G=b.G[0, i],
            cv=float(b.cv[0, i]),
            energy=float(b.energy[0, i]),
            mean_w=float(b.mean_w[0, i]),
            duration=float(b.duration[0, i]),
            peak_power=float(b.peak_power[0, i]),
            unreachable=float(b.unreachable[0, i]),
            branch_table=[
                {"branch": BRANCH_NAMES[bb], "J": float(b.J[0, j]), "cv": float(b.cv[0, j])}
                for j, bb in enumerate(b.branches)
            ],
        )
        return d

    def metrics_of(self, x: ArrayLike) -> dict[str, float]:
        """The scalar metrics of placement ``x`` (3,) (no comparison with the original): J, energy
        (J, kWh), mean manipulability (m³) and its ratio to w_M, time (s), mean and peak
        electrical power (W), the two terms of J, constraint violation, feasibility (1/0),
        fraction of unreachable points, R, γ, φ and the IK branch index."""
        return self._metrics(self._detail(x))

    def _metrics(self, d: dict[str, Any]) -> dict[str, float]:
        PC = self.params.energy_weight
        return {
            "J": d["J"],
            "energy_J": d["energy"],
            "energy_kWh": float(joules_to_kwh(d["energy"])),
            "mean_manipulability": d["mean_w"],
            "mean_manipulability_ratio": d["mean_w"] / self.w_max,
            "time_s": d["duration"],
            "mean_power_W": d["energy"] / d["duration"],
            "peak_power_W": d["peak_power"],
            "J_energy_term": PC * d["energy"] / (self.P_n * d["duration"]),
            "J_manipulability_term": (1.0 - PC) * (1.0 - d["mean_w"] / self.w_max),
            "constraint_violation": d["cv"],
            "feasible": float(d["cv"] <= 0.0),
            "unreachable_fraction": d["unreachable"],
            "R": float(d["x"][0]),
            "gamma": float(d["x"][1]),
            "phi": float(d["x"][2]),
            "branch_index": float(BRANCH_NAMES.index(d["branch"])),
        }

    def solution(self, x: FloatArray) -> Solution:
        x = np.asarray(x, dtype=float)
        if x.shape != (3,):
            raise ValueError(f"x: expected (R, γ, φ) of shape (3,), got {x.shape}")
        if not np.all(np.isfinite(x)):
            raise ValueError("x: must be finite")
        d = self._detail(x)
        metrics = self._metrics(d)
        ref = self._original_metrics()
        for key, name in (("energy_J", "energy"), ("mean_manipulability", "manipulability"),
                          ("time_s", "time")):
            metrics[f"{name}_change_pct"] = 100.0 * (metrics[key] - ref[key]) / ref[key]
        # the paper's "porcentaje de optimización" (Tables 2-3): energy and time saved relative
        # to the original, manipulability gained relative to the OPTIMISED value
        metrics["paper_energy_pct"] = 100.0 * (ref["energy_J"] - metrics["energy_J"]) / ref[
            "energy_J"]
        metrics["paper_time_pct"] = 100.0 * (ref["time_s"] - metrics["time_s"]) / ref["time_s"]
        metrics["paper_manipulability_pct"] = 100.0 * (
            metrics["mean_manipulability"] - ref["mean_manipulability"]
        ) / metrics["mean_manipulability"]
        motion = self._motion(d)
        names = [f"q{i}" for i in range(1, 7)]
        e_joint = integrate(np.where(np.isfinite(d["power"]), d["power"], 0.0), d["t"])
        electrical = self.robot.motors.electrical
        table: list[dict[str, Any]] = [
            {"metric": "q_min", "unit": "rad", "values": d["q"].min(axis=0).tolist()},
            {"metric": "q_max", "unit": "rad", "values": d["q"].max(axis=0).tolist()},
            {"metric": "|qd|_max", "unit": "rad/s", "values": np.abs(d["qd"]).max(axis=0).tolist()},
            {"metric": "qd_limit", "unit": "rad/s", "values": self.robot.qd_max.tolist()},
            {"metric": "|tau|_max", "unit": "N·m", "values": np.abs(d["tau"]).max(axis=0).tolist()},
            {"metric": "E_electrical", "unit": "J",
             "values": [float(e) if m else None for e, m in zip(e_joint, electrical, strict=True)]},
        ]
        extra = {
            "branch": d["branch"],
            "branches": d["branch_table"],
            "constraints": dict(zip(CONSTRAINT_NAMES, (float(g) for g in d["G"]), strict=True)),
            "path": self.path.name,
            "joint_names": names,
        }
        return Solution(x=x.copy(), objectives={"J": d["J"]}, metrics=metrics, table=table,
                        motion=motion, extra=extra)

    def _original_metrics(self) -> dict[str, float]:
        cached = getattr(self, "_orig_cache", None)
        if cached is None:
            cached = self.metrics_of(self.x_original)
            self._orig_cache = cached
        return cached

    def _motion(self, d: dict[str, Any]) -> Motion:
        power = np.where(np.isfinite(d["power"]), d["power"], 0.0)
        P_total = d["P_total"]
        t = d["t"]
        energy = np.concatenate([[0.0], np.cumsum(0.5 * (P_total[1:] + P_total[:-1]) * np.diff(t))])
        targets = d["T"][:, :3, 3]
        return Motion(
            t=t - t[0],
            q=d["q"],
            joint_names=tuple(f"q{i}" for i in range(1, 7)),
            qd=d["qd"],
            qdd=d["qdd"],
            jerk=_gradient(d["qdd"], t),
            tau=d["tau"],
            power=power,
            energy=energy,
            tool=targets,
            robot=self.robot.name,
            power_kind="electrical",
            scene={
                "targets": targets,
                "target_approach": d["T"][:, :3, 2],
                "original_path": self.path.p,
                "workspace_origin": self.workspace.origin,
                "manipulability": d["w"],
            },
        )

    def baseline_solutions(self) -> dict[str, Solution]:
        return {"original": self.solution(self.x_original)}

    def extras(self, front_X: FloatArray, front_F: FloatArray) -> dict[str, Any]:
        return {
            "workspace": self.workspace.as_dict(),
            "w_M": self.w_max,
            "P_n_W": self.P_n,
            "x_original": self.x_original.tolist(),
            "path": {"name": self.path.name, "points": self.path.n_points,
                     "duration_s": self.path.duration, "length_m": self.path.length},
            "paper": PAPER.get(self.path.name, {}),
        }


# ---------------------------------------------------------------------------------------------
# study descriptor and the initialisation comparison (Figure 8)
# ---------------------------------------------------------------------------------------------


def build(robot: Robot, params: Params) -> PathPlacementProblem:
    """The problem for ``robot`` (a PUMA-type arm) and validated ``params``."""
    if not isinstance(params, Params):
        params = Params.model_validate(params)
    return PathPlacementProblem(robot, params)


#: HKA settings of this study: seed 001 does not publish N, N_ξ, α, its survey step nor ϖ
#: (``penalty``); these converge in ~20 generations on both built-in paths (see the docs).
HKA_PARAMS: dict[str, Any] = {
    "n_samples": 30,
    "n_best": 6,
    "alpha": 0.6,
    "init": "survey",
    "survey_size": 216,
    "survey_best": 5,
    "penalty": 1e3,
    "spread_tol": 1e-4,
}

STUDY = Study(
    kind="path_placement",
    title="Seed 001: HKA placement of a tool path for electrical energy and manipulability",
    seed_paper="001",
    params=Params,
    default_robot="puma560",
    default_optimizer={"kind": "hka", "params": dict(HKA_PARAMS)},
    default_generations=30,
    build=build,
    robot_kinds=("serial",),
)


def compare_initialisations(
    params: Params | dict[str, Any] | None = None,
    *,
    robot: Robot | None = None,
    seeds: Iterable[int] = range(10),
    generations: int = STUDY.default_generations,
    center_generations: int | None = None,
    hka_params: dict[str, Any] | None = None,
    problem: PathPlacementProblem | None = None,
) -> dict[str, Any]:
    """Seed 001 Figure 8: HKA with its original initialisation (``init="center"``, eq 16)
    against the modified one (``init="survey"``) on the same problem, for each seed.

    Both run ``generations`` generations (the survey is the modified run's first generation,
    ``survey_size`` evaluations instead of ``n_samples``); ``center_generations`` gives the
    plain runs another budget (e.g. the same number of evaluations). ``hka_params`` default to
    the study's (:data:`HKA_PARAMS`); ``problem`` reuses a built problem.

    Returns ``{"rows": [...], "summary": {...}, "curves": {...}}``: one row per (seed, init)
    with J, energy (J), mean manipulability, feasibility, generations; per init the mean, std,
    min and max of J, energy and w_p, the feasible count and the number of seeds it won; and
    the per-generation best J of each run (the convergence curves).
    """
    from legcore.optimizers import MaxGenerations, get_algorithm, minimize

    if problem is None:
        if robot is None:
            from legcore.robots import catalog

            robot = catalog.get(STUDY.default_robot)  # type: ignore[assignment]
        prm = Params() if params is None else (
            params if isinstance(params, Params) else Params.model_validate(params))
        problem = build(robot, prm)  # type: ignore[arg-type]
    base = dict(HKA_PARAMS if hka_params is None else hka_params)
    pen = base.get("penalty")
    pen = 1e3 if pen is None else float(pen)  # to rank runs (Deb's rule has no weight)
    rows: list[dict[str, Any]] = []
    curves: dict[str, list[list[float]]] = {"center": [], "survey": []}
    seed_list: Sequence[int] = list(seeds)
    for seed in seed_list:
        for init in ("center", "survey"):
            algo = get_algorithm("hka", **{**base, "init": init})
            n_gen = generations if init == "survey" or center_generations is None \
                else center_generations
            res = minimize(problem, algo, MaxGenerations(n_gen), seed=int(seed))
            m = problem.metrics_of(res.x)
            rows.append({
                "seed": int(seed),
                "init": init,
                "J": float(res.F[0]),
                "cv": float(res.cv),
                "energy_J": m["energy_J"],
                "mean_manipulability": m["mean_manipulability"],
                "time_s": m["time_s"],
                "feasible": bool(res.cv <= 0.0),
                "n_gen": int(res.n_gen),
                "n_evals": int(res.n_evals),
                "x": [float(v) for v in res.x],
            })
            curves[init].append([float(r.best_f[0]) + pen * r.best_cv for r in res.history])
    summary: dict[str, Any] = {}
    for init in ("center", "survey"):
        sel = [r for r in rows if r["init"] == init]
        entry: dict[str, Any] = {"runs": len(sel), "feasible": sum(r["feasible"] for r in sel)}
        for key in ("J", "energy_J", "mean_manipulability"):
            v = np.array([r[key] for r in sel])
            entry[key] = {"mean": float(v.mean()), "std": float(v.std()),
                          "min": float(v.min()), "max": float(v.max())}
        summary[init] = entry
    wins = {"center": 0, "survey": 0, "tie": 0}
    for seed in seed_list:
        c = next(r for r in rows if r["seed"] == seed and r["init"] == "center")
        s = next(r for r in rows if r["seed"] == seed and r["init"] == "survey")
        cost_c = c["J"] + pen * c["cv"]
        cost_s = s["J"] + pen * s["cv"]
        if abs(cost_c - cost_s) <= 1e-9:
            wins["tie"] += 1
        else:
            wins["center" if cost_c < cost_s else "survey"] += 1
    summary["wins"] = wins
    return {"rows": rows, "summary": summary, "curves": curves, "generations": generations,
            "center_generations": center_generations or generations, "hka": base}
