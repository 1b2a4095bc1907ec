"""What a ``hexapod_workspace`` result reports besides its front: the stance at t, the front's
stability split and body poses, Fig. 8's workspaces (the front's and its mirrors), the
hypervolume and the exact pose workspace. It reads the problem through
:class:`WorkspaceProblem` (the problem imports this module: a protocol, not an import)."""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from legcore.metrics import hypervolume
from legcore.studies.hexapod_workspace.geometry import (
    OTHER_STANCE,
    PoseWorkspace,
    Tripod,
    mirror_front_back,
    mirror_left_right,
)
from legcore.studies.hexapod_workspace.params import Params

__all__ = ["WorkspaceProblem", "extras", "mirrored_workspace"]

FloatArray = NDArray[np.float64]


class WorkspaceProblem(Protocol):
    """The tripod problem as its report reads it (documented on
    :class:`~legcore.studies.hexapod_workspace.problem.HexapodWorkspaceProblem`)."""

    params: Params
    tripod: Tripod
    stance_legs: dict[str, tuple[str, ...]]
    theta_start: FloatArray
    theta2: float
    theta3: float
    feet_start: FloatArray
    beta1_0: float
    beta5_0: float
    perimeter_0: float
    S_start: FloatArray
    symmetry: dict[str, bool]

    def feet(self, theta1: FloatArray) -> FloatArray:
        """Feet (..., 3, 3) m at t+1 in the body frame for coxa angles θ1 (..., 3) rad."""
        ...

    def front_report(self, X: FloatArray) -> dict[str, Any]:
        """Per-point data of a front X (k, 3)."""
        ...

    def pose_workspace(self) -> PoseWorkspace:
        """The exact body-pose workspace on the parameters' grid."""
        ...


def extras(problem: WorkspaceProblem, front_X: FloatArray, front_F: FloatArray) -> dict[str, Any]:
    """What a result reports of the study (see
    :meth:`~legcore.studies.hexapod_workspace.problem.HexapodWorkspaceProblem.extras`)."""
    p = problem.params
    X = np.asarray(front_X, dtype=float).reshape(-1, 3)
    k = X.shape[0]
    rep = problem.front_report(X) if k else None
    out: dict[str, Any] = {
        "legs": list(problem.tripod.legs),
        "units": {"theta1": "rad", "f1_beta1": "rad", "f2_beta5": "rad",
                  "f3_perimeter": "m", "pose": "(m, m, rad)", "S": "m"},
        "stance_t": {
            "theta1": problem.theta_start.tolist(), "theta2": problem.theta2,
            "theta3": problem.theta3, "feet": problem.feet_start.tolist(),
            "beta1": problem.beta1_0, "beta5": problem.beta5_0, "perimeter": problem.perimeter_0,
            "S_f": float(problem.S_start[0]), "S_b": float(problem.S_start[1]),
        },
    }
    if rep is None:
        out["front"] = {"n": 0}
        out["stability_split"] = {"mode": p.stability, "n_front": 0, "n_stable": 0,
                                  "n_unstable": 0}
    else:
        stable = rep["stable"]
        out["front"] = {
            "n": k,
            "theta1": X.tolist(),
            "F": rep["F"].tolist(),
            "S_f": rep["S"][:, 0].tolist(),
            "S_b": rep["S"][:, 1].tolist(),
            "stable": stable.tolist(),
            "body_pose": rep["pose"].tolist(),
            "foot_slip_max": rep["slip"].max(axis=1).tolist(),
            "exact_reachable": rep["exact_reachable"].tolist(),
        }
        out["stability_split"] = {
            "mode": p.stability,
            "n_front": k,
            "n_stable": int(stable.sum()),
            "n_unstable": int((~stable).sum()),
            "fraction_stable": float(stable.mean()),
            "unstable_index": np.flatnonzero(~stable).tolist(),
        }
        out["workspace"] = mirrored_workspace(problem, X, rep)
        ref = np.asarray(p.hv_ref(), dtype=float)
        hv = hypervolume(np.asarray(front_F, dtype=float).reshape(-1, 3), ref)
        out["hypervolume"] = {"value": hv.value, "ref_point": list(hv.ref_point),
                              "normalised": hv.value / float(np.prod(ref)),
                              "n_points": hv.n_points}
    ws = problem.pose_workspace()
    out["pose_workspace"] = ws.summary()
    if rep is not None:
        out["pose_workspace"]["front_poses_reachable"] = int(rep["exact_reachable"].sum())
    return out

def mirrored_workspace(problem: WorkspaceProblem, X: FloatArray,
                       rep: dict[str, Any] | None = None) -> dict[str, Any]:
    """Fig. 8a (the front's body displacements) and Fig. 8b (with the mirrored solutions).

    ``front``: body poses (k, 3) and body-frame feet at t+1 (k, 3, 2) of the front (the
    paper's Matlab plots move the feet, not the body); ``mirrored``: the front/back mirror
    (same tripod, opposite walking direction), re-evaluated; ``full``: both; ``other_tripod``:
    the left/right mirror — the same front for the other tripod (identical objectives).
    """
    rep = rep or problem.front_report(X)
    out: dict[str, Any] = {"front": {"theta1": X.tolist(), "body_pose": rep["pose"].tolist(),
                                     "feet_xy": problem.feet(X)[..., :2].tolist(),
                                     "stable": rep["stable"].tolist()}}
    if not problem.symmetry["front_back"]:
        out["mirrored"] = None
        out["note"] = "robot hips are not front/back symmetric: no mirrored workspace"
        return out
    Xm = mirror_front_back(X)
    rm = problem.front_report(Xm)
    out["mirrored"] = {"theta1": Xm.tolist(), "body_pose": rm["pose"].tolist(),
                       "feet_xy": problem.feet(Xm)[..., :2].tolist(),
                       "F": rm["F"].tolist(), "stable": rm["stable"].tolist()}
    full_pose = np.vstack((rep["pose"], rm["pose"]))
    full_stable = np.concatenate((rep["stable"], rm["stable"]))
    out["full"] = {
        "body_pose": full_pose.tolist(),
        "stable": full_stable.tolist(),
        "x_range": [float(full_pose[:, 0].min()), float(full_pose[:, 0].max())],
        "y_range": [float(full_pose[:, 1].min()), float(full_pose[:, 1].max())],
        "yaw_range": [float(full_pose[:, 2].min()), float(full_pose[:, 2].max())],
    }
    if problem.symmetry["left_right"]:
        other = OTHER_STANCE[problem.params.stance]
        out["other_tripod"] = {
            "legs": list(problem.stance_legs[other]),
            "theta1": mirror_left_right(X).tolist(),
            "body_pose": (rep["pose"] * np.array([-1.0, 1.0, -1.0])).tolist(),
        }
    return out
