"""Issue 12: the first job of a fresh worker process, cold and warm, vs a warm one.

The seed 000 example (``examples/000_swing_energy_flat.yaml``: population 100, 100 generations,
and its three baseline GA runs) in fresh processes with NUMBA_NUM_THREADS=1:

- **cold**: empty numba cache (``NUMBA_CACHE_DIR``) and empty result cache (``LEGOPT_CACHE_DIR``):
  every kernel compiled, the baselines optimised — a new container before issue 12;
- **kernels warm**: the numba cache filled (by the cold run, as ``python -m legcore.warmup``
  does at image build), the baselines not cached;
- **warm caches**: both caches filled — a fresh worker of an image with issue 12;
- **fresh worker**: both caches filled and ``legcore.warmup.warm_up()`` run at process start, as
  a worker does before its first job (``Settings.worker_warmup``, ``services.worker.celery_app``);
- **second job**: the same job again in the cold run's process (kernels in memory, baselines in
  the in-process cache): the warm reference.

CPU = ``time.process_time()`` of the job (``legcore.run``), imports (and the warm-up) timed
apart; every figure is the median of 3 processes (the warm reference: of jobs 2–4 of the cold
process).

    python benchmarks/bench_warm_start.py
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "examples" / "000_swing_energy_flat.yaml"
REPEATS = 3  # processes per warm row (medians); the cold row runs once (a full compile)

CHILD = r"""
import json, sys, time
t0, c0 = time.perf_counter(), time.process_time()
import yaml
import legcore
from legcore.runner import run
spec = yaml.safe_load(open(sys.argv[1]))
spec["record"] = False
if sys.argv[3] == "1":
    from legcore.warmup import warm_up
    warm_up(verbose=False)
imports = (time.perf_counter() - t0, time.process_time() - c0)
jobs = []
for _ in range(int(sys.argv[2])):
    t0, c0 = time.perf_counter(), time.process_time()
    run(spec)
    jobs.append((time.perf_counter() - t0, time.process_time() - c0))
print(json.dumps({"imports": imports, "jobs": jobs}))
"""


def child(numba_dir: Path, results_dir: Path, jobs: int, preload: bool = False
          ) -> dict[str, list[float]]:
    env = {**os.environ, "NUMBA_NUM_THREADS": "1", "NUMBA_CACHE_DIR": str(numba_dir),
           "LEGOPT_CACHE_DIR": str(results_dir)}
    cmd = [sys.executable, "-c", CHILD, str(SPEC), str(jobs), str(int(preload))]
    out = subprocess.run(cmd, cwd=ROOT, env=env, check=True, capture_output=True,
                         text=True).stdout
    result: dict[str, list[float]] = json.loads(out.strip().splitlines()[-1])
    return result


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        numba_dir, results = root / "numba", root / "res"
        cold = child(numba_dir, results, 1 + REPEATS)
        kernels = [child(numba_dir, root / f"res{i}", 1) for i in range(REPEATS)]
        warm = [child(numba_dir, results, 1) for _ in range(REPEATS)]
        worker = [child(numba_dir, results, 1, preload=True) for _ in range(REPEATS)]
    ref_wall = statistics.median(j[0] for j in cold["jobs"][1:])
    ref_cpu = statistics.median(j[1] for j in cold["jobs"][1:])
    rows = [
        ("cold: empty caches (a new container before issue 12)", [cold]),
        ("kernels cached, baselines not cached", kernels),
        ("kernels and baselines cached", warm),
        ("fresh worker (issue 12): caches + warm-up at start", worker),
    ]
    print("| process | start (imports, warm-up) wall / CPU | first job wall | first job CPU | "
          "CPU / warm job |")
    print("|---|---|---|---|---|")
    for label, runs in rows:
        iw = statistics.median(r["imports"][0] for r in runs)
        ic = statistics.median(r["imports"][1] for r in runs)
        wall = statistics.median(r["jobs"][0][0] for r in runs)
        cpu = statistics.median(r["jobs"][0][1] for r in runs)
        print(f"| {label} | {iw:.2f} s / {ic:.2f} s | {wall:.2f} s | {cpu:.2f} s | "
              f"{cpu / ref_cpu:.2f}× |")
    print(f"| warm job: jobs 2–{1 + REPEATS} of the cold process | — | {ref_wall:.2f} s | "
          f"{ref_cpu:.2f} s | 1.00× |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
