"""Batched FK + Jacobian (numba) vs a plain Python loop over Pinocchio, in the same run.

    .venv/bin/python benchmarks/bench_kinematics.py [--B 100] [--repeat 5]

For ``calderon_leg`` and ``puma560``, random joint trajectories of B × K samples (default
100 × 300 = 3·10⁴): samples per second of

- the reference loop: per sample ``pinocchio.framesForwardKinematics`` + ``computeFrameJacobian``
  (LOCAL_WORLD_ALIGNED at the tool frame), and for FK alone ``framesForwardKinematics``;
- ``legcore.kinematics.fk_jacobian`` / ``fk`` on the whole (B, K, n) array (one numba pass);

with the speed-up and the max |difference| of the tool pose and Jacobian entries from the loop.
Times are the best of ``--repeat`` runs after a warm-up call (numba compilation excluded).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import pinocchio as pin

from legcore.kinematics import fk, fk_jacobian
from legcore.robots import Robot, catalog

K = 300


def _best(fn: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    out = fn()
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def loop_fk_jacobian(robot: Robot, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The plain per-sample Pinocchio loop (the reference)."""
    model, data, fid = robot.model, robot.data(), robot.tool_frame
    rf = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    qf = q.reshape(-1, robot.nq)
    T = np.empty((qf.shape[0], 4, 4))
    J = np.empty((qf.shape[0], 6, robot.nq))
    for s in range(qf.shape[0]):
        pin.framesForwardKinematics(model, data, qf[s])
        T[s] = data.oMf[fid].homogeneous
        J[s] = pin.computeFrameJacobian(model, data, qf[s], fid, rf)
    return T, J


def loop_fk(robot: Robot, q: np.ndarray) -> np.ndarray:
    model, data, fid = robot.model, robot.data(), robot.tool_frame
    qf = q.reshape(-1, robot.nq)
    T = np.empty((qf.shape[0], 4, 4))
    for s in range(qf.shape[0]):
        pin.framesForwardKinematics(model, data, qf[s])
        T[s] = data.oMf[fid].homogeneous
    return T


def run(name: str, B: int, repeat: int) -> list[tuple[str, str, float, float, float]]:
    robot = catalog.get(name)
    assert isinstance(robot, Robot)
    rng = np.random.default_rng(0)
    q = rng.uniform(robot.q_min, robot.q_max, (B, K, robot.nq))
    n = B * K
    t_loop, (T_ref, J_ref) = _best(lambda: loop_fk_jacobian(robot, q), repeat)
    t_fast, (T, J) = _best(lambda: fk_jacobian(robot, q), repeat)
    diff = max(
        float(np.abs(T.reshape(-1, 4, 4) - T_ref).max()),
        float(np.abs(J.reshape(-1, 6, robot.nq) - J_ref).max()),
    )
    t_loop_fk, T_ref2 = _best(lambda: loop_fk(robot, q), repeat)
    t_fast_fk, T2 = _best(lambda: fk(robot, q), repeat)
    diff_fk = float(np.abs(T2.reshape(-1, 4, 4) - T_ref2).max())
    return [
        (name, "FK + Jacobian", n / t_loop, n / t_fast, diff),
        (name, "FK only", n / t_loop_fk, n / t_fast_fk, diff_fk),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--B", type=int, default=100, help="trajectories (K = 300 samples each)")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    rows = []
    for name in ("calderon_leg", "puma560"):
        rows.extend(run(name, args.B, args.repeat))
    print(f"B·K = {args.B}·{K} = {args.B * K} samples; best of {args.repeat} runs")
    header = (
        f"{'robot':<14} {'task':<15} {'pinocchio loop':>16} {'numba batched':>16} "
        f"{'speed-up':>9} {'max |diff|':>11}"
    )
    print(header)
    print("-" * len(header))
    for name, task, loop, fast, diff in rows:
        print(
            f"{name:<14} {task:<15} {loop:>14,.0f}/s {fast:>14,.0f}/s {fast / loop:>8.1f}x "
            f"{diff:>11.1e}"
        )


if __name__ == "__main__":
    main()
