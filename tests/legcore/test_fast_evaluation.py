"""Fast evaluation kernels (issue 12) against their references, and the problems' F, G.

- ``chain_points`` (positions only, block-wise trig) = the translations of ``frames``/``fk``
  (themselves tested against Pinocchio in ``test_kinematics``) on every catalog robot and a
  URDF arm with tilted axes and a prismatic joint;
- ``chain_clearance`` (all boxes in one pass, bounding-box skip) = ``segment_box_depth`` (numpy);
- ``travel_and_peak``, ``peak_abs`` = the numpy reductions; ``compose_ppoly`` = scipy's
  ``PPoly`` derivatives + ``compose_time_law``;
- ``swing_energy`` (seed 000 flat/obstacle, several boxes, a leg whose foot is a tool frame) and
  ``path_tracking`` (seed 004): ``evaluate`` = the pre-issue-12 evaluation written out here with
  the reference functions, to 1e-12.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from scipy.interpolate import PPoly

from legcore.chain_points import chain_points
from legcore.dynamics import inverse_dynamics
from legcore.energy import mechanical_energy
from legcore.kinematics import fk, frames
from legcore.robots import LeggedRobot, Robot, build_robot, catalog
from legcore.runner import prepare
from legcore.studies.path_tracking.kin import compose_ppoly, peak_abs
from legcore.studies.swing_energy.geometry import (
    chain_clearance,
    segment_box_depth,
    travel_and_peak,
)
from legcore.studies.swing_energy.problem import Params, SwingEnergyProblem
from legcore.studies.swing_energy.study import build
from legcore.trajectories.sampling import compose_time_law

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


_LINK = ('<inertial><mass value="0.5"/><origin xyz="0.05 0 0"/><inertia ixx="0.01" ixy="0" '
         'ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>')
_URDF = f"""<robot name="rp4">
  <link name="base"/><link name="l1">{_LINK}</link><link name="l2">{_LINK}</link>
  <link name="l3">{_LINK}</link><link name="l4">{_LINK}</link><link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3" rpy="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="50" velocity="2"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.05 0.02 0.1" rpy="1.5707963 0 0"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-2.5" upper="2.5" effort="50" velocity="2"/></joint>
  <joint name="j3" type="prismatic"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.3 0 0" rpy="0 0.2 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.1" effort="5" velocity="0.5"/></joint>
  <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/>
    <origin xyz="0 0.01 0.06" rpy="0.3 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-2" upper="2" effort="10" velocity="3"/></joint>
  <joint name="tipj" type="fixed"><parent link="l4"/><child link="tip"/>
    <origin xyz="0.02 0 0.1" rpy="0 0.4 0"/></joint>
</robot>"""


def _serial_robots() -> list[tuple[str, Robot]]:
    out: list[tuple[str, Robot]] = []
    for name in catalog.names():
        r = catalog.get(name)
        if isinstance(r, LeggedRobot):
            out.extend((f"{name}/{leg.name}", leg.robot) for leg in r.legs[:1])
        else:
            out.append((name, r))
    out.append(("urdf_rp4", build_robot({"kind": "urdf", "name": "rp4", "urdf": _URDF})))
    return out


def _population(problem: Any, size: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    X = problem.xl + rng.random((size, problem.n_var)) * (problem.xu - problem.xl)
    return np.asarray(problem.snap(X), dtype=float)


# ---------------------------------------------------------------------------------- kernels


@pytest.mark.parametrize("label,robot", _serial_robots(), ids=lambda x: x if isinstance(x, str)
                         else "")
def test_chain_points_equal_the_frames_translations(label: str, robot: Robot) -> None:
    rng = np.random.default_rng(5)
    # (3, 70, n): more than one trig block; wide angles exercise the range reduction
    q = rng.uniform(robot.q_min - 3.0, robot.q_max + 3.0, (3, 70, robot.nq))
    ref = np.concatenate([frames(robot, q)[..., :3, 3], fk(robot, q)[..., None, :3, 3]], axis=-2)
    P = chain_points(robot, q, tool=True)
    assert P.shape == (3, 70, robot.nq + 2, 3) and P.flags.c_contiguous
    np.testing.assert_allclose(P, ref, atol=1e-12, rtol=0)
    np.testing.assert_array_equal(chain_points(robot, q), P[..., :-1, :])
    np.testing.assert_array_equal(chain_points(robot, q[0, 0]), P[0, 0, :-1])
    # points fixed in the link frames (the quadruped study's link COMs)
    off = rng.uniform(-0.1, 0.1, (robot.nq, 3))
    F = frames(robot, q)
    want = np.einsum("...lij,lj->...li", F[..., 1:, :3, :3], off) + F[..., 1:, :3, 3]
    got = chain_points(robot, q, offsets=off)
    np.testing.assert_allclose(got[..., 1:, :], want, atol=1e-12, rtol=0)
    np.testing.assert_array_equal(got[..., 0, :], P[..., 0, :])
    with pytest.raises(ValueError, match="offsets"):
        chain_points(robot, q, offsets=off[:-1])


def test_chain_clearance_equals_the_slab_reference_over_several_boxes() -> None:
    rng = np.random.default_rng(8)
    P = rng.uniform(-0.2, 0.2, (6, 40, 4, 3))
    P[:, :, 0] = 0.0
    centers = np.array([[0.0, 0.0, -0.05], [0.08, -0.05, 0.0], [-0.1, 0.1, 0.1]])
    halves = np.array([[0.05, 0.04, 0.03], [0.02, 0.06, 0.05], [0.03, 0.03, 0.03]])
    depth, zmin = chain_clearance(P, centers, halves)
    a, b = P[:, :, :-1], P[:, :, 1:]
    per_box = [segment_box_depth(a, b, c, h).max(axis=(1, 2)) for c, h in zip(centers, halves,
                                                                              strict=True)]
    np.testing.assert_allclose(depth, np.max(per_box, axis=0), atol=1e-15, rtol=0)
    assert np.all(depth > 0.0)  # the points are dense enough: every chain hits a box
    np.testing.assert_array_equal(zmin, P[:, :, 1:, 2].min(axis=(1, 2)))
    d1, z1 = chain_clearance(P[:, :, ::-1][:, :, ::-1], centers[1], halves[1])  # a strided view
    np.testing.assert_allclose(d1, per_box[1], atol=1e-15, rtol=0)
    np.testing.assert_array_equal(chain_clearance(P)[0], np.zeros(6))
    np.testing.assert_array_equal(chain_clearance(P)[1], z1)


def test_travel_and_peak_and_peak_abs_equal_numpy() -> None:
    rng = np.random.default_rng(2)
    q, qdd = rng.normal(size=(2, 5, 37, 4))
    theta, acc = travel_and_peak(q, qdd)
    np.testing.assert_allclose(theta, np.sum(np.abs(np.diff(q, axis=1)), axis=1), rtol=1e-15)
    np.testing.assert_array_equal(acc, np.max(np.abs(qdd), axis=1))
    np.testing.assert_array_equal(peak_abs(qdd), np.abs(qdd).max(axis=1))
    qdd[1, 7, 2] = np.nan
    np.testing.assert_array_equal(peak_abs(qdd), np.abs(qdd).max(axis=1))


def test_compose_ppoly_equals_scipy_and_compose_time_law() -> None:
    rng = np.random.default_rng(4)
    x = np.r_[0.0, np.cumsum(rng.uniform(0.05, 0.2, 30))]
    x[10] = x[11]  # a join: a zero-length interval, as in the study's joint paths
    poly = PPoly(rng.normal(size=(6, x.size - 1, 3)), x)
    sigma = np.r_[rng.uniform(-0.1, x[-1] + 0.1, 400), x, np.sort(rng.uniform(0, x[-1], 50))]
    sig = np.stack([sigma, *rng.normal(size=(3, sigma.size))])
    ref = compose_time_law(np.stack([poly(sigma, nu) for nu in range(4)]), sig)
    out = compose_ppoly(poly, sig)
    for d in range(4):
        np.testing.assert_allclose(out[d], ref[d], rtol=0, atol=1e-13 * np.abs(ref[d]).max())


# ---------------------------------------------------------------------------------- problems


def _swing_reference(p: SwingEnergyProblem, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The score criterion's F, G as evaluated before issue 12 (4×4 frames, numpy)."""
    q, qdd = p.trajectories(X, (0, 2))
    theta = np.sum(np.abs(np.diff(q, axis=-2)), axis=-2)
    theta = np.where(theta < 1e-12, 0.0, theta)
    acc = np.max(np.abs(qdd), axis=-2)
    acc = np.where(acc < 1e-9, 0.0, acc)

    def ratio(num: np.ndarray, den: np.ndarray, eps: float) -> np.ndarray:
        return np.minimum((num + eps) / (den + eps), 1.0)

    f_d = ratio(p.theta_min, theta, p.eps_d) @ p.w_d
    f_a = ratio(p.acc_coordinated, acc, p.eps_a) @ p.w_a
    F = -(p.params.w1 * f_d + p.params.w2 * f_a)
    P = frames(p.robot, q)[..., :3, 3]
    if not p._foot_is_last_frame:
        P = np.concatenate([P, fk(p.robot, q)[..., None, :3, 3]], axis=-2)
    cols = []
    if p.params.ground:
        cols.append(p.z_ground - p.params.ground_tolerance - P[:, :, 1:, 2].min(axis=(1, 2)))
    if p.boxes:
        a, b = P[:, :, :-1], P[:, :, 1:]
        cols.append(np.max([segment_box_depth(a, b, box.center, np.asarray(box.half_size) + m)
                            .max(axis=(1, 2)) for box, m in zip(p.boxes, p.margins,
                                                                strict=True)], axis=0))
    return F[:, None], np.stack(cols, axis=1)


def _leg_with_tool() -> Robot:
    """A 3-joint DH leg whose foot is a tool offset (not the last link frame)."""
    joints: list[dict[str, Any]] = [{"alpha": np.pi / 2, "a": 0.02, "mass": 0.1,
                                     "com": [-0.01, 0, 0],
                                     "inertia": [[1e-6, 0, 0], [0, 1e-5, 0], [0, 0, 1e-5]]}]
    joints += [{"a": 0.12, "mass": 0.1, "com": [-0.05, 0, 0],
                "inertia": [[1e-6, 0, 0], [0, 5e-5, 0], [0, 0, 5e-5]]} for _ in range(2)]
    tool = np.eye(4)
    tool[:3, 3] = [0.03, 0.01, 0.0]
    return build_robot({"kind": "dh", "name": "leg_tool", "joints": joints,
                        "tool": tool.tolist()})


def _swing_cases() -> list[tuple[str, SwingEnergyProblem]]:
    cases = []
    for name in ("000_swing_energy_flat", "000_swing_energy_obstacle"):
        spec = yaml.safe_load((EXAMPLES / f"{name}.yaml").read_text())
        cases.append((name, prepare(spec).problem))
    leg = _leg_with_tool()
    base = {"q_start": (-0.2, -0.6, 1.2), "q_end": (0.2, -0.6, 1.2)}
    p = build(leg, Params(**base))
    mid = 0.5 * (p.foot_start + p.foot_end)
    boxes = ({"center": tuple(mid + [0, 0, 0.01]), "size": (0.02, 0.02, 0.02), "margin": 0.001},
             {"center": tuple(mid + [0.03, 0.0, 0.05]), "size": (0.01, 0.04, 0.03),
              "margin": 0.004})
    cases.append(("tool_foot_two_boxes", build(leg, Params(**base, obstacles=boxes))))
    return cases


@pytest.mark.parametrize("label,problem", _swing_cases(), ids=lambda x: x if isinstance(x, str)
                         else "")
def test_swing_energy_evaluation_equals_the_reference(label: str,
                                                      problem: SwingEnergyProblem) -> None:
    X = _population(problem, 100, seed=12)
    X[0] = problem.coordinated_x()
    F, G = problem.evaluate(X)
    F_ref, G_ref = _swing_reference(problem, X)
    np.testing.assert_allclose(F, F_ref, atol=1e-12, rtol=0)
    np.testing.assert_allclose(G, G_ref, atol=1e-12, rtol=0)
    if problem.boxes:
        assert np.any(G[:, -1] > 0.0) and np.any(G[:, -1] == 0.0)  # both kinds are tested
    if label == "tool_foot_two_boxes":
        assert not problem._foot_is_last_frame


@pytest.mark.parametrize("example", ["004_path_tracking", "004_path_tracking_energy_time"])
def test_path_tracking_evaluation_equals_the_reference(example: str) -> None:
    spec = yaml.safe_load((EXAMPLES / f"{example}.yaml").read_text())
    p = prepare(spec).problem
    X = np.vstack([_population(p, 40, seed=12), p.seed_x()])
    F, G = p.evaluate(X)
    # the pre-issue-12 simulate: scipy PPoly derivatives + compose_time_law, numpy reductions
    law = p.time_law(X)
    B, K, n = X.shape[0], p.n_samples, p.robot.nq
    t = law.sample_times(K, 10)
    s4 = law.evaluate(t).reshape(4, B * K)
    q, qd, qdd, _ = compose_time_law(p.joints.derivatives(s4[0]), s4).reshape(4, B, K, n)
    tau = inverse_dynamics(p.robot, q, qd, qdd)
    r = p.robot
    G_ref = np.concatenate([np.abs(qd).max(axis=1) / r.qd_max - 1.0,
                            np.abs(qdd).max(axis=1) / p.qdd_max - 1.0,
                            np.abs(tau).max(axis=1) / r.tau_max - 1.0,
                            (law.fit.max(axis=1) - 1.0)[:, None]], axis=1)
    G_ref = np.where(np.isfinite(G_ref), G_ref, 1e6)
    cols = {"time": law.T, "energy": mechanical_energy(qd, tau, t).total}
    F_ref = np.stack([cols[name] for name in p.objective_names], axis=1)
    np.testing.assert_allclose(F, F_ref, atol=1e-12, rtol=0)
    np.testing.assert_allclose(G, G_ref, atol=1e-12, rtol=0)
    sim = p.simulate(X[-1:])  # the decoded motion still carries the tool path and the energy
    assert sim["p"].shape == (1, K, 3) and sim["E"].shape == (1,)
    lean = p.simulate(X[-1:], full=False)  # no tool path; the energy only as an objective
    assert "p" not in lean and ("E" in lean) == ("energy" in p.objective_names)
