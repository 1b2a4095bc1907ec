"""Issue 23: the first run on a fresh clone, and the first submission to a fresh API.

Two figures a new user meets before any other:

1. **First `legopt run` after the install step.** Private, empty caches (``NUMBA_CACHE_DIR``,
   ``LEGOPT_CACHE_DIR``); the install step ``python -m legcore.warmup`` (what ``python3 run.py``
   runs once after creating the virtualenv) fills the kernel cache; then ``legopt run`` of a
   URDF-leg job (example-robot-data's Solo-12 front-left leg, the swing study with its
   robot-derived defaults) in a fresh process, then the same again (the warm run). Goal: first
   ≤ 1.5× warm. The row "no install step" is the same first run with an empty kernel cache:
   what the issue measured (36–43 s).
2. **First ``POST /jobs`` on a fresh API.** A fresh embedded service (new data directory, new
   SQLite file; the kernel cache of part 1 as the install step leaves it), ``uvicorn`` started
   and ready (``/api/v1/ready``: 503 while it warms its validation processes,
   ``services/api/warmup.py``; the time from start to ready is reported); then the first
   submission of each of: the URDF leg, a
   path-placement job (``examples/001_path_placement_jar.yaml``, which took 126 s before issue
   23) and seed 000, each timed, then each submitted again (the warm figure). Goal: < 1 s.

Wall times in seconds, one process per row (medians of ``--repeats`` for the warm figures),
``NUMBA_NUM_THREADS=1``.

    python benchmarks/bench_first_run.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import platform
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx
import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.robot_files import ERD_URDF, erd_robots_dir  # noqa: E402


def leg_spec() -> dict[str, Any]:
    """The URDF-leg job: Solo-12's front-left leg (inline URDF), the swing study's defaults."""
    root = erd_robots_dir()
    if root is None:
        raise SystemExit("example-robot-data is not installed (it is in requirements.lock)")
    urdf = (root / ERD_URDF["solo12"]).read_text()
    return {
        "robot": {"kind": "urdf", "name": "solo12_leg", "urdf": urdf, "legs": "auto",
                  "leg": "FL"},
        "problem": {"kind": "swing_energy"},
        "seed": 1,
        "record": False,
    }  # fmt: skip


def _env(caches: Path, **extra: str) -> dict[str, str]:
    return {
        **os.environ,
        "NUMBA_NUM_THREADS": "1",
        "NUMBA_CACHE_DIR": str(caches / "numba"),
        "LEGOPT_CACHE_DIR": str(caches / "results"),
        **extra,
    }


def timed(cmd: list[str], env: dict[str, str]) -> float:
    """Wall seconds of ``cmd`` (must succeed)."""
    t0 = time.perf_counter()
    out = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if out.returncode:
        raise SystemExit(f"{' '.join(cmd[:4])} failed ({out.returncode}):\n{out.stderr[-2000:]}")
    return dt


def legopt_run(spec_file: Path, caches: Path, out: Path) -> float:
    cmd = [sys.executable, "-m", "services.cli", "run", str(spec_file), "--out", str(out), "-q"]
    return timed(cmd, _env(caches))


def first_run(tmp: Path, repeats: int) -> list[tuple[str, float]]:
    spec_file = tmp / "leg.yaml"
    spec_file.write_text(yaml.safe_dump(leg_spec()))
    cold = legopt_run(spec_file, tmp / "cold", tmp / "out-cold")
    caches = tmp / "installed"
    install = timed([sys.executable, "-m", "legcore.warmup"], _env(caches))
    first = legopt_run(spec_file, caches, tmp / "out-first")
    warm = statistics.median(
        legopt_run(spec_file, caches, tmp / f"out-warm{i}") for i in range(repeats)
    )
    return [
        ("install step (`python -m legcore.warmup`, once per machine)", install),
        ("first `legopt run`, no install step (empty kernel cache)", cold),
        ("first `legopt run` after the install step", first),
        (f"warm `legopt run` (median of {repeats})", warm),
    ]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def first_posts(tmp: Path, caches: Path, repeats: int) -> list[tuple[str, float, float]]:
    data = tmp / "api-data"
    data.mkdir()
    env = _env(
        caches,
        LEGOPT_DATA_DIR=str(data),
        LEGOPT_DATABASE_URL=f"sqlite:///{data / 'legopt.db'}",
        LEGOPT_BROKER_URL="filesystem://",
        LEGOPT_ARTIFACT_DIR=str(data / "artifacts"),
    )
    cli = [sys.executable, "-m", "services.cli"]
    subprocess.run([*cli, "db", "upgrade"], cwd=ROOT, env=env, check=True, capture_output=True)
    made = subprocess.run([*cli, "keys", "create", "--name", "bench"], cwd=ROOT, env=env,
                          check=True, capture_output=True, text=True)  # fmt: skip
    key = made.stdout.strip().splitlines()[-1]
    port = _free_port()
    api = subprocess.Popen(
        [sys.executable, "-m", "uvicorn", "services.api.app:app", "--host", "127.0.0.1",
         "--port", str(port), "--log-level", "warning"],
        cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    url = f"http://127.0.0.1:{port}/api/v1"
    specs = {
        "URDF leg (Solo-12 FL, swing)": leg_spec(),
        "path placement (examples/001, jar)": yaml.safe_load(
            (ROOT / "examples" / "001_path_placement_jar.yaml").read_text()
        ),
        "seed 000 swing (examples/000)": yaml.safe_load(
            (ROOT / "examples" / "000_swing_energy_flat.yaml").read_text()
        ),
    }
    rows = []
    started = time.perf_counter()
    try:
        with httpx.Client(headers={"X-API-Key": key}, timeout=600) as c:
            while True:  # ready: wait on the API itself, not a fixed sleep
                try:
                    ready = c.get(f"{url}/ready")
                    if ready.status_code == 200:
                        warm = ready.json().get("warmup_s") or 0.0
                        rows.append(("(start → /ready; of which warm-up)",
                                     time.perf_counter() - started, warm))  # fmt: skip
                        break
                except httpx.HTTPError:
                    pass
                if api.poll() is not None:
                    raise SystemExit("the API exited at start")
                time.sleep(0.1)

            def post(spec: dict[str, Any]) -> float:
                t0 = time.perf_counter()
                resp = c.post(f"{url}/jobs", json=spec)
                dt = time.perf_counter() - t0
                if resp.status_code not in (201, 202):
                    raise SystemExit(f"POST /jobs: {resp.status_code} {resp.text[:500]}")
                return dt

            for name, spec in specs.items():
                first = post(spec)
                again = statistics.median(post({**spec, "seed": 100 + i}) for i in range(repeats))
                rows.append((name, first, again))
    finally:
        api.terminate()
        api.wait(30)
    return rows


def machine() -> str:
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, "
            f"load {load:.1f} at the end")  # fmt: skip


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=3, help="warm repeats (medians)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="legopt-first-run-") as tmp_name:
        tmp = Path(tmp_name)
        runs = first_run(tmp, args.repeats)
        posts = first_posts(tmp, tmp / "installed", args.repeats)
    warm = runs[-1][1]
    print("| `legopt run` of a URDF-leg job | wall s | × warm |")
    print("|---|---|---|")
    for label, s in runs:
        print(f"| {label} | {s:.2f} | {s / warm:.2f}× |")
    print()
    print("| `POST /jobs` on a fresh API | first s | again s (median) |")
    print("|---|---|---|")
    start_row, *posts = posts
    print(
        f"| API start → `/ready` s; of which the validation warm-up s | {start_row[1]:.1f} | "
        f"{start_row[2]:.1f} |"
    )
    for name, first, again in posts:
        print(f"| {name} | {first:.3f} | {again:.3f} |")
    print(f"\nMachine: {machine()}.")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
