"""Decoding of one ``path_tracking`` time law into a :class:`~legcore.studies.study.Solution`:
the full motion (t, q, q̇, q̈, q⃛, τ, power, cumulative energy, the tool path by FK), the metrics
(cycle time, energies — absolute, with a shared supply, net —, limit use, segment times, what
the decision vector says in its own terms), the per-joint table and the extras (constraint
values, energy per joint, path and orientation errors, the law's form)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore import kinematics
from legcore.joint_metrics import joint_metrics
from legcore.problems.base import constraint_violation
from legcore.studies.path_tracking.contract import TrackingProblem
from legcore.studies.path_tracking.timelaw import RampShape, TimeLaw, segment_profiles
from legcore.studies.study import Motion, Solution

__all__ = ["decode_law"]

FloatArray = NDArray[np.float64]


def _cumulative_trapezoid(y: FloatArray, t: FloatArray) -> FloatArray:
    """∫_0^t y dt (K,) by the trapezoid rule on samples ``y`` (K,) at times ``t`` (K,)."""
    return np.concatenate([[0.0], np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(t))])


def decode_law(problem: TrackingProblem, law: TimeLaw, x: FloatArray | None = None,
               encoded: dict[str, float] | None = None, shape: RampShape | None = None
               ) -> Solution:
    """The Solution of one time ``law`` (B = 1) of ``problem``: of the decision vector ``x``
    when it has one in the problem's encoding (else None: a baseline of another form),
    ``encoded`` what its own parameters say (t_a, V_k, …: put into the metrics)."""
    encoded = encoded or {}
    sim = problem.simulate(law)
    t = sim["t"][0]
    q, qd, qdd, jerk, tau = (sim[k][0] for k in ("q", "qd", "qdd", "jerk", "tau"))
    T_tool = kinematics.fk(problem.robot, q)
    tool = T_tool[:, :3, 3]
    power = tau * qd
    energy = _cumulative_trapezoid(np.abs(power).sum(axis=1), t)
    G = sim["G"][0]
    if problem.limit_check > 1:
        G = problem.dense_limits(law, sim["G"], problem.limit_check)[0]
    cv = float(constraint_violation(G[None, :])[0])
    seg_T = law.segment_times()[0]
    jm = joint_metrics(t, q, tau, qd=qd, qdd=qdd, jerk=jerk, tool_pos=tool)
    table: list[dict[str, Any]] = [
        {"metric": row.label, "key": row.key, "unit": row.unit, "values": list(row.per_joint)}
        for row in jm.as_table() if row.per_joint is not None
    ]
    table += [
        {"metric": "q_min", "key": "q_min", "unit": "rad", "values": q.min(axis=0).tolist()},
        {"metric": "q_max", "key": "q_max", "unit": "rad", "values": q.max(axis=0).tolist()},
        {"metric": "ω_max/ω_lim", "key": "qd_use", "unit": "1",
         "values": (jm.omega_max / problem.robot.qd_max).tolist()},
        {"metric": "α_max/α_lim", "key": "qdd_use", "unit": "1",
         "values": (np.abs(qdd).max(axis=0) / problem.qdd_max).tolist()},
        {"metric": "τ_max/τ_lim", "key": "tau_use", "unit": "1",
         "values": (jm.tau_max / problem.robot.tau_max).tolist()},
    ]
    T, E = float(sim["T"][0]), float(sim["E"][0])
    P = power.sum(axis=1)  # W: the joints' mechanical powers summed
    metrics: dict[str, float] = {
        "time": T,
        "energy": E,
        # one supply shared by the joints (a DC bus): what it gives, none taken back
        "energy_shared": float(_cumulative_trapezoid(np.maximum(P, 0.0), t)[-1]),
        # net work ∫ Σ τ q̇ dt: the change of the arm's mechanical energy (0 J rest to rest
        # on a closed path; what perfect regeneration would cost)
        "energy_net": float(_cumulative_trapezoid(P, t)[-1]),
        "feasible": float(cv <= 0.0),
        "cv": cv,
        "path_length": float(jm.path_length),
        "theta_total": float(jm.theta_total),
        "tool_speed_max": float(np.linalg.norm(sim["pd"][0], axis=1).max()),
        "qd_use_max": float(np.max(jm.omega_max / problem.robot.qd_max)),
        "qdd_use_max": float(np.max(np.abs(qdd).max(axis=0) / problem.qdd_max)),
        "tau_use_max": float(np.max(jm.tau_max / problem.robot.tau_max)),
        "ramp_shrink": float(law.shrink[0]),
        **encoded,
    }
    for k in range(problem.n_seg):
        metrics[f"T_{k + 1}"] = float(seg_T[k])
    e_path, e_rot = problem.tool.errors(T_tool, sim["p"][0])
    motion = Motion(
        t=t,
        q=q,
        joint_names=tuple(problem.robot.model.names[1:]),
        qd=qd,
        qdd=qdd,
        jerk=jerk,
        tau=tau,
        power=power,
        energy=energy,
        tool=tool,
        robot=problem.robot.name,
        scene={"path": problem.path.polyline(), "targets": problem.path.joins},
    )
    extra = {
        "variable_names": list(problem.variable_names),
        "segment_times": seg_T.tolist(),
        "orientation": problem.tool.describe(),
        "rest": problem.rest.tolist(),
        "qdd_max": problem.qdd_max.tolist(),
        "constraints": dict(zip(problem.constraint_names, G.tolist(), strict=True)),
        "energy_per_joint": sim["E_joint"][0].tolist(),
        "orientation_error": float(e_rot.max()),
        "path_error": float(e_path.max()),
    }
    if "V_1" in encoded:  # a trapezoid law: its cruise speeds and ramp shape
        V = [encoded[f"V_{k + 1}"] for k in range(problem.n_seg)]
        extra |= {"segment_speeds": V, "segment_profiles": segment_profiles(np.array(V)),
                  "ramp": shape or problem.params.ramp}
    else:
        extra |= {"ramp": "profile", "knots": law.sigma_start[0].tolist() + [
            float(problem.path.lengths.sum())]}
    objectives = {name: metrics[name] for name in problem.objective_names}
    return Solution(x=None if x is None else np.array(x, dtype=float), objectives=objectives,
                    metrics=metrics, table=table, motion=motion, extra=extra)
