"""Service overhead of one job: ``execute_job`` on the embedded SQLite store vs ``legcore.run``.

For each example, in one process (numba and the study's baselines warmed first), interleaved
A/B/C triples: A = ``legcore.run(spec)``, B = ``execute_job`` of the same spec with
``record: false``, C = ``execute_job`` with ``record: true`` (the ``.rrd`` written too). Each
job is a fresh row in a fresh SQLite database under a temporary data dir, with the default
settings (checkpoint every 5 generations, heartbeat every 15 s). Reports the medians over
``--pairs`` triples, the ratios B/A and C/A (goal: ≤ 1.15× and ≤ 1.3×), the artifact sizes and
the database growth per job.

    python benchmarks/bench_worker_overhead.py [--pairs 7] [--generations 2] [examples/...yaml ...]

``--generations N`` runs every example for N generations instead of its own budget (the tiny
jobs of issue 23: goal ≤ 1.3× at 2 generations).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import yaml  # noqa: E402

EXAMPLES = ("examples/002_hexapod_workspace.yaml", "examples/000_swing_energy_flat.yaml")


def _setup(data_dir: Path) -> Any:
    os.environ["LEGOPT_DATA_DIR"] = str(data_dir)
    os.environ.pop("LEGOPT_DATABASE_URL", None)
    from services.store.migrate import upgrade
    from services.store.session import reset_engine
    from services.store.settings import get_settings

    get_settings.cache_clear()
    reset_engine()
    settings = get_settings()
    upgrade(settings.database_url)
    return settings


def _new_job(spec: dict[str, Any], key_id: str) -> str:
    from services.store import repository as repo
    from services.store.session import session_scope

    with session_scope() as s:
        total = int(spec.get("budget", {}).get("generations") or 0)
        return repo.create_job(s, owner_key_id=key_id, spec=spec, total_generations=total).id


def _artifact_sizes(job_id: str) -> dict[str, int]:
    from services.store import output_queries as oq
    from services.store.session import session_scope

    with session_scope() as s:
        return {a.kind: a.size_bytes for a in oq.list_artifacts(s, job_id)}


def bench(path: str, pairs: int, generations: int | None = None) -> dict[str, Any]:
    import legcore
    from services.store import api_keys
    from services.store.keys import generate_api_key
    from services.store.session import session_scope
    from services.worker.execute import execute_job

    spec = yaml.safe_load((ROOT / path).read_text())
    if generations is not None:
        spec["budget"] = {**spec.get("budget", {}), "generations": generations}
    plain, recorded = {**spec, "record": False}, {**spec, "record": True}
    with tempfile.TemporaryDirectory(prefix="legopt-bench-") as tmp:
        settings = _setup(Path(tmp))
        db = Path(tmp) / "legopt.db"
        with session_scope() as s:
            key = api_keys.create_api_key(s, name="bench", key_hash=generate_api_key()[1]).id
        legcore.run(spec)  # warm: numba, the study's baselines
        for warm in (plain, recorded):
            assert execute_job(_new_job(warm, key), settings).status == "succeeded"
        t_run: list[float] = []
        t_job: list[float] = []
        t_rec: list[float] = []
        sizes: dict[str, int] = {}
        db_before = db.stat().st_size
        for _ in range(pairs):
            t0 = time.perf_counter()
            legcore.run(spec)
            t_run.append(time.perf_counter() - t0)
            job = _new_job(plain, key)
            t0 = time.perf_counter()
            assert execute_job(job, settings).status == "succeeded"
            t_job.append(time.perf_counter() - t0)
            job = _new_job(recorded, key)
            t0 = time.perf_counter()
            assert execute_job(job, settings).status == "succeeded"
            t_rec.append(time.perf_counter() - t0)
            sizes = _artifact_sizes(job)
        db_growth = (db.stat().st_size - db_before) / (2 * pairs)
    run, job_s, rec = (statistics.median(t) for t in (t_run, t_job, t_rec))
    return {
        "example": Path(path).stem,
        "run_s": run,
        "job_s": job_s,
        "rec_s": rec,
        "ratio": job_s / run,
        "ratio_rec": rec / run,
        "rrd_kib": sizes.get("recording", 0) / 1024,
        "result_kib": sizes.get("result", 0) / 1024,
        "db_kib_per_job": db_growth / 1024,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("examples", nargs="*", default=list(EXAMPLES))
    ap.add_argument("--pairs", type=int, default=7, help="interleaved A/B/C triples (>= 5)")
    ap.add_argument("--generations", type=int, default=None,
                    help="run every example for this many generations (default: its own)")
    args = ap.parse_args(argv)
    rows = [bench(p, args.pairs, args.generations) for p in args.examples]
    print(f"{'example':<26} {'run s':>7} {'job s':>7} {'×':>6} {'job+rrd s':>9} {'×':>6} "
          f"{'rrd KiB':>8} {'result KiB':>10} {'db KiB/job':>10}")  # fmt: skip
    for r in rows:
        print(f"{r['example']:<26} {r['run_s']:>7.3f} {r['job_s']:>7.3f} {r['ratio']:>6.2f} "
              f"{r['rec_s']:>9.3f} {r['ratio_rec']:>6.2f} {r['rrd_kib']:>8.0f} "
              f"{r['result_kib']:>10.0f} {r['db_kib_per_job']:>10.0f}")  # fmt: skip
    print(f"\nmedians of {args.pairs} interleaved triples; load average "
          f"{' '.join(f'{v:.2f}' for v in os.getloadavg())}, {os.cpu_count()} CPUs")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
