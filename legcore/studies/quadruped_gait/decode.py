"""Decoding one step of the ``quadruped_gait`` walk: the cycle's motion on the walking body (world
frame: x along the walk), the energy, margin and load metrics, the per-joint table of seed
000's metrics, the gait, servo and Table 2 layouts. It reads the problem through
:class:`~legcore.studies.quadruped_gait.contract.GaitProblem`."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore.energy import integrate
from legcore.joint_metrics import joint_metrics
from legcore.studies.quadruped_gait.contract import GaitProblem
from legcore.studies.study import Motion, Solution
from legcore.support_polygon import support_polygon

__all__ = ["solution"]

FloatArray = NDArray[np.float64]


def solution(problem: GaitProblem, x: FloatArray) -> Solution:
    """One step ``x`` (3,) of ``problem`` decoded (see
    :meth:`~legcore.studies.quadruped_gait.problem.QuadrupedGaitProblem.solution`)."""
    x = np.asarray(x, dtype=float).reshape(-1)
    if x.shape != (3,) or not np.all(np.isfinite(x)):
        raise ValueError(
            f"x: expected 3 finite numbers (step_length, step_height, duty), got {x}"
        )
    r = problem.simulate(x[None, :], detail=True)
    F, G = problem.objective_constraints(r)
    d = {k: (v[0] if isinstance(v, np.ndarray) and v.ndim >= 1 else v) for k, v in r.items()}
    t, q, qd, qdd, tau = d["t"], d["q"], d["qd"], d["qdd"], d["tau"]
    p = problem.params
    power = tau * qd
    absp = np.maximum(power, 0.0) if p.energy_model == "positive_work" else np.abs(power)
    cum = np.concatenate(([0.0], np.cumsum(0.5 * (absp[1:] + absp[:-1]).sum(-1) * np.diff(t))))
    x_body = problem.speed * t  # body displacement (m) along world x
    body_h = problem.depth - float(np.mean([leg.hip[2, 3] for leg in problem.legs]))
    body = np.stack((x_body, np.zeros_like(t), np.full_like(t, body_h)), -1)
    feet_w = d["feet"] + body[:, None, :]
    com_w = d["com"] + body
    tool_leg = problem.roles.index("FR")
    # seed 000 metrics per joint; D = the FR foot's path relative to the body over a cycle
    jerk = _periodic_jerk(t, qdd)
    jm = joint_metrics(t, q, tau, qd=qd, qdd=qdd, jerk=jerk, tool_pos=d["feet"][:, tool_leg])
    reachable = bool(np.all(d["reachable"]))
    feasible = bool(np.all(G <= 0.0))
    E, D = float(d["E"]), float(d["D"])
    E_joint = d["E_joint"]
    n_j = list(problem.n_joints)
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
        "speed_m_s": problem.speed,
        "step_length_m": float(x[0]),
        "step_height_m": float(x[1]),
        "duty": float(x[2]),
        "min_stability_margin_m": float(d["margin"]),
        # no foot on the ground at some sample: the margin is -inf, stored as null + this flag
        "airborne": float(not np.isfinite(d["margin"])),
        "required_stability_margin_m": problem.required_margin,
        "max_joint_speed_ratio": float(d["qd_ratio"]),
        "max_torque_ratio": float(d["tau_ratio"]),
        "max_torque_Nm": float(np.max(np.abs(tau))),
        "max_joint_speed_rad_s": float(np.max(np.abs(qd))),
        "max_foot_load_N": float(np.max(d["loads"])),
        "min_foot_load_N": float(np.min(d["loads"])),
        "reachable": float(reachable),
        "feasible": float(feasible),
    }
    for j, name in enumerate(problem.leg_names):
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
        "foot_names": problem.leg_names,
        "support": sup,
        "support_polygon": np.concatenate((polys, np.zeros(polys.shape[:-1] + (1,))), -1),
        "support_polygon_n": n_poly,
        "com": com_w,
        "com_ground": com_w * np.array([1.0, 1.0, 0.0]),
        "body_position": body,
        "body_size": problem.robot.body_size,
        "stability_margin": d["margin_t"],
        "foot_loads_N": d["loads"],
    }
    motion = Motion(
        t=t,
        q=q,
        joint_names=problem.joint_names,
        qd=qd,
        qdd=qdd,
        jerk=jerk,
        tau=tau,
        power=power,
        energy=cum,
        tool=feet_w[:, tool_leg],
        robot=problem.robot.name,
        legs=problem.leg_names,
        scene=scene,
    )
    extra = {
        "objective": p.objective,
        "constraints": dict(zip(problem.constraint_names, (float(g) for g in G[0]), strict=True)),
        "gait": {
            "name": problem.gait.name,
            "legs": list(problem.gait.legs),
            "offsets": list(problem.gait.offsets),
            "duty": float(x[2]),
            "lift_off_order": [
                n for _, n in sorted(zip(problem.gait.offsets, problem.gait.legs, strict=True))
            ],
            "source": problem.gait.source,
        },
        "table_columns": list(problem.joint_names),
        "servo_table": problem.servo_table(t, q),
        "table2": problem.table2(float(x[0])),
        "ik": {g.name: ("closed form leg2" if g.closed_form and not problem.numeric
                        else "numerical (legcore.ik.solve)") for g in problem.gait_legs},
    }
    return Solution(
        x=x.copy(),
        objectives={p.objective: float(F[0, 0])},
        metrics=metrics,
        table=table,
        motion=motion,
        extra=extra,
    )


def _periodic_jerk(t: FloatArray, qdd: FloatArray) -> FloatArray:
    """Jerk (K, n) rad/s³ by differentiating ``qdd`` on the closed cycle grid (periodic central
    differences; the cycle is C², so the jerk is piecewise continuous)."""
    dt = t[1] - t[0]
    core = qdd[:-1]
    j = (np.roll(core, -1, axis=0) - np.roll(core, 1, axis=0)) / (2.0 * dt)
    return np.concatenate((j, j[:1]), 0)
