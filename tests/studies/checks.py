"""Physical checks of decoded solutions, shared by the study × robot matrix (a short
``legcore.run``: tests/studies/test_arm_matrix.py, test_legged_matrix.py) and the runs through
the real service (tests/studies/test_service_studies.py and the arm matrix's service test),
where the solution is the *stored* result's decision vector decoded again
(:func:`stored_solution`) — so the same checks hold for what the service kept, not just "it ran".

The checks do not use legcore's kinematics or dynamics: positions by Pinocchio FK
(:func:`tests.studies.physics.tool_positions`), torques and power by Pinocchio's RNEA.

The energy bound (:func:`check_energy`). A study reports its mechanical energy as
``E = Σ_k (f_k + f_{k+1}) Δt_k / 2`` with ``f = Σ_i |τ_i q̇_i|`` (``legcore.energy``: the
trapezoid on the samples). With no external force doing work, ``P = Σ_i τ_i q̇_i = q̇ᵀ·RNEA(q,
q̇, q̈)``, which is ``dE_mech/dt`` (kinetic + potential energy of the chain) for a consistent
motion (q̈ the derivative of q̇). Per sample ``f ≥ |P|``, and
the trapezoid's weights are positive, so per interval ``(f_k + f_{k+1}) Δt_k / 2 ≥ |S_k|`` with
``S_k = (P_k + P_{k+1}) Δt_k / 2`` — hence, exactly, ``E ≥ B = Σ_k |S_k|``: the gravity (and
inertia) bound of the motion, integrated by the study's own quadrature. The check allows only
rounding (1e-9 relative); the study's power equals ``q̇ᵀ·RNEA`` to 1e-9 (asserted; measured
~1e-15), and so do its torques where no contact force acts (a stance leg's carry the ground
reaction, vertical on a foot moving horizontally: no work, the power is unchanged).

The matrix tests used to compare ``E`` with ``0.98 ×`` the sampled total variation
``Σ_k |E_mech(t_{k+1}) − E_mech(t_k)|`` (:func:`tests.studies.physics.energy_variation`). That is
the same integral ``∫|dE_mech/dt| dt`` by another quadrature, and the two differ by the
trapezoid's error, O(Δt²): on these grids (33 samples a gait cycle, 51 a swing)
``Σ_k |S_k − ΔE_mech,k|`` is up to 31 % of the variation (ANYmal's gait; 6.5 %, 1.7 %, 0.44 % at
64, 128, 256 samples a cycle: the quadrature error, not a modelling one), so no fixed
margin such as 2 % could be justified; it passed only because ``E`` is well above the variation
(≥ 1.04 ×). With the same quadrature no margin is needed.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin

from legcore.kinematics import fk
from legcore.robots import LeggedRobot, Robot
from legcore.studies.study import Solution
from tests.studies.physics import tool_positions

#: Position tolerance of the physical checks (issue 9: "to 1e-6 m").
POS_TOL = 1e-6
#: Rounding allowance of the exact energy inequality ``E ≥ B`` (relative).
ENERGY_RTOL = 1e-9


def rnea_torques(robot: Robot, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """(K, n) N·m: Pinocchio's inverse dynamics of the chain at each sample."""
    model, data = robot.model, robot.data()
    return np.array([pin.rnea(model, data, q[k], qd[k], qdd[k]) for k in range(q.shape[0])])


def power_bound(t: np.ndarray, P: np.ndarray) -> float:
    """``B = Σ_k |S_k|``, ``S_k`` the trapezoid of the power ``P`` (K,) W over interval k (J)."""
    return float(np.abs(0.5 * (P[1:] + P[:-1]) * np.diff(t)).sum())


def check_energy(robot: Robot, t: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                 tau: np.ndarray, energy: float, *, contact: bool = False) -> float:
    """The study's joint power ``Σ_i τ_i q̇_i`` is the rate of the chain's mechanical energy
    (``q̇ᵀ·RNEA``, Pinocchio) — for a free chain its torques are RNEA's; with ``contact`` (a
    stance leg) they also carry the ground reaction, which does no work — and its mechanical
    energy is at least the motion's gravity/inertia bound ``B`` (module doc); returns ``B``."""
    ref = rnea_torques(robot, q, qd, qdd)
    if not contact:
        np.testing.assert_allclose(tau, ref, rtol=0, atol=1e-9 * max(1.0, np.abs(ref).max()))
    P = np.einsum("ki,ki->k", ref, qd)
    np.testing.assert_allclose(np.einsum("ki,ki->k", tau, qd), P, rtol=0,
                               atol=1e-9 * max(1.0, np.abs(P).max()))
    bound = power_bound(t, P)
    assert bound > 0.0
    assert energy >= bound * (1.0 - ENERGY_RTOL), (energy, bound)
    return bound


def check_limits(robot: Robot, mo: Any, qdd_max: np.ndarray | None = None) -> None:
    """Joint positions, speeds, torques (and accelerations) inside the robot's limits."""
    assert robot.within_limits(mo.q, tol=1e-9).all()
    assert np.all(np.abs(mo.qd) <= robot.qd_max * (1 + 1e-9))
    assert np.all(np.abs(mo.tau) <= robot.tau_max * (1 + 1e-9))
    if qdd_max is not None:
        assert np.all(np.abs(mo.qdd) <= qdd_max * (1 + 1e-9))


def _motion(sol: Solution) -> Any:
    mo = sol.motion
    assert mo is not None and mo.qd is not None and mo.qdd is not None and mo.tau is not None
    return mo


def check_tracking(problem: Any, sol: Solution, law: Any = None) -> None:
    """``path_tracking``: the tool on the path at σ(t) and its orientation kept (1e-6), every
    limit held, q̇ the derivative of q, energy ≥ the bound (``law``: the time law of a
    solution without a decision vector, e.g. the physical minimum)."""
    robot, mo = problem.robot, _motion(sol)
    assert sol.metrics["feasible"] == 1.0
    if law is None:
        law = problem.time_law(np.asarray(sol.x)[None, :])
    sigma = law.evaluate(mo.t[None, :])[0, 0]
    path = problem.path.derivatives(sigma)[0]
    assert np.abs(tool_positions(robot, mo.q) - path).max() < POS_TOL  # on the path
    assert problem.tool.errors(fk(robot, mo.q), path)[1].max() < POS_TOL  # orientation kept
    check_limits(robot, mo, problem.qdd_max)
    np.testing.assert_allclose(np.gradient(mo.q, mo.t, axis=0)[1:-1], mo.qd[1:-1],
                               atol=0.02 * np.abs(mo.qd).max() + 1e-9)
    check_energy(robot, mo.t, mo.q, mo.qd, mo.qdd, mo.tau, sol.metrics["energy"])


def check_placement(problem: Any, sol: Solution) -> None:
    """``path_placement``: every placed target reached by the tool, position and orientation
    (1e-6), limits held, mechanical energy ≥ the bound."""
    robot, mo = problem.robot, _motion(sol)
    assert sol.metrics["feasible"] == 1.0 and sol.metrics["unreachable_fraction"] == 0.0
    assert sol.extra["energy_kind"] == "mechanical" and mo.power_kind == "mechanical"
    placed = problem.placed_poses(sol.x)[0]
    assert np.abs(tool_positions(robot, mo.q) - placed[:, :3, 3]).max() < POS_TOL
    assert np.abs(fk(robot, mo.q)[:, :3, :3] - placed[:, :3, :3]).max() < POS_TOL
    check_limits(robot, mo)
    check_energy(robot, mo.t, mo.q, mo.qd, mo.qdd, mo.tau, sol.metrics["energy_J"])
    assert 0.0 < sol.metrics["mean_manipulability_ratio"] <= 1.0 + 1e-9


def swing_chain(robot: Robot | LeggedRobot, leg: str | None) -> Robot:
    """The serial chain a ``swing_energy`` run swings: the robot, or its leg ``leg``."""
    if isinstance(robot, LeggedRobot):
        assert leg is not None, "a legged robot swings one named leg"
        return robot.leg(leg).robot
    return robot


def check_swing(robot: Robot | LeggedRobot, leg: str | None, sol: Solution,
                start: list[float], end: list[float]) -> None:
    """``swing_energy``: the foot (by Pinocchio FK of the decoded joints, in the leg's base
    frame) starts and ends at the requested positions (1e-6 m); the energy ≥ the bound; on a
    legged robot the drawn path is the leg's, from its hip."""
    chain, mo = swing_chain(robot, leg), _motion(sol)
    feet = tool_positions(chain, mo.q[[0, -1]])
    np.testing.assert_allclose(feet, [start, end], atol=POS_TOL)
    check_energy(chain, mo.t, mo.q, mo.qd, mo.qdd, mo.tau, sol.metrics["energy_total"])
    if isinstance(robot, LeggedRobot):
        assert leg is not None
        hip = robot.leg(leg).hip[:3, 3]
        assert mo.legs == (leg,) and mo.robot == robot.name
        np.testing.assert_allclose(mo.tool[[0, -1]] - hip, [start, end], atol=POS_TOL)


def check_gait(robot: LeggedRobot, sol: Solution) -> None:
    """``quadruped_gait``: every foot (Pinocchio FK of its leg's joints, placed at its hip) on
    its target (1e-6 m), the stance feet on the ground, each leg's energy ≥ its bound (the
    ground reactions are vertical on feet that move horizontally: they do no work)."""
    mo = _motion(sol)
    assert sol.metrics["reachable"] == 1.0
    feet_body = mo.scene["feet"] - mo.scene["body_position"][:, None, :]
    col = 0
    for j, name in enumerate(mo.legs):
        leg = robot.leg(name)
        cols = slice(col, col + leg.robot.nq)
        np.testing.assert_allclose(leg.foot_in_body(tool_positions(leg.robot, mo.q[:, cols])),
                                   feet_body[:, j], atol=POS_TOL)
        check_energy(leg.robot, mo.t, mo.q[:, cols], mo.qd[:, cols], mo.qdd[:, cols],
                     mo.tau[:, cols], sol.metrics[f"energy_{name}_J"], contact=True)
        col = cols.stop
    assert col == mo.q.shape[1]
    sup = mo.scene["support"]
    np.testing.assert_allclose(mo.scene["feet"][..., 2][sup], 0.0, atol=1e-9)
    assert sol.metrics["energy_per_cycle_J"] > 0.0


def check_hexapod(problem: Any, sol: Solution) -> bool:
    """``hexapod_workspace``: when the motion keeps the feet fixed, each stance foot (Pinocchio
    FK of its leg, at its hip on the moving body; study frame: forward is +y) stays where it
    started (1e-6 m), and the body ends at the reported pose. A solution that claims to be
    stable has its body pose inside the support triangle of the fixed feet (signed distance to
    each edge, by cross products, ≥ −the feet's slip). Returns whether the feet were checked
    (a motion that falls back to the paper's, feet not fixed, says so and is not)."""
    mo = sol.motion
    assert mo is not None
    if sol.metrics.get("stable") == 1.0 and "body_pose" in sol.extra:
        P = np.asarray(problem.feet_start, dtype=float)[:, :2]
        c = np.asarray(sol.extra["body_pose"][:2], dtype=float)
        e = np.roll(P, -1, axis=0) - P                       # edges 0→1, 1→2, 2→0
        w = c - P
        area2 = e[0, 0] * (P[2, 1] - P[0, 1]) - e[0, 1] * (P[2, 0] - P[0, 0])
        dist = np.sign(area2) * (e[:, 0] * w[:, 1] - e[:, 1] * w[:, 0]) / np.linalg.norm(e, axis=1)
        assert dist.min() >= -sol.metrics["foot_slip_max"] - 1e-12, (dist, sol.metrics)
    if sol.metrics["motion_feet_fixed"] != 1.0:
        return False
    robot, tripod = problem.robot, problem.tripod
    assert mo.legs == tripod.legs
    body_T = np.asarray(mo.scene["body_T"])
    for k, name in enumerate(mo.legs):
        hip = tripod.hips[k]  # the leg's base frame in the study frame
        p_leg = tool_positions(robot.leg(name).robot, mo.q[:, 3 * k:3 * k + 3])
        p_body = p_leg @ hip[:3, :3].T + hip[:3, 3]
        p_world = np.einsum("kij,kj->ki", body_T[:, :3, :3], p_body) + body_T[:, :3, 3]
        np.testing.assert_allclose(p_world, np.broadcast_to(problem.feet_start[k], p_world.shape),
                                   atol=POS_TOL)
    if "body_pose" in sol.extra:
        assert mo.tool is not None
        np.testing.assert_allclose(mo.tool[-1, :2], sol.extra["body_pose"][:2], atol=1e-12)
    return True


# ----------------------------------------------------------------- results stored by the service


def stored_solution(problem: Any, stored: dict[str, Any]) -> Solution:
    """A stored solution (``best_x`` + ``metrics`` of ``GET /jobs/{id}/result``, or one of its
    ``baselines``' summaries) decoded again by ``problem`` (the job's spec prepared here). The
    decoded metrics must be the stored ones — the checks then hold for what the service kept."""
    x = stored["x"]
    sol = problem.solution(np.asarray(x, dtype=float))
    for name, value in stored["metrics"].items():
        got = sol.metrics[name]
        assert (math.isnan(value) and math.isnan(got)) or got == _approx(value), (name, got, value)
    return sol


def _approx(value: float) -> Any:
    import pytest

    return pytest.approx(value, rel=1e-9, abs=1e-12)


def stored_best(result: dict[str, Any]) -> dict[str, Any]:
    """The best solution of ``GET /jobs/{id}/result`` as ``{"x", "metrics"}``."""
    return {"x": result["best_x"], "metrics": result["metrics"]}


def stored_baselines(result: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Baseline name -> its stored summary (``x``, ``metrics``, …) from the result."""
    return {b["name"]: b["metrics"] for b in result["baselines"]}
