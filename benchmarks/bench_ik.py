"""Numerical IK along a 2,000-sample path: ``legcore.ik.solve`` vs a per-sample pinocchio DLS loop.

    .venv/bin/python benchmarks/bench_ik.py [--K 2000] [--repeat 5]

Robots: UR5 and Panda from the URDFs of ``example-robot-data`` (built with
``legcore.robots.build_robot({"kind": "urdf", ...})``; the Panda's two finger joints are locked
by making them fixed in the URDF text, the tool is ``panda_hand_tcp``). Without that package the
same arms from their makers' DH tables are used, and the table says so.

Path: the tool poses of a smooth joint motion (sums of sines, inside the limits, away from
singularities), K samples; task ``"pose"`` (position and orientation), accuracy 1e-9 m and
1e-9 rad for every sample, the solver started at the first sample's configuration. Columns:

- ``pinocchio loop``: the obvious alternative — a Python loop over samples, each warm-started
  from the previous solution, damped least squares on Pinocchio
  (``framesForwardKinematics`` + ``computeFrameJacobian`` LOCAL_WORLD_ALIGNED, error
  ``[p* − p; log3(R* Rᵀ)]``, ``Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e`` with λ = 1e-9, full steps) until both
  errors are ≤ 1e-9 (no joint limits, no null-space term);
- ``oracle numpy batch``: ``legcore.ik.dls.ik_dls`` on all K samples at once (numpy, every
  sample iterated together), each seeded with the *exact* solution of its previous sample — the
  best a parallel-in-samples scheme could start from;
- ``legcore.ik.solve``: the compiled continuation (joint limits, rest-posture null space for the
  7-DOF Panda, branch tracking).

Times are the best of ``--repeat`` rounds after a warm-up call (numba compilation excluded); in
each round the loop and ``solve`` run in turn, so a change of load on a shared machine hits both.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from legcore.ik import solve
from legcore.ik.dls import ik_dls
from legcore.kinematics import fk
from legcore.robots import Robot, build_robot
from legcore.transforms import log3

TOL = 1e-9
HALF = math.pi / 2


def _interleaved(fns: list[Callable[[], Any]], repeat: int) -> list[tuple[float, Any]]:
    """Best wall time of each function over ``repeat`` rounds, the functions taking turns in
    every round (so a change of machine load hits all of them alike); one warm-up call each."""
    outs = [fn() for fn in fns]
    best = [math.inf] * len(fns)
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            t0 = time.perf_counter()
            outs[i] = fn()
            best[i] = min(best[i], time.perf_counter() - t0)
    return list(zip(best, outs, strict=True))


def erd_urdf_robot(subpath: str, name: str, tool_frame: str | None) -> Robot | None:
    """A robot from an example-robot-data URDF (finger joints locked), None if not installed."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the tests package
    from tests.robot_files import erd_arm_spec, erd_robots_dir

    root_dir = erd_robots_dir()
    if root_dir is None:
        return None
    return build_robot(erd_arm_spec((root_dir / subpath).read_text(encoding="utf-8"), name,
                                    tool_frame))


def dh_robot(name: str) -> Robot:
    """The same arms from their makers' DH tables (fallback without example-robot-data)."""
    if name == "ur5":
        d = [0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823]
        a = [0.0, -0.425, -0.39225, 0.0, 0.0, 0.0]
        al = [HALF, 0.0, 0.0, HALF, -HALF, 0.0]
        lim = [2 * math.pi, 2 * math.pi, math.pi, 2 * math.pi, 2 * math.pi, 2 * math.pi]
        joints = [{"d": d[i], "a": a[i], "alpha": al[i], "q_min": -lim[i], "q_max": lim[i]}
                  for i in range(6)]
        return build_robot({"kind": "dh", "name": "ur5_dh", "joints": joints})
    a = [0.0, 0.0, 0.0, 0.0825, -0.0825, 0.0, 0.088]
    d = [0.333, 0.0, 0.316, 0.0, 0.384, 0.0, 0.0]
    al = [0.0, -HALF, HALF, HALF, -HALF, HALF, HALF]
    lo = [-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973]
    hi = [2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973]
    joints = [{"d": d[i], "a": a[i], "alpha": al[i], "q_min": lo[i], "q_max": hi[i]}
              for i in range(7)]
    c, s = math.cos(-math.pi / 4), math.sin(-math.pi / 4)
    tool = [[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0.2104], [0, 0, 0, 1]]
    return build_robot({"kind": "dh", "name": "panda_dh", "convention": "modified",
                        "joints": joints, "tool": tool})


def smooth_path(robot: Robot, K: int, center: np.ndarray, seed: int = 0) -> np.ndarray:
    """Joint motion (K, n): three sines of ≤ 0.13 rad each about ``center``, inside the limits."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, K)[:, None]
    c = rng.uniform(-0.13, 0.13, (3, robot.nq))
    q = center + c[0] * np.sin(2 * np.pi * t) + c[1] * np.sin(4 * np.pi * t + 1)
    q = q + c[2] * np.cos(2 * np.pi * t)
    return np.clip(q, robot.q_min, robot.q_max)


def pinocchio_dls_loop(robot: Robot, T: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """Per-sample Python loop of pinocchio DLS, warm-started from the previous solution."""
    model, data, fid = robot.model, robot.data(), robot.tool_frame
    rf = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    lam2 = 1e-18 * np.eye(6)
    q = np.array(q0, dtype=float)
    out = np.full((T.shape[0], robot.nq), np.nan)
    e = np.empty(6)
    for k in range(T.shape[0]):
        p_t, R_t = T[k, :3, 3], T[k, :3, :3]
        for _ in range(100):
            pin.framesForwardKinematics(model, data, q)
            M = data.oMf[fid]
            e[:3] = p_t - M.translation
            e[3:] = pin.log3(R_t @ M.rotation.T)
            if np.linalg.norm(e[:3]) <= TOL and np.linalg.norm(e[3:]) <= TOL:
                out[k] = q
                break
            J = pin.computeFrameJacobian(model, data, q, fid, rf)
            q = q + J.T @ np.linalg.solve(J @ J.T + lam2, e)
    return out


def errors(robot: Robot, q: np.ndarray, T: np.ndarray) -> tuple[float, float]:
    """Max position (m) and rotation (rad) error of FK(q) against T (NaN rows count as inf)."""
    if np.isnan(q).any():
        return math.inf, math.inf
    F = fk(robot, q)
    ep = np.linalg.norm(F[:, :3, 3] - T[:, :3, 3], axis=-1).max()
    er = np.linalg.norm(log3(T[:, :3, :3] @ np.swapaxes(F[:, :3, :3], -1, -2)), axis=-1).max()
    return float(ep), float(er)


CENTERS = {
    "ur5": np.array([0.3, -1.2, 1.5, -1.0, 1.2, 0.3]),
    "panda": np.array([0.0, -0.5, 0.0, -2.0, 0.0, 1.6, 0.8]),
}


def run(name: str, K: int, repeat: int) -> tuple[list[str], str]:
    sub, tool = {
        "ur5": ("ur_description/urdf/ur5_robot.urdf", None),
        "panda": ("panda_description/urdf/panda.urdf", "panda_hand_tcp"),
    }[name]
    robot = erd_urdf_robot(sub, name, tool)
    source = "URDF (example-robot-data)"
    if robot is None:
        robot, source = dh_robot(name), "DH table (example-robot-data not installed)"
    q_path = smooth_path(robot, K, CENTERS[name])
    T = fk(robot, q_path)
    q0 = q_path[0]
    (t_loop, q_loop), (t_ours, sol) = _interleaved(
        [lambda: pinocchio_dls_loop(robot, T, q0),
         lambda: solve(robot, T, "pose", q0=q0, path=True)],
        repeat,
    )
    seeds = np.concatenate([q0[None], q_loop[:-1]])  # oracle: each sample's previous solution
    ((t_np, res),) = _interleaved([lambda: ik_dls(robot, T, seeds, tol=TOL, damping=1e-9)], repeat)
    row = [
        f"{robot.name} ({robot.nq} DOF)", f"{K}",
        f"{t_loop * 1e3:.0f} ms", f"{t_np * 1e3:.1f} ms", f"{t_ours * 1e3:.1f} ms",
        f"{t_loop / t_ours:.0f}×",
        "{:.1e} / {:.1e}".format(*errors(robot, q_loop, T)),
        "{:.1e} / {:.1e}".format(*errors(robot, sol.q, T)),
        f"{sol.iterations.mean():.1f}", f"{int(sol.flip.sum())}",
        f"{int((~res.reachable).sum())}",
    ]
    return row, source


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--K", type=int, default=2000, help="samples along the path")
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    head = ["robot", "K", "pinocchio loop", "oracle numpy batch", "legcore.ik.solve",
            "solve vs loop", "loop err m / rad", "solve err m / rad", "iters/sample",
            "flips", "numpy unconverged"]
    rows, sources = [], []
    for name in ("ur5", "panda"):
        row, source = run(name, args.K, args.repeat)
        rows.append(row)
        sources.append(f"{name}: {source}")
    print(f"machine: {os.cpu_count()} cores, {platform.processor() or platform.machine()}, "
          f"load {os.getloadavg()[0]:.2f}; robots: " + "; ".join(sources))
    print(f"task 'pose', tolerance {TOL:g} m and rad, best of {args.repeat} interleaved runs")
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for row in rows:
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
