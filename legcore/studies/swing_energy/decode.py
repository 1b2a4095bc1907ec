"""Decoding one ``swing_energy`` solution: the sampled trajectory, the seed's Table 2/3 metrics
and the scene (:func:`solution`), the least obstacle clearance and the
study-level facts a result reports (:func:`extras`). It reads the problem through
:class:`~legcore.studies.swing_energy.contract.SwingProblem`."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore.dynamics import inverse_dynamics
from legcore.joint_metrics import joint_metrics
from legcore.robots.model import Robot
from legcore.studies.study import Box, Motion, Solution
from legcore.studies.swing_energy.contract import SwingProblem
from legcore.studies.swing_energy.geometry import point_box_distance

__all__ = ["extras", "solution"]

FloatArray = NDArray[np.float64]


def solution(problem: SwingProblem, x: FloatArray, label: str | None = None) -> Solution:
    """The full decoded trajectory of ``x`` with the seed's Table 2/3 metrics.

    ``objectives``: {"score"}; ``metrics``: score, f_d, f_a, θ_T, D, E, ∫τ²dt, clearances
    (m; ``obstacle_clearance`` is the least distance of any link segment to the boxes, ≥
    their ``margin`` when feasible), constraint values, ``feasible`` (1/0), ``on_grid`` (1 when
    every value is a multiple of the resolution), and ``criterion`` (this problem's F).
    """
    x = np.asarray(x, dtype=float)
    if x.shape != (problem.n_var,):
        raise ValueError(f"x: expected shape ({problem.n_var},), got {x.shape}")
    q, qd, qdd, jerk = (a[0] for a in problem.trajectories(x[None]))
    tau = inverse_dynamics(problem.robot, q, qd, qdd)
    P = problem.chain_points(q)  # (K, M, 3)
    foot = P[:, -1]
    jm = joint_metrics(problem.t, q, tau, qd=qd, qdd=qdd, jerk=jerk, tool_pos=foot)
    f_d, f_a = (float(v[0]) for v in problem.score_parts(q[None], qdd[None]))
    score = problem.params.w1 * f_d + problem.params.w2 * f_a
    F, G = problem.evaluate(x[None])
    power = tau * qd
    absp = np.abs(power).sum(axis=1)
    energy = np.concatenate([[0.0], np.cumsum(0.5 * (absp[1:] + absp[:-1]) * np.diff(problem.t))])
    genes = problem.genes(x)
    if label is None:
        label = ("Calderón 2015 (proposed): w1 f_d + w2 f_a" if problem.criterion == "score"
                 else f"GA minimising {problem.criterion}")
    metrics: dict[str, float] = {
        "score": score,
        "f_d": f_d,
        "f_a": f_a,
        "theta_total": float(jm.theta_total),
        "path_length": float(jm.path_length),
        "energy_total": float(jm.energy_total),
        "tau_sq_total": float(jm.tau_sq_total),
        "duration": float(jm.duration),
        "criterion": float(F[0, 0]),
        "ground_clearance": float(P[:, 1:, 2].min() - problem.z_ground),
        "on_grid": float(np.allclose(genes.ravel() * problem.res, x, rtol=0.0, atol=1e-9)),
        "lift_height": float(P[:, -1, 2].max() - problem.z_ground),
    }
    for name, g in zip(problem.constraint_names, G[0], strict=True):
        metrics[f"g_{name}"] = float(g)
    metrics["feasible"] = float(np.all(G <= 0.0))
    scene: dict[str, Any] = {
        "targets": np.stack([problem.foot_start, problem.foot_end]),
        "ground_z": problem.z_ground,
    }
    if problem.boxes:
        metrics["obstacle_clearance"] = _clearance(problem, P)
        scene["obstacles"] = list(problem.boxes)
        scene["obstacle_margin"] = problem.margin
    motion = Motion(
        t=problem.t.copy(), q=q, qd=qd, qdd=qdd, jerk=jerk, tau=tau, power=power, energy=energy,
        tool=foot, joint_names=_joint_names(problem.robot), robot=problem.label, scene=scene,
    )
    if problem.hip is not None:  # one leg of a legged robot: draw it on the body, at its hip
        motion = _on_body(motion, problem.hip, problem.robot_name, str(problem.params.leg))
    table = [
        {"metric": r.label, "key": r.key, "unit": r.unit,
         **({"values": list(r.per_joint)} if r.per_joint is not None else {"total": r.total})}
        for r in jm.as_table()
    ]
    extra = {
        "label": label,
        "criterion": problem.criterion,
        "encoding": problem.params.encoding,
        "genes": genes.tolist(),
        "via_steps": problem.via_steps(x[None])[0].tolist(),
        "via_points": (problem.via_steps(x[None])[0] * problem.res).tolist(),
        "start_steps": problem.start_steps.tolist(),
        "end_steps": problem.end_steps.tolist(),
        "q_start": problem.q_start.tolist(),
        "q_end": problem.q_end.tolist(),
        "resolution": problem.res,
    }
    return Solution(x=x.copy(), objectives={"score": score}, metrics=metrics, table=table,
                    motion=motion, extra=extra)

def _clearance(problem: SwingProblem, P: FloatArray, per_segment: int = 60) -> float:
    """Least distance (m) of the sampled link segments P (K, M, 3) to the boxes (no
    margin)."""
    lam = np.linspace(0.0, 1.0, per_segment)[:, None]
    a, b = P[:, :-1, None, :], P[:, 1:, None, :]
    pts = a + lam * (b - a)  # (K, M - 1, per_segment, 3)
    return min(float(point_box_distance(pts, box.center, box.half_size).min())
               for box in problem.boxes)


def extras(problem: SwingProblem, front_X: FloatArray) -> dict[str, Any]:
    """Study-level facts: start/end, AcC, the obstacle, and the energy comparison."""
    best_E = None
    if front_X.shape[0]:
        q, qd, qdd = problem.trajectories(front_X[:1], (0, 1, 2))
        best_E = float(problem.energy(q, qd, qdd)[0])
    base = problem.baseline_solutions()
    energies = {k: v.metrics["energy_total"] for k, v in base.items()}
    out: dict[str, Any] = {
        "q_start": problem.q_start.tolist(),
        "q_end": problem.q_end.tolist(),
        "foot_start": problem.foot_start.tolist(),
        "foot_end": problem.foot_end.tolist(),
        "z_ground": problem.z_ground,
        "acc_coordinated": problem.acc_coordinated.tolist(),
        "theta_min": problem.theta_min.tolist(),
        "obstacle": None if problem.box is None else {
            "center": list(problem.box.center), "half_size": list(problem.box.half_size),
            "margin": problem.margin},
        "obstacles": [{"center": list(b.center), "half_size": list(b.half_size),
                       "margin": m} for b, m in zip(problem.boxes, problem.margins, strict=True)],
        "leg": problem.label,
        "tube": problem.tube,
        "energy_best": best_E,
        "energy_baselines": energies,
    }
    if best_E is not None:
        out["energy_saving_vs_baselines"] = {
            k: (1.0 - best_E / e) if e > 0 else None for k, e in energies.items()}
    return out



def _on_body(motion: Motion, hip: FloatArray, robot: str, leg: str) -> Motion:
    """``motion`` of one leg moved from its hip frame to the body frame (hip with the body's
    axes: a translation), named after the whole robot and that leg (for drawing it)."""
    d = hip[:3, 3]
    scene = dict(motion.scene)
    scene["targets"] = np.asarray(scene["targets"]) + d
    scene["ground_z"] = float(scene["ground_z"] + d[2])
    if "obstacles" in scene:
        scene["obstacles"] = [
            Box(center=(b.center[0] + d[0], b.center[1] + d[1], b.center[2] + d[2]),
                half_size=b.half_size) for b in scene["obstacles"]]
    scene["frame"] = f"body frame of {robot} (leg {leg}: its hip at {d.round(4).tolist()} m)"
    return dataclasses.replace(motion, tool=None if motion.tool is None else motion.tool + d,
                               robot=robot, legs=(leg,), scene=scene)


def _joint_names(robot: Robot) -> tuple[str, ...]:
    names = [robot.model.names[i] for i in range(1, robot.model.njoints)]
    return tuple(names) if len(names) == robot.nq else tuple(f"q{i + 1}" for i in range(robot.nq))
