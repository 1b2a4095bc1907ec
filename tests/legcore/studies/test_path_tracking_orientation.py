"""path_tracking beyond seed 004's capsule: the tool orientation (down with a fixed heading,
free), user paths in another plane, and the defaults derived on an arm that is not the seed's.
The seed's own problem: ``test_path_tracking.py``; optimisation runs:
``test_path_tracking_optimum.py``."""

from __future__ import annotations

import math

import numpy as np
import pytest

import legcore
from legcore import kinematics
from legcore.robots import catalog
from legcore.studies.path_tracking.joints import ToolOrientation
from legcore.studies.path_tracking.problem import DEFAULT_QDD_MAX, Params
from legcore.studies.path_tracking.study import STUDY


@pytest.fixture(scope="module")
def arm():
    return catalog.get("articulated_5dof")


def test_tool_orientation_targets_and_heading():
    down = ToolOrientation((0.0, 0.0, -2.0), yaw=0.3)
    assert down.axis == (0.0, 0.0, -1.0) and down.task == "pose"
    R = down.rotation()
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(R) == pytest.approx(1.0)
    assert math.atan2(R[1, 0], R[0, 0]) == pytest.approx(0.3)  # heading in the xy plane
    side = ToolOrientation((1.0, 0.0, 0.0))  # along world x: heading measured from world y
    assert side.task == "axis" and side.rotation()[:, 0] == pytest.approx([0.0, 1.0, 0.0])
    assert ToolOrientation(None).task == "position"
    p = np.array([[0.1, 0.2, 0.3]])
    assert side.targets(p).shape == (1, 6) and down.targets(p).shape == (1, 4, 4)
    with pytest.raises(ValueError, match="tool_yaw"):
        ToolOrientation(None, 0.1)
    with pytest.raises(ValueError, match="tool_axis"):
        ToolOrientation((0.0, 0.0, 0.0))


def test_free_orientation_in_a_vertical_plane(arm):
    """A path in the vertical plane y = 0.35 m (u = x, v = z), tool orientation free: the
    generic IK places it; FK of the decoded motion is on the path to 1e-9 m."""
    segments = (
        {"type": "line", "start": (-0.10, 0.30), "end": (0.10, 0.30)},
        {"type": "arc", "center": (0.10, 0.40), "r": 0.10, "beta": -math.pi / 2,
         "phi": math.pi},
    )
    pr = STUDY.build(arm, Params(segments=segments, plane_origin=(0.0, 0.35, 0.0),
                           plane_e1=(1.0, 0.0, 0.0), plane_e2=(0.0, 0.0, 1.0),
                           orientation="free", n_samples=200))
    sol = pr.solution(np.array([0.2, 0.15, 0.5, 0.5, 0.1]))
    mo = sol.motion
    assert sol.extra["path_error"] < 1e-9 and sol.extra["orientation_error"] == 0.0
    np.testing.assert_allclose(mo.tool[:, 1], 0.35, atol=1e-9)
    np.testing.assert_allclose(mo.tool[0], [-0.10, 0.35, 0.30], atol=1e-9)
    np.testing.assert_allclose(mo.tool[-1], [0.10, 0.35, 0.50], atol=1e-9)
    v = np.einsum("kij,kj->ki", kinematics.jacobian(arm, mo.q), mo.qd)
    speed = np.linalg.norm(v[:, :3], axis=1)
    assert speed.max() == pytest.approx(0.2, rel=1e-6) and sol.metrics["feasible"] == 1.0


TURN = (  # a line and a quarter arc in the seed's plane z = 0.50 m, the base turning ~90°
    {"type": "line", "start": (0.45, -0.10), "end": (0.45, 0.10)},
    {"type": "arc", "center": (0.35, 0.10), "r": 0.10, "beta": 0.0, "phi": math.pi / 2},
)


def _holds_the_heading(arm, mo, yaw: float) -> None:
    """FK of the decoded motion: tool pointing down with its x axis at ``yaw`` in the xy plane
    on every sample, and no angular velocity (the orientation is fixed in the world) — so joint
    5 turns with the base."""
    T = kinematics.fk(arm, mo.q)
    np.testing.assert_allclose(T[:, :3, 2], np.tile([0.0, 0.0, -1.0], (mo.n_samples, 1)),
                               atol=1e-9)
    np.testing.assert_allclose(np.arctan2(T[:, 1, 0], T[:, 0, 0]), yaw, atol=1e-10)
    assert np.ptp(mo.q[:, 4]) > 0.1  # joint 5 turns with the base to hold the heading
    v = np.einsum("kij,kj->ki", kinematics.jacobian(arm, mo.q), mo.qd)
    np.testing.assert_allclose(v[:, 3:], 0.0, atol=1e-8 * max(1.0, np.abs(mo.qd).max()))


def test_user_path_with_fixed_tool_heading(arm):
    """Tool down with a fixed heading (``tool_yaw`` 0.3 rad) on a user path: the decoded
    motion is on the path and holds the heading, joint 5 turning (restored from before the
    generic IK; the closed form gave 1e-12, the numerical pose IK 1e-9–1e-10)."""
    pr = STUDY.build(arm, Params(segments=TURN, tool_yaw=0.3, speeds="single", n_samples=200))
    assert pr.variable_names == ("V", "t_a", "t_d")
    sol = pr.solution(np.array([0.15, 0.5, 0.5]))
    mo = sol.motion
    assert sol.extra["path_error"] < 1e-9 and sol.extra["orientation_error"] < 1e-9
    assert sol.extra["orientation"] == "the tool axis along [0.0, 0.0, -1.0] at heading 0.3 rad"
    _holds_the_heading(arm, mo, 0.3)
    np.testing.assert_allclose(mo.tool[0], [0.45, -0.10, 0.50], atol=1e-12)
    assert mo.tool[-1] == pytest.approx([0.35, 0.20, 0.50], abs=1e-9)


def test_fixed_tool_heading_end_to_end(arm):
    """The same path and heading through ``legcore.run`` (a short NSGA-II): the optimum and the
    seed law both hold the heading, on the path, within every limit."""
    res = legcore.run({
        "problem": {"kind": "path_tracking", "segments": list(TURN), "tool_yaw": 0.3,
                    "speeds": "single", "n_samples": 200},
        "optimizer": {"kind": "nsga2", "params": {"pop_size": 20}},
        "seed": 1,
        "budget": {"generations": 5},
    })
    for sol in (res.best, res.baselines["seed"]):
        mo = sol.motion
        assert sol.metrics["feasible"] == 1.0
        assert sol.extra["path_error"] < 1e-9 and sol.extra["orientation_error"] < 1e-9
        _holds_the_heading(arm, mo, 0.3)
        assert np.all(np.abs(mo.qd).max(axis=0) <= arm.qd_max)
        assert np.all(np.abs(mo.qdd).max(axis=0) <= DEFAULT_QDD_MAX)
    assert res.best.objectives["time"] < res.baselines["seed"].objectives["time"]


# ------------------------------------------------------------------ defaults on another arm


def test_workspace_analysis_of_the_seed_arm(arm):
    """Sampled FK: the reach from the shoulder is the arm's a2 + a3 + d5 = 1.0 m at most (and
    nearly reached); the dexterity of the position task is σ_min(J_v) / reach; holding the tool
    down (the 5-joint arm's roll about the tool axis is then useless) it is still positive and
    the joint rates it implies move the tool in the plane without tilting it."""
    from legcore.studies.arm_workspace import arm_workspace, centres, dexterity, plane_basis

    ws = arm_workspace(arm)
    assert 0.98 < ws.reach <= 1.0 + 1e-12
    np.testing.assert_allclose(ws.shoulder, [0.0, 0.0, 0.5], atol=1e-12)
    q = ws.q[:5]
    Jv = kinematics.jacobian(arm, q)[:, :3]
    np.testing.assert_allclose(ws.dexterity[:5],
                               np.linalg.svd(Jv, compute_uv=False)[:, -1] / ws.reach, rtol=1e-9)
    down = centres(arm, (0.0, 0.0, -1.0))
    assert down and down[0].dexterity > 0.2
    c = down[0]
    np.testing.assert_allclose(kinematics.fk(arm, c.q)[:3, 2], [0.0, 0.0, -1.0], atol=1e-9)
    B = plane_basis((0.0, 0.0, -1.0))
    d = dexterity(arm, c.q, (0.0, 0.0, -1.0), ws.reach, B)
    assert float(d) == pytest.approx(c.dexterity, rel=1e-12)
    J = kinematics.jacobian(arm, c.q)
    A = np.vstack([J[:3], J[3:5]])  # tilts about x and y: the axis is z
    qd = np.linalg.pinv(A, rcond=1e-9) @ np.concatenate([B[:, 0], [0.0, 0.0]])
    np.testing.assert_allclose(J[:3] @ qd, B[:, 0], atol=1e-9)  # the tool moves as asked
    np.testing.assert_allclose(J[3:5] @ qd, 0.0, atol=1e-9)  # without tilting


def test_defaults_on_an_arm_that_is_not_the_seeds(arm):
    """The 5-DOF arm on a 1 cm higher base column (other kinematics: no preset — the same arm under
    another name, or with other masses, keeps the paper's task): seed 004's capsule scaled
    to 0.4 × the reach, in a plane through a well-conditioned posture, the tool down; V =
    0.10 m/s × the path's length / the seed's, V_bounds (V/10, 10 V); the build follows it
    exactly."""
    from legcore.robots import build_robot
    from legcore.studies.path_tracking.defaults import SEED_PATH_LENGTH, capsule

    seed = capsule(0.6)  # the seed's capsule, centred: its arcs about (±0.2, 0) m, r 0.1 m
    for mine, ref in zip(seed, STUDY.preset.params["segments"], strict=True):
        got = mine.model_dump()
        for key in ("center", "start", "end"):
            if key in got:
                np.testing.assert_allclose(np.add(got[key], (0.0, 0.3)), ref[key], atol=1e-15)
    renamed = build_robot(arm.spec.model_copy(update={"name": "my_arm"}))
    assert STUDY.task(renamed, Params()).preset is not None  # the same kinematics
    joints = [arm.spec.joints[0].model_copy(update={"d": arm.spec.joints[0].d + 0.01}),
              *arm.spec.joints[1:]]
    other = build_robot(arm.spec.model_copy(update={"name": "my_arm", "joints": joints}))
    task = STUDY.task(other, Params())
    p = task.params
    assert task.preset is None and p.orientation == "down"
    assert set(task.rules) >= {"segments", "plane_origin", "plane_e1", "plane_e2", "rest", "V",
                               "V_bounds", "orientation"}
    across = p.segments[0].center[0] - p.segments[2].center[0] + 2 * p.segments[0].r
    assert across == pytest.approx(0.4, abs=1e-3)  # 0.4 × the reach (1.0 m)
    pr = STUDY.build(other, Params(n_samples=100))
    assert p.V == pytest.approx(float(f"{0.1 * pr.path.length / SEED_PATH_LENGTH:.3g}"))
    assert p.V_bounds == pytest.approx((p.V / 10, 10 * p.V), rel=1e-2)
    assert pr.joints.path_error < 1e-8 and pr.rest.tolist() == pytest.approx(list(p.rest))
    sol = pr.solution(pr.seed_x())
    assert sol.metrics["feasible"] == 1.0 and not pr.violations(pr.seed_x())
    with pytest.raises(ValueError, match=r"^segments\.0: tool point .* beyond its reach"):
        STUDY.build(other, Params(plane_origin=(3.0, 0.0, 0.5), plane_e1=(1.0, 0.0, 0.0),
                                  plane_e2=(0.0, 1.0, 0.0), orientation="down",
                                  segments=STUDY.preset.params["segments"]))
