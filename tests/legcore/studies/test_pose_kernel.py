"""The compiled body-pose IK of closed-form tripods equals its numpy formulation (issue 23):
:func:`body_pose_ik` and :func:`pose_workspace` against :func:`body_pose_ik_reference` — the same
reachability everywhere, the same NaNs, joint angles within 1e-12 rad (numpy's SIMD arctan2 may
differ from libm's by an ulp) — on seed 002's tripods, and on a parametric hexapod whose limits
exercise the behind-the-yaw-axis family and the knee-down fallback of ``knee="either"``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from legcore.robots import catalog
from legcore.studies.hexapod_workspace.geometry import (
    PoseWorkspace,
    Tripod,
    body_pose_ik,
    body_pose_ik_reference,
    pose_workspace,
    tripod_from_robot,
)
from legcore.studies.hexapod_workspace.problem import Params
from legcore.studies.hexapod_workspace.robot import HexapodGeometry, parametric_hexapod
from legcore.studies.hexapod_workspace.study import build

ATOL = 1e-12  # rad


def _tripod(which: str) -> Tripod:
    if which.startswith("seed002"):
        return tripod_from_robot(catalog.get("citedi_hexapod"), which[-3:])
    # coxa free all round (feet behind the yaw axis), femur kept low (knee-up fails, down not)
    g = HexapodGeometry(q_min=(-math.pi, -1.5, -2.5), q_max=(math.pi, -0.2, 2.5))
    return tripod_from_robot(parametric_hexapod(g), "246")


def _assert_same(got: tuple[np.ndarray, np.ndarray], want: tuple[np.ndarray, np.ndarray]) -> None:
    (q, ok), (q_ref, ok_ref) = got, want
    assert q.shape == q_ref.shape and ok.shape == ok_ref.shape
    np.testing.assert_array_equal(ok, ok_ref)
    np.testing.assert_array_equal(np.isnan(q), np.isnan(q_ref))
    np.testing.assert_allclose(q, q_ref, rtol=0.0, atol=ATOL, equal_nan=True)


@pytest.mark.parametrize("which", ["seed002_135", "seed002_246", "wide"])
@pytest.mark.parametrize("knee", ["up", "down", "either"])
@pytest.mark.parametrize("seed", [0, 1])
def test_body_pose_ik_equals_the_numpy_reference(which: str, knee: str, seed: int) -> None:
    tri = _tripod(which)
    rng = np.random.default_rng(seed)
    q_feet = np.column_stack((rng.uniform(-0.4, 0.4, 3), rng.uniform(-0.5, -0.3, 3),
                              rng.uniform(-0.9, -0.6, 3)))
    feet = tri.feet(q_feet)
    span = 0.12 if which == "wide" else 0.04
    shape = (40, 250)  # a batch of two axes
    x, y = rng.uniform(-span, span, shape), rng.uniform(-span, span, shape)
    yaw = rng.uniform(-math.pi, math.pi, shape) if which == "wide" else rng.uniform(-0.6, 0.6,
                                                                                  shape)
    got = body_pose_ik(tri, feet, x, y, yaw, knee=knee)
    want = body_pose_ik_reference(tri, feet, x, y, yaw, knee=knee)
    _assert_same(got, want)
    ok = want[1]
    assert ok.any() and not ok.all()
    if which == "wide":  # the branches the kernel must reproduce were taken
        q = want[0]
        assert (np.abs(q[..., 0]) > math.pi / 2).any()            # foot behind the yaw axis
        if knee == "either":
            assert (q[..., 2] > 0.0).any()                          # knee-down fallback


def test_body_pose_ik_broadcasts_like_the_reference() -> None:
    tri = _tripod("seed002_135")
    problem = build(catalog.get("citedi_hexapod"), Params())
    x = np.linspace(-0.02, 0.02, 7)
    got = body_pose_ik(tri, problem.feet_start, x[:, None], x[None, :], 0.1)
    want = body_pose_ik_reference(tri, problem.feet_start, x[:, None], x[None, :], 0.1)
    _assert_same(got, want)
    one = body_pose_ik(tri, problem.feet_start, 0.0, 0.0, 0.0)
    _assert_same(one, body_pose_ik_reference(tri, problem.feet_start, 0.0, 0.0, 0.0))
    assert one[0].shape == (3, 3) and one[1].all()


def _old_masks(reachable: np.ndarray) -> list[list[str]]:
    """The masks as ``PoseWorkspace.summary`` wrote them before (a loop over the cells)."""
    return [["".join("1" if v else "0" for v in row) for row in plane] for plane in reachable]


@pytest.mark.parametrize("knee", ["up", "either"])
def test_pose_workspace_of_seed002_equals_the_numpy_reference(knee: str) -> None:
    problem = build(catalog.get("citedi_hexapod"), Params(knee=knee))
    x, y, yaw = problem.params.pose_grid()
    ws = pose_workspace(problem.tripod, problem.feet_start, x, y, yaw, knee=knee,
                        q_ref=problem.q_stance)
    assert isinstance(ws, PoseWorkspace)
    Yaw, Y, X = np.meshgrid(yaw, y, x, indexing="ij")
    q, ok = body_pose_ik_reference(problem.tripod, problem.feet_start, X, Y, Yaw, knee=knee,
                                   q_ref=problem.q_stance)
    reach = ok.all(axis=-1)
    np.testing.assert_array_equal(ws.reachable, reach)
    assert 0 < reach.sum() < reach.size
    q = np.where(reach[..., None, None], q, np.nan)
    np.testing.assert_array_equal(np.isnan(ws.q), np.isnan(q))
    np.testing.assert_allclose(ws.q, q, rtol=0.0, atol=ATOL, equal_nan=True)
    assert ws.summary()["masks"] == _old_masks(reach)
    assert ws.summary(masks=False).keys() == ws.summary().keys() - {"masks"}
