"""``hexapod_workspace`` on any hexapod: a parametric hexapod whose defaults are the seed robot,
the same hexapod as DH legs (closed forms) and as generated URDF text (numerical FK/IK), and
robots that are not hexapods refused by name. Seed 002's own robot: ``test_hexapod_workspace.py``
and ``test_hexapod_workspace_run.py``."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import legcore
from legcore.robots import catalog
from legcore.studies.hexapod_workspace.problem import Params
from legcore.studies.hexapod_workspace.study import build

ROBOT = catalog.get("citedi_hexapod")


# ------------------------------------------------------------------------------ any hexapod

GEOMETRY = {
    "link_lengths": (0.03, 0.08, 0.12),
    "hips": {"L1": (0.06, 0.1, 0.0), "L2": (0.08, 0.0, 0.0), "L3": (0.06, -0.1, 0.0),
             "L4": (-0.06, 0.1, math.pi), "L5": (-0.08, 0.0, math.pi),
             "L6": (-0.06, -0.1, math.pi)},
}
GRID = {"pose_x_extent": 0.06, "pose_y_extent": 0.06, "pose_xy_step": 0.004,
        "pose_yaw_step": math.pi / 18}


def test_parametric_defaults_are_the_seed_robot() -> None:
    from legcore.studies.hexapod_workspace.robot import HexapodGeometry

    p = build(ROBOT, Params(hexapod=HexapodGeometry()))
    ref = build(ROBOT, Params())
    X = np.random.default_rng(1).uniform(-0.5, 0.5, (20, 3))
    np.testing.assert_array_equal(p.evaluate(X)[0], ref.evaluate(X)[0])
    assert p.tripod.closed_form and p.robot.name == "parametric_hexapod"


def test_urdf_hexapod_numerical_path_equals_the_closed_form() -> None:
    """The same parametric hexapod as DH legs (leg3 closed forms) and as generated URDF text
    (x forward; numerical FK/IK): same tripod, objectives, motion and pose workspace."""
    from legcore.robots import build_any_robot
    from legcore.studies.hexapod_workspace.robot import (
        HexapodGeometry,
        hexapod_urdf,
        parametric_hexapod,
    )

    g = HexapodGeometry.model_validate(GEOMETRY)
    dh = build(parametric_hexapod(g), Params(**GRID))
    urdf = build(build_any_robot({"kind": "urdf", "name": "hx", "urdf": hexapod_urdf(g),
                                  "legs": "auto"}), Params(**GRID))
    assert dh.tripod.closed_form and not urdf.tripod.closed_form
    assert urdf.tripod.legs == ("L1", "L3", "L5") and urdf.symmetry == dh.symmetry
    np.testing.assert_allclose(urdf.feet_start, dh.feet_start, atol=1e-12)
    X = np.random.default_rng(0).uniform(-0.5, 0.5, (50, 3))
    np.testing.assert_allclose(urdf.evaluate(X)[0], dh.evaluate(X)[0], atol=1e-12)
    a, b = dh.pose_workspace(), urdf.pose_workspace()
    assert a.reachable.sum() > 100 and np.array_equal(a.reachable, b.reachable)
    np.testing.assert_allclose(b.q, a.q, atol=1e-6, equal_nan=True)
    sa, sb = dh.solution(X[3]), urdf.solution(X[3])
    for k in ("beta1", "perimeter", "S_f", "body_dx", "body_dyaw", "exact_reachable"):
        assert sb.metrics[k] == pytest.approx(sa.metrics[k], abs=1e-9), k
    np.testing.assert_allclose(sb.motion.q, sa.motion.q, atol=1e-6)


def test_urdf_hexapod_runs_and_others_are_refused_by_name() -> None:
    from legcore.studies.hexapod_workspace.robot import HexapodGeometry, hexapod_urdf

    text = hexapod_urdf(HexapodGeometry.model_validate(GEOMETRY))
    spec = {"robot": {"kind": "urdf", "name": "hx", "urdf": text, "legs": "auto"},
            "problem": {"kind": "hexapod_workspace", "paper_baselines": False, **GRID},
            "optimizer": {"kind": "moead", "params": {"n_subproblems": 30}},
            "budget": {"generations": 5}, "seed": 3}
    r = legcore.run(spec)
    json.dumps(r.to_dict(), allow_nan=False)
    assert set(r.baselines) == {"start", "straight_walk"}
    assert r.extras["pose_workspace"]["n_reachable"][len(r.extras["pose_workspace"]["yaw"]) // 2]
    from legcore.runner import prepare

    with pytest.raises(ValueError, match="^robot: hexapod_workspace needs 6 legs of 3 joints; "
                                         "robot animatronic_quadruped has 4 legs$"):
        prepare({"robot": "animatronic_quadruped", "problem": {"kind": "hexapod_workspace"}})
