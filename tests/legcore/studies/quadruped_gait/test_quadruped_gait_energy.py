"""``quadruped_gait`` (seed 003): stance loads and joint torques against Pinocchio, the energy
of a step, the stability margin, the minimum-energy step under the margin (optimisation), the
closed form against the numerical IK on any quadruped, and violations with their size and unit.
The servo table and the IK branch: ``test_quadruped_gait.py``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from legcore.energy import integrate
from legcore.jobspec import parse_job_spec
from legcore.robots import catalog
from legcore.runner import run
from legcore.studies.quadruped_gait.problem import Params
from legcore.studies.quadruped_gait.study import build
from legcore.studies.registry import get_study
from tests.legcore.studies.quadruped_gait.quadruped_gait_helpers import (
    DEFAULT_X,
    NEAR_OPT_X,
    PAPER_WALK_X,
    ROBOT,
)

EXAMPLE = Path(__file__).resolve().parents[4] / "examples" / "003_quadruped_gait.yaml"


# ------------------------------------------------------------------------- loads and energy
def test_stance_loads_hold_the_robot_and_torques_match_pinocchio(problem):
    r = problem.simulate(DEFAULT_X[None], detail=True)
    loads, feet, com = r["loads"][0], r["feet"][0], r["com"][0]
    W = problem.mass * 9.81
    assert np.allclose(loads.sum(-1), W, rtol=1e-12)
    moment = np.einsum("kj,kji->ki", loads, feet[..., :2] - com[:, None, :2])
    assert np.allclose(moment, 0.0, atol=1e-12)
    assert loads.min() >= -1e-12 and np.all(loads[~r["support"][0]] == 0.0)
    # the load is handed over during the four-foot phases: no jumps between samples
    assert np.abs(np.diff(loads, axis=0)).max() < 0.25 * W
    # τ = RNEA − J_vᵀ F against pinocchio's RNEA with the foot force as an external force
    q, qd, qdd, tau = (r[k][0] for k in ("q", "qd", "qdd", "tau"))
    for j, leg in enumerate(problem.legs):
        rb = leg.robot
        model, data = rb.model, rb.data()
        for k in (0, 10, 25, 40, 57):
            cols = slice(2 * j, 2 * j + 2)
            F_leg = loads[k, j] * (leg.hip[:3, :3].T @ [0.0, 0.0, 1.0])
            pin.forwardKinematics(model, data, q[k, cols])
            pin.updateFramePlacements(model, data)
            foot = data.oMf[rb.tool_frame]
            fext = [pin.Force.Zero() for _ in range(model.njoints)]
            oMi = data.oMi[2]
            f_local = oMi.rotation.T @ F_leg
            r_local = oMi.actInv(foot).translation
            fext[2] = pin.Force(f_local, np.cross(r_local, f_local))
            ref = pin.rnea(model, data, q[k, cols], qd[k, cols], qdd[k, cols], fext)
            assert np.allclose(tau[k, cols], ref, atol=1e-12), (leg.name, k)


def test_energy_is_the_integral_of_joint_power(default_solution):
    m, met = default_solution.motion, default_solution.metrics
    E = float(integrate(np.abs(m.tau * m.qd), m.t).sum())
    assert met["energy_per_cycle_J"] == pytest.approx(E, rel=1e-12)
    assert m.energy[-1] == pytest.approx(E, rel=1e-12)
    assert sum(met[f"energy_{n}_J"] for n in m.legs) == pytest.approx(E, rel=1e-12)
    assert met["energy_swing_J"] + met["energy_stance_J"] == pytest.approx(E)
    assert met["energy_per_metre_J_per_m"] == pytest.approx(E / (0.119 / 0.8))
    assert met["cycle_time_s"] == pytest.approx(0.119 / (0.8 * 0.03))
    # swing-only dynamics cost far less than carrying the body
    unloaded = build(ROBOT, Params(stance_load="none")).solution(DEFAULT_X)
    assert unloaded.metrics["energy_per_cycle_J"] < 0.6 * E
    # per-cycle objective
    pc = build(ROBOT, Params(objective="energy_per_cycle"))
    F, _ = pc.evaluate(DEFAULT_X[None])
    assert F[0, 0] == pytest.approx(E, rel=1e-12)


def test_margin_of_the_default_step_and_of_the_paper_walk(problem):
    F, G = problem.evaluate(np.array([DEFAULT_X, PAPER_WALK_X]))
    assert np.all(G[0] <= 0.0)  # the default step is feasible (margin 1.17 mm >= 1 mm)
    # duty 3/4 with Table 2's stroke 1.2 mm behind the hips: the COM leaves the support
    # triangle at the beat boundaries (margin ≈ −0.55 mm)
    assert G[1, 0] > 1.0 and G[1, 1:].max() <= 0.0
    centred = build(ROBOT, Params(stroke_center=0.0, com_offset=(0.0, 0.0)))
    r = centred.simulate(PAPER_WALK_X[None], detail=True)
    from legcore.support_polygon import stability_margin

    body_only = stability_margin(r["feet"][0], r["support"][0]).min()
    assert body_only == pytest.approx(0.0, abs=1e-12)  # docs/legged.md: zero at the beats


# -------------------------------------------------------------------------- optimisation
def _check_run(r, gens):
    d = r.to_dict()
    json.dumps(d, allow_nan=False)
    best, base = r.best, r.baselines["default_step"]
    assert r.objective_names == ("energy_per_metre",)
    assert best.metrics["feasible"] == 1.0 and best.metrics["reachable"] == 1.0
    assert best.metrics["min_stability_margin_m"] >= 0.001 - 1e-9
    assert best.objectives["energy_per_metre"] <= base.objectives["energy_per_metre"]
    assert r.baselines["paper_walk"].metrics["feasible"] == 0.0
    assert len(r.history) == gens
    assert len(d["best"]["extra"]["servo_table"]["rows"]) == 64
    assert len(d["extras"]["table2_paper"]["rows"]) == 8
    return best, base


def test_run_end_to_end_reduced_budget():
    spec = {"problem": {"kind": "quadruped_gait"}, "seed": 7, "budget": {"generations": 8}}
    r = run(spec)
    best, base = _check_run(r, 8)
    assert best.objectives["energy_per_metre"] < 0.85 * base.objectives["energy_per_metre"]
    again = run(spec)
    assert np.array_equal(again.best.x, best.x)


@pytest.mark.slow
def test_example_spec_reaches_the_minimum_energy_step():
    """The example at the study's own settings: the optimum is a short, low, high-duty step,
    ≈ 0.774 J/m on a 0.001 × 0.0001 grid of (s, β) at h = 1 cm; the default step 1.207 J/m."""
    spec = parse_job_spec(yaml.safe_load(EXAMPLE.read_text()))
    assert spec.problem.kind == "quadruped_gait"
    r = run(spec)
    best, base = _check_run(r, 40)
    e = best.objectives["energy_per_metre"]
    assert e <= 0.78 and e <= 0.66 * base.objectives["energy_per_metre"]
    s, h, beta = best.x
    assert 0.045 < s < 0.07 and h < 0.0105 and 0.83 < beta < 0.88


# ------------------------------------------------------------------------------ any quadruped
def test_closed_form_fast_path_equals_the_numerical_ik():
    """The leg2 closed form (analytic rates) against legcore.ik.solve + Jacobian rates on the
    same robot: joint motion, torques, energy and margin agree."""
    X = np.array([DEFAULT_X, NEAR_OPT_X, [0.1, 0.04, 0.77]])
    fast = build(ROBOT, Params())
    slow = build(ROBOT, Params(ik="numeric"))
    a, b = fast.simulate(X, detail=True), slow.simulate(X, detail=True)
    assert a["reachable"].all() and b["reachable"].all()
    np.testing.assert_allclose(b["q"], a["q"], atol=1e-6)
    np.testing.assert_allclose(b["qd"], a["qd"], atol=1e-5)
    np.testing.assert_allclose(b["qdd"], a["qdd"], rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(b["tau"], a["tau"], atol=1e-7)
    np.testing.assert_allclose(b["E"], a["E"], rtol=1e-6)
    np.testing.assert_allclose(b["margin"], a["margin"], atol=1e-9)
    sol = slow.solution(DEFAULT_X)
    assert set(sol.extra["ik"].values()) == {"numerical (legcore.ik.solve)"}


def test_legs_by_corner_and_clear_errors():
    p = build(ROBOT, Params())
    assert p.roles == ("FL", "FR", "RL", "RR") and p.extras(np.zeros((0, 3)), np.zeros((0, 1)))[
        "legs"] == {"FL": "FL", "FR": "FR", "RL": "RL", "RR": "RR"}
    with pytest.raises(ValueError, match="^q_ref: unknown legs"):
        build(ROBOT, Params(q_ref={"XX": (0.0, 0.0)}))
    with pytest.raises(ValueError, match="^q_ref: leg 'FL' has 2 joints"):
        build(ROBOT, Params(q_ref={"FL": (0.0, 0.0, 0.0)}))
    with pytest.raises(ValueError, match="^servo_offset_deg: leg 'FR' has 2 joints"):
        build(ROBOT, Params(servo_offset_deg={"FR": (0.0, 0.0, 0.0)}))
    with pytest.raises(ValueError, match="^robot: quadruped_gait needs 4 legs of 2–3 joints; "
                                         "robot citedi_hexapod has 6 legs"):
        get_study("quadruped_gait").build(catalog.get("citedi_hexapod"), Params())


# ------------------------------------------------------------------------------- violations
def test_violations_say_what_is_violated_with_size_and_unit(problem):
    """The margin in mm, the joint over its speed or torque limit with its peak and limit, a
    foot pulling on the ground in N — each the size of its column of G."""
    assert problem.violations(DEFAULT_X) == ()  # the seed's default step is feasible
    (margin,) = problem.violations(PAPER_WALK_X)
    _, G = problem.evaluate(PAPER_WALK_X[None])
    assert margin.constraint == "stability_margin_mm" and margin.unit == "mm"
    assert margin.amount == pytest.approx(G[0, 0]) and 1.0 < margin.amount < 2.0
    assert margin.text == (f"static stability margin {1.0 - margin.amount:.3g} mm, "
                           f"{margin.amount:.3g} mm short of the required 1 mm")
    fast = build(ROBOT, Params(speed=0.2))  # 6.7 × the seed's speed
    speed, torque = fast.violations(DEFAULT_X)
    qd = fast.solution(DEFAULT_X).motion.qd
    j = int(np.argmax(np.abs(qd).max(axis=0) / 5.0))  # the servos' 5 rad/s
    assert speed.constraint == "joint_speed" and speed.text.startswith(
        f"joint {fast.joint_names[j]} at {np.abs(qd).max() / 5.0:.0%} of its speed limit 5 rad/s")
    assert torque.constraint == "torque" and "of its torque limit 0.1177 N·m" in torque.text
    heavy_front = build(ROBOT, Params(com_offset=(0.03, 0.0)))  # body COM 3 cm ahead
    margin, pull = heavy_front.violations(DEFAULT_X)
    loads = heavy_front.solution(DEFAULT_X).motion.scene["foot_loads_N"]
    assert margin.amount > 10.0 and pull.constraint == "foot_pull" and pull.unit == "N"
    assert pull.amount == pytest.approx(-loads.min()) and "pulls on the ground" in pull.text
