"""Wall time of every example study at the seed's own settings, on one core.

For each `examples/*.yaml`: the whole `legcore.run` (prepare + optimisation + decoding the best,
the front and the paper's baselines) and the optimiser loop alone, with NUMBA_NUM_THREADS=1.
Run in a fresh process per study so numba compilation is counted once, as a worker would see it
(the first job on a fresh worker), plus a second, warm run.

    python benchmarks/bench_studies.py
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, sys, time
import yaml
import legcore
from legcore.runner import prepare
spec = yaml.safe_load(open(sys.argv[1]))
out = {}
for label in ("cold", "warm"):
    t0 = time.perf_counter()
    r = legcore.run(spec)
    out[label] = time.perf_counter() - t0
    out[label + "_opt"] = r.optimizer["elapsed_s"]
out["gens"] = r.optimizer["n_gen"]
out["evals"] = r.optimizer["n_evals"]
out["algorithm"] = r.optimizer["kind"]
print(json.dumps(out))
"""


def main() -> int:
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1")
    rows = []
    for spec in sorted((ROOT / "examples").glob("*.yaml")):
        res = subprocess.run(
            [sys.executable, "-c", CHILD, str(spec)],
            env=env, cwd=ROOT, capture_output=True, text=True, check=True,
        )  # fmt: skip
        rows.append((spec.stem, json.loads(res.stdout.strip().splitlines()[-1])))
    print(f"{'example':<34} {'algo':<6} {'gens':>5} {'evals':>7} {'run cold s':>10} "
          f"{'run warm s':>10} {'optimiser s':>11}")  # fmt: skip
    for name, r in rows:
        print(f"{name:<34} {r['algorithm']:<6} {r['gens']:>5} {r['evals']:>7} {r['cold']:>10.2f} "
              f"{r['warm']:>10.2f} {r['warm_opt']:>11.2f}")  # fmt: skip
    print("\nrun = legcore.run (prepare, optimise, decode best/front/baselines); optimiser = the "
          "generations alone; one core (NUMBA_NUM_THREADS=1)")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
