"""path_tracking (seed 004) optimised: the minimum time within every limit against the seed law
and the physical minimum (TOPP-RA), the minimum energy at the seed's cycle time, and (slow) the
seed budget's optima. The problem itself: ``test_path_tracking.py``."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import legcore
from legcore.robots import catalog
from legcore.studies.path_tracking.problem import DEFAULT_QDD_MAX


@pytest.fixture(scope="module")
def arm():
    return catalog.get("articulated_5dof")


def test_optimised_time_respects_every_limit_and_beats_the_seed(arm):
    res = legcore.run({
        "problem": {"kind": "path_tracking"},
        "optimizer": {"kind": "nsga2", "params": {"pop_size": 30}},
        "seed": 1,
        "budget": {"generations": 15},
    })
    best, seed = res.best, res.baselines["seed"]
    mo = best.motion
    assert best.metrics["feasible"] == 1.0
    assert np.all(np.abs(mo.qd).max(axis=0) <= arm.qd_max)  # |q̇| <= 1.5 rad/s everywhere
    assert np.all(np.abs(mo.qdd).max(axis=0) <= DEFAULT_QDD_MAX)  # |q̈| <= 5 rad/s²
    assert np.all(np.abs(mo.tau).max(axis=0) <= arm.tau_max)  # |τ| <= (40, 40, 20, 5, 2) N·m
    assert best.objectives["time"] < 0.5 * seed.objectives["time"]
    assert best.extra["path_error"] < 1e-9 and best.extra["orientation_error"] < 1e-12
    # the ramps last what the acceleration limit allows, not milliseconds
    assert min(best.metrics["t_a"], best.metrics["t_d"]) > 0.05
    assert set(res.baselines) == {"time_optimal", "seed", "seed_max_V"}
    assert res.baselines["seed_max_V"].metrics["feasible"] == 1.0
    # the physical minimum (TOPP-RA) is a lower bound of every feasible law, and feasible
    T_star = res.baselines["time_optimal"].objectives["time"]
    assert res.baselines["time_optimal"].violations == ()
    assert T_star < best.objectives["time"]
    assert res.gap is not None and res.gap["reference"] == pytest.approx(T_star)
    assert res.gap["pct"] == pytest.approx(100 * (best.objectives["time"] / T_star - 1))
    assert res.extras["front"][0]["time_change_pct"] < -50.0
    text = json.dumps(res.to_dict(), allow_nan=False)
    assert '"seed_max_V"' in text


def test_energy_at_the_seed_cycle_time_beats_the_seed():
    """Objective energy, the seed's own scheme (one V, t_a, t_d) and its cycle time as T_max."""
    T_seed = 11.0 + 2.0 * math.pi
    res = legcore.run({
        "problem": {"kind": "path_tracking", "objective": "energy", "T_max": T_seed,
                    "speeds": "single"},
        "optimizer": {"kind": "nsga2", "params": {"pop_size": 20}},
        "seed": 2,
        "budget": {"generations": 10},
    })
    best, seed = res.best, res.baselines["seed"]
    assert best.metrics["feasible"] == 1.0 and best.metrics["time"] <= T_seed
    assert best.objectives["energy"] < seed.objectives["energy"]
    assert np.all(np.abs(best.motion.qd).max(axis=0) <= 1.5)
    json.dumps(res.to_dict(), allow_nan=False)


@pytest.mark.slow
def test_default_budget_reaches_the_limit_bound_optimum(arm):
    """Seed budget (NSGA-II 40 × 60): T within 2 % of 3.849 s (NSGA-II 100 × 200, seeds 1–3:
    3.849–3.868 s), with the joint-speed and acceleration limits active."""
    res = legcore.run({"problem": {"kind": "path_tracking"}, "seed": 1})
    m = res.best.metrics
    assert m["feasible"] == 1.0
    assert m["time"] < 3.849 * 1.02
    assert m["qd_use_max"] > 0.99 and m["qd_use_max"] <= 1.0 and m["tau_use_max"] <= 1.0
    assert m["qdd_use_max"] > 0.99 and m["qdd_use_max"] <= 1.0


@pytest.mark.slow
def test_default_budget_without_the_acceleration_limit_reaches_the_seed_optimum(arm):
    """The seed's own problem (joint speed and torque limits, no acceleration limit: qdd_max
    null) at the seed budget (NSGA-II 40 × 60): T within 2 % of 2.948 s (NSGA-II 100 × 200 and
    HKA 100 × 200 both reach 2.948 s), with a joint-speed limit active — the number asserted
    before the 5 rad/s² default arrived (``test_default_budget_reaches_the_limit_bound_optimum``
    asserts the limited problem's 3.849 s)."""
    res = legcore.run({"problem": {"kind": "path_tracking", "qdd_max": None}, "seed": 1})
    m = res.best.metrics
    assert m["feasible"] == 1.0
    assert m["time"] < 2.948 * 1.02
    assert m["qd_use_max"] > 0.99 and m["qd_use_max"] <= 1.0 and m["tau_use_max"] <= 1.0
    assert m["qdd_use_max"] == 0.0  # no acceleration limit: nothing to use
