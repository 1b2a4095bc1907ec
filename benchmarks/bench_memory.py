"""Issue 12: predicted vs measured peak memory of seed 000 jobs, chunked and unchunked.

Each size runs in a fresh process: ``job_size(prepare(spec)).peak_bytes`` (the prediction the
service's size check uses), then the whole ``legcore.run`` (3 generations — the peak is reached
in the first — and 2-generation baseline GAs: the same arrays as the seed's 100), then the
process's peak RSS (``VmHWM`` of /proc/self/status). "unchunked" reruns the job with a 1 TiB
evaluation budget (``LEGOPT_EVAL_MEMORY_MB``): the whole population in one batch, as before.

    python benchmarks/bench_memory.py [--quick]
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SIZES = [(100, 0.01), (300, 0.005), (1000, 0.002), (2000, 0.001), (2000, 0.0005)]

CHILD = r"""
import json, sys, time
import yaml
import legcore
from legcore.memory import bytes_per_sample, chunk_rows
from legcore.runner import job_size, prepare
spec = json.loads(sys.argv[1])
prepared = prepare(spec)
size = job_size(prepared)
t0 = time.perf_counter()
legcore.run(spec)
# VmHWM: this process image's peak RSS (ru_maxrss would also count the forking parent's)
hwm = next(ln for ln in open("/proc/self/status") if ln.startswith("VmHWM:"))
print(json.dumps({"predicted": size.peak_bytes, "samples": size.samples,
                  "rss": int(hwm.split()[1]) * 1024,
                  "bps": bytes_per_sample(prepared.problem),
                  "chunk": chunk_rows(prepared.problem), "wall": time.perf_counter() - t0}))
"""


def measure(pop: int, dt: float, budget_mb: float | None) -> dict[str, float]:
    spec = {"problem": {"kind": "swing_energy", "dt": dt, "baseline_generations": 2},
            "optimizer": {"kind": "ga", "params": {"pop_size": pop}},
            "budget": {"generations": 3}, "seed": 1}
    env = {**os.environ, "NUMBA_NUM_THREADS": "1"}
    if budget_mb is not None:
        env["LEGOPT_EVAL_MEMORY_MB"] = str(budget_mb)
    out = subprocess.run([sys.executable, "-c", CHILD, json.dumps(spec)], cwd=ROOT, env=env,
                         check=True, capture_output=True, text=True).stdout
    result: dict[str, float] = json.loads(out.strip().splitlines()[-1])
    return result


def main() -> int:
    quick = "--quick" in sys.argv
    mib = 1024**2
    print("| population × samples | bytes/sample | chunk rows | predicted peak | measured peak | "
          "measured / predicted | unchunked measured | wall (chunked) |")
    print("|---|---|---|---|---|---|---|---|")
    for pop, dt in SIZES[:2] if quick else SIZES:
        c = measure(pop, dt, None)
        u = measure(pop, dt, 1024 * 1024)
        print(f"| {pop} × {int(c['samples'])} | {c['bps']:.0f} B | {int(c['chunk'])} | "
              f"{c['predicted'] / mib:.0f} MiB | {c['rss'] / mib:.0f} MiB | "
              f"{c['rss'] / c['predicted']:.2f} | {u['rss'] / mib:.0f} MiB | {c['wall']:.1f} s |",
              flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
