"""Batched inverse dynamics vs a plain Python loop over ``pinocchio.rnea``, in the same run.

    .venv/bin/python benchmarks/bench_dynamics.py [--repeat 5] [--large 1000]

For ``calderon_leg`` and ``puma560``, random joint trajectories of B × K samples (K = 300):
samples per second of the per-sample pinocchio loop (the reference), the serial numba kernel and
the default batched call (multi-threaded for large batches), with their ratios to the loop and
the max |difference| from the loop (N·m). Times are the best of ``--repeat`` runs after a warm-up
call (numba compilation excluded; the loop is timed once per repeat as well).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numba
import numpy as np

from legcore.dynamics import inverse_dynamics, inverse_dynamics_reference
from legcore.robots import catalog

K = 300


def _best(fn: Callable[[], np.ndarray], repeat: int) -> tuple[float, np.ndarray]:
    best = float("inf")
    out = fn()
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def run(robot_name: str, B: int, repeat: int) -> dict[str, float]:
    robot = catalog.get(robot_name)
    rng = np.random.default_rng(0)
    q = rng.uniform(robot.q_min, robot.q_max, (B, K, robot.nq))
    qd = rng.uniform(-2.0, 2.0, q.shape)
    qdd = rng.uniform(-5.0, 5.0, q.shape)
    inverse_dynamics(robot, q[:1], qd[:1], qdd[:1])  # compile / load the numba cache
    loop_repeat = max(1, repeat if B * K <= 50_000 else 1)
    t_loop, ref = _best(lambda: inverse_dynamics_reference(robot, q, qd, qdd), loop_repeat)
    t_ser, ser = _best(lambda: inverse_dynamics(robot, q, qd, qdd, parallel=False), repeat)
    t_bat, bat = _best(lambda: inverse_dynamics(robot, q, qd, qdd), repeat)
    n = B * K
    return {
        "loop": n / t_loop,
        "serial": n / t_ser,
        "batched": n / t_bat,
        "diff": float(max(np.abs(ser - ref).max(), np.abs(bat - ref).max())),
        "identical": float(np.array_equal(ser, bat)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--large", type=int, default=1000, help="B of the large batch")
    args = parser.parse_args()
    print(f"numba threads: {numba.get_num_threads()}, K = {K} samples per trajectory")
    header = (
        f"{'robot':<14}{'B x K':>12}{'loop [S/s]':>13}{'serial [S/s]':>14}"
        f"{'batched [S/s]':>15}{'serial/loop':>13}{'batched/loop':>14}{'max|diff| N·m':>15}"
    )
    print(header)
    print("-" * len(header))
    for name in ("calderon_leg", "puma560"):
        for B in (100, args.large):
            r = run(name, B, args.repeat)
            print(
                f"{name:<14}{f'{B} x {K}':>12}{r['loop']:>13.3g}{r['serial']:>14.3g}"
                f"{r['batched']:>15.3g}{r['serial'] / r['loop']:>12.1f}x"
                f"{r['batched'] / r['loop']:>13.1f}x{r['diff']:>15.1e}"
            )
            assert r["identical"] == 1.0, "serial and parallel kernels differ"
            assert r["diff"] < 1e-9, "fast path disagrees with pinocchio.rnea"


if __name__ == "__main__":
    main()
