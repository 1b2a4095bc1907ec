"""Decoding of a ``path_placement`` solution: metrics, per-joint table, Motion (pure numpy)."""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from legcore.energy import integrate, joules_to_kwh
from legcore.robots.model import Robot
from legcore.studies.path_placement.joints import gradient
from legcore.studies.path_placement.params import Params
from legcore.studies.path_placement.paths import ToolPath
from legcore.studies.path_placement.region import Region
from legcore.studies.study import Motion, Solution
from legcore.studies.task import Violation


class PathPlacementProblem(Protocol):
    """What the decoding reads of the study's problem
    (:class:`legcore.studies.path_placement.problem.PathPlacementProblem`, which imports this
    module: a protocol, not an import, so the two are no circle)."""

    robot: Robot
    params: Params
    path: ToolPath
    closed_form: bool
    energy_kind: str
    workspace: Region
    w_max: float
    P_n: float
    torque: bool
    constraint_names: tuple[str, ...]

__all__ = ["metrics", "motion", "solution", "violations"]

FloatArray = NDArray[np.float64]


def metrics(problem: PathPlacementProblem, d: dict[str, Any]) -> dict[str, float]:
    """The scalar metrics of one placement's detail ``d``: J, energy (J, kWh), mean
    manipulability (m³) and its ratio to w_M, time (s), mean and peak power (W), the two terms of
    J, constraint violation, feasibility (1/0), fraction of unreachable points, the placement
    (R, γ, φ or x, y, z) and the IK branch index."""
    PC = problem.params.energy_weight
    out = {
        "J": d["J"],
        "energy_J": d["energy"],
        "energy_kWh": float(joules_to_kwh(d["energy"])),
        "mean_manipulability": d["mean_w"],
        "mean_manipulability_ratio": d["mean_w"] / problem.w_max,
        "time_s": d["duration"],
        "mean_power_W": d["energy"] / d["duration"],
        "peak_power_W": d["peak_power"],
        "J_energy_term": PC * d["energy"] / (problem.P_n * d["duration"]),
        "J_manipulability_term": (1.0 - PC) * (1.0 - d["mean_w"] / problem.w_max),
        "constraint_violation": d["cv"],
        "feasible": float(d["cv"] <= 0.0),
        "unreachable_fraction": d["unreachable"],
    }
    for name, v in zip(problem.workspace.variable_names, d["x"], strict=True):
        out[name] = float(v)
    out["branch_index"] = float(d["branch_index"])
    return out


def violations(problem: PathPlacementProblem, d: dict[str, Any]) -> tuple[Violation, ...]:
    """What the placement of detail ``d`` breaks (``PathPlacementProblem.violations``)."""
    r = problem.robot
    names = [str(v) for v in list(r.model.names)[1:]]
    out: list[Violation] = []
    ok = np.asarray(d["ok"], dtype=bool)
    K, bad = ok.size, int((~ok).sum())
    if bad:
        out.append(Violation(
            "unreachable", 100.0 * bad / K, "%",
            f"{100.0 * bad / K:.3g} % of the path ({bad} of {K} points) out of reach of "
            f"{r.name} at this placement (with the path's tool orientations, inside the joint "
            f"limits)"))
    q = d["q"]
    over = np.maximum(r.q_min - q, q - r.q_max).max(axis=0)
    for j in (int(i) for i in np.flatnonzero(over > 0.0)):
        out.append(Violation(
            f"q{j + 1}_limit", float(over[j]), "rad",
            f"joint {names[j]}: {over[j]:.3g} rad beyond its limits [{r.q_min[j]:.4g}, "
            f"{r.q_max[j]:.4g}] rad"))
    peaks = [("qd", "speed", np.abs(d["qd"]).max(axis=0), r.qd_max, "rad/s")]
    if problem.torque:
        peaks.append(("tau", "torque", np.abs(d["tau"]).max(axis=0), r.tau_max, "N·m"))
    for key, what, peak, lim, unit in peaks:
        for j in (int(i) for i in np.flatnonzero(peak > lim)):
            out.append(Violation(
                f"{key}{j + 1}_limit", float(peak[j] - lim[j]), unit,
                f"joint {names[j]}: peak {what} {peak[j]:.4g} {unit}, "
                f"{100.0 * (peak[j] / lim[j] - 1.0):.3g} % over its limit {lim[j]:.4g} {unit}"))
    if d["peak_power"] > problem.P_n:
        out.append(Violation(
            "nominal_power", float(d["peak_power"] - problem.P_n), "W",
            f"peak power {d['peak_power']:.4g} W, {100.0 * (d['peak_power'] / problem.P_n - 1):.3g}"
            f" % over the nominal power P_n = {problem.P_n:.4g} W"))
    return tuple(out)


def solution(
    problem: PathPlacementProblem, x: FloatArray, d: dict[str, Any], ref: dict[str, float],
    ref_broken: tuple[Violation, ...] = (),
) -> Solution:
    """The decoded :class:`Solution` of placement ``x`` with detail ``d``; ``ref``: the
    original placement's metrics, ``ref_broken`` what it violates (then no % change: NaN,
    and ``extra.change_pct_reason`` says why)."""
    out = metrics(problem, d)
    def pct(num: float, den: float) -> float | None:
        if ref_broken:
            return math.nan
        return 100.0 * num / den if den != 0.0 and math.isfinite(num / den) else None

    # the % changes (left out where the reference is 0, e.g. an original out of reach); the
    # paper's "porcentaje de optimización" (Tables 2-3): energy and time saved relative to the
    # original, manipulability gained relative to the OPTIMISED value
    changes = {
        "energy_change_pct": pct(out["energy_J"] - ref["energy_J"], ref["energy_J"]),
        "manipulability_change_pct": pct(out["mean_manipulability"] - ref["mean_manipulability"],
                                         ref["mean_manipulability"]),
        "time_change_pct": pct(out["time_s"] - ref["time_s"], ref["time_s"]),
        "paper_energy_pct": pct(ref["energy_J"] - out["energy_J"], ref["energy_J"]),
        "paper_time_pct": pct(ref["time_s"] - out["time_s"], ref["time_s"]),
        "paper_manipulability_pct": pct(out["mean_manipulability"] - ref["mean_manipulability"],
                                        out["mean_manipulability"]),
    }
    out |= {k: v for k, v in changes.items() if v is not None}
    mo = motion(problem, d)
    n = problem.robot.nq
    e_joint = integrate(np.where(np.isfinite(d["power"]), d["power"], 0.0), d["t"])
    counted = (problem.robot.motors.electrical if problem.energy_kind == "electrical"
               else np.ones(n, dtype=bool))
    table: list[dict[str, Any]] = [
        {"metric": "q_min", "unit": "rad", "values": d["q"].min(axis=0).tolist()},
        {"metric": "q_max", "unit": "rad", "values": d["q"].max(axis=0).tolist()},
        {"metric": "|qd|_max", "unit": "rad/s", "values": np.abs(d["qd"]).max(axis=0).tolist()},
        {"metric": "qd_limit", "unit": "rad/s", "values": problem.robot.qd_max.tolist()},
        {"metric": "|tau|_max", "unit": "N·m", "values": np.abs(d["tau"]).max(axis=0).tolist()},
        {"metric": f"E_{problem.energy_kind}", "unit": "J",
         "values": [float(e) if m else None for e, m in zip(e_joint, counted, strict=True)]},
    ]
    extra = {
        "branch": d["branch"],
        "branches": d["branch_table"],
        "constraints": dict(zip(problem.constraint_names, (float(g) for g in d["G"]),
                                strict=True)),
        "path": problem.path.name,
        "joint_names": [f"q{i}" for i in range(1, n + 1)],
        "energy_kind": problem.energy_kind,
        "ik": "closed form (PUMA-type)" if problem.closed_form else "numerical",
        "region": problem.workspace.as_dict(),
    }
    if ref_broken:
        extra["change_pct_reason"] = (
            "no % change: the reference (the original placement) is infeasible on "
            f"{problem.robot.name}: " + "; ".join(v.text or v.constraint for v in ref_broken))
    return Solution(x=x.copy(), objectives={"J": d["J"]}, metrics=out, table=table,
                    motion=mo, extra=extra)


def motion(problem: PathPlacementProblem, d: dict[str, Any]) -> Motion:
    """The time series of one placement's detail ``d``."""
    power = np.where(np.isfinite(d["power"]), d["power"], 0.0)
    P_total = d["P_total"]
    t = d["t"]
    energy = np.concatenate([[0.0], np.cumsum(0.5 * (P_total[1:] + P_total[:-1]) * np.diff(t))])
    targets = d["T"][:, :3, 3]
    return Motion(
        t=t - t[0],
        q=d["q"],
        joint_names=tuple(f"q{i}" for i in range(1, problem.robot.nq + 1)),
        qd=d["qd"],
        qdd=d["qdd"],
        jerk=gradient(d["qdd"], t),
        tau=d["tau"],
        power=power,
        energy=energy,
        tool=targets,
        robot=problem.robot.name,
        power_kind=problem.energy_kind,
        scene={
            "targets": targets,
            "target_approach": d["T"][:, :3, 2],
            "original_path": problem.path.p,
            "workspace_origin": problem.workspace.centre(),
            "manipulability": d["w"],
        },
    )

