"""Issue 9 "Must show": real robots × the legged study kinds, each a short ``legcore.run`` with
physical checks, or the refusal naming the missing capability.

- ``swing_energy``: the foot starts and ends at the requested positions (1e-6 m, by Pinocchio
  FK of the decoded joints), and the mechanical energy is at least the total variation of the
  leg's mechanical energy (its gravity/inertia bound).
- ``quadruped_gait``: every foot follows its target (1e-6 m) with the stance feet on the
  ground, and each leg's energy is at least the variation of its mechanical energy (the
  ground reactions are vertical on feet that move horizontally: they do no work).
- ``hexapod_workspace``: no robot here has six legs — each is refused by name; the parametric
  and URDF hexapods run in tests/legcore/problems/test_hexapod_workspace.py.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import legcore
from legcore.robots import LeggedRobot
from tests.studies.conftest import refusal_message
from tests.studies.physics import energy_variation, tool_positions

SpecOf = Callable[[str], dict[str, Any]]

#: swing_energy rows: robot -> (leg or None, foot start, foot end) in the leg's base frame, m.
SWINGS: dict[str, tuple[str | None, list[float], list[float]]] = {
    "ur5": (None, [0.34, 0.2, 0.1], [0.46, 0.2, 0.1]),
    "solo12_leg": (None, [-0.06, 0.0594, -0.22], [0.06, 0.0594, -0.22]),
    "solo12": ("HL", [-0.06, 0.0594, -0.22], [0.06, 0.0594, -0.22]),
    "anymal": ("LF", [0.10, 0.13, -0.45], [0.22, 0.13, -0.45]),
    "go1": ("FL", [-0.06, 0.08, -0.28], [0.06, 0.08, -0.28]),
}
GA = {"kind": "ga", "params": {"pop_size": 16, "fitness": "window", "penalty": None}}


@pytest.mark.parametrize("name", sorted(SWINGS))
def test_swing_energy_on_real_legs(name: str, robot_spec: SpecOf, built_robot: Any) -> None:
    leg, start, end = SWINGS[name]
    problem: dict[str, Any] = {
        "kind": "swing_energy", "foot_start": start, "foot_end": end, "exact_ends": True,
        "T": 1.0, "dt": 0.02, "step_height": 0.03, "baselines": ["calderon2008_parabolic"],
    }
    if leg is not None:
        problem["leg"] = leg
    r = legcore.run({"robot": robot_spec(name), "problem": problem, "optimizer": GA,
                     "budget": {"generations": 3}, "seed": 2})
    json.dumps(r.to_dict(), allow_nan=False)
    robot = built_robot(name)
    chain = robot.leg(leg).robot if isinstance(robot, LeggedRobot) else robot
    for sol in (r.best, r.baselines["calderon2008_parabolic"]):
        m = sol.motion
        assert m is not None and m.qd is not None
        feet = tool_positions(chain, m.q[[0, -1]])  # Pinocchio, in the leg's base frame
        np.testing.assert_allclose(feet, [start, end], atol=1e-6)
        assert sol.metrics["energy_total"] >= 0.98 * energy_variation(chain, m.q, m.qd) - 1e-9
        if leg is not None:  # drawn on the body: the motion is the leg's, at its hip
            hip = robot.leg(leg).hip[:3, 3]
            assert m.legs == (leg,) and m.robot == robot.name
            np.testing.assert_allclose(m.tool[[0, -1]] - hip, [start, end], atol=1e-6)
    assert r.best.metrics["on_grid"] == 1.0


def test_swing_energy_refuses_a_seven_joint_arm(robot_spec: SpecOf) -> None:
    msg = refusal_message({"robot": robot_spec("panda"), "problem": {"kind": "swing_energy"}})
    assert msg == "robot: swing_energy needs 2–6 actuated joints; robot panda has 7"


def test_swing_energy_on_a_legged_robot_names_the_leg(robot_spec: SpecOf) -> None:
    msg = refusal_message({"robot": robot_spec("go1"), "problem": {"kind": "swing_energy"}})
    assert msg.startswith("leg: swing_energy swings one leg of the legged robot 'go1'")
    assert "FL" in msg


HKA = {"kind": "hka", "params": {"n_samples": 8, "n_best": 3}}


@pytest.mark.parametrize("name", ["solo12", "anymal", "go1"])
def test_quadruped_gait_on_real_quadrupeds(name: str, preset: SpecOf, built_robot: Any) -> None:
    spec = preset(f"quadruped_gait_{name}")
    spec.update(optimizer=HKA, budget={"generations": 2}, record=False)
    spec["problem"]["samples_per_cycle"] = 32
    r = legcore.run(spec)
    json.dumps(r.to_dict(), allow_nan=False)
    sol = r.baselines["default_step"]
    assert sol.metrics["reachable"] == 1.0
    m = sol.motion
    assert m is not None and m.qd is not None
    robot = built_robot(name)
    feet_body = m.scene["feet"] - m.scene["body_position"][:, None, :]
    col = 0
    for j, leg_name in enumerate(m.legs):
        leg = robot.leg(leg_name)
        n = leg.robot.nq
        q, qd = m.q[:, col:col + n], m.qd[:, col:col + n]
        np.testing.assert_allclose(leg.foot_in_body(tool_positions(leg.robot, q)),
                                   feet_body[:, j], atol=1e-6)
        bound = energy_variation(leg.robot, q, qd)
        assert sol.metrics[f"energy_{leg_name}_J"] >= 0.98 * bound - 1e-9, (leg_name, bound)
        col += n
    sup = m.scene["support"]
    np.testing.assert_allclose(m.scene["feet"][..., 2][sup], 0.0, atol=1e-9)
    assert sol.metrics["energy_per_cycle_J"] > 0.0
    assert set(sol.extra["ik"].values()) == {"numerical (legcore.ik.solve)"}


@pytest.mark.parametrize("name", ["ur5", "panda", "solo12_leg"])
def test_quadruped_gait_refuses_serial_chains(name: str, robot_spec: SpecOf) -> None:
    msg = refusal_message({"robot": robot_spec(name), "problem": {"kind": "quadruped_gait"}})
    assert msg.startswith("robot:") and "needs a legged robot" in msg and name in msg


@pytest.mark.parametrize(
    ("name", "why"),
    [
        ("ur5", "needs a legged robot"),
        ("panda", "needs a legged robot"),
        ("solo12_leg", "needs a legged robot"),
        ("solo12", "hexapod_workspace needs 6 legs of 3 joints; robot solo12 has 4 legs"),
        ("anymal", "hexapod_workspace needs 6 legs of 3 joints; robot anymal has 4 legs"),
        ("go1", "hexapod_workspace needs 6 legs of 3 joints; robot go1 has 4 legs"),
    ],
)
def test_hexapod_workspace_refuses_what_is_not_a_hexapod(
    name: str, why: str, robot_spec: SpecOf
) -> None:
    msg = refusal_message({"robot": robot_spec(name), "problem": {"kind": "hexapod_workspace"}})
    assert msg.startswith("robot:") and why in msg
