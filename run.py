#!/usr/bin/env python3
"""One entry point for a fresh clone: creates `.venv`, installs the lock, runs a task.

    python3 run.py demo          # the main job on the embedded default (no Redis/Postgres)
    python3 run.py test [ARGS]   # the test suite (ARGS go to pytest)
    python3 run.py bench         # the benchmark scripts in benchmarks/
    python3 run.py legopt ARGS   # any `legopt` command inside the environment

Only the standard library is used here, so it runs on a bare Python 3.11.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
LOCK = ROOT / "requirements.lock"
STAMP = VENV / ".legopt-installed"


def _venv_bin(name: str) -> Path:
    return VENV / ("Scripts" if os.name == "nt" else "bin") / name


def _fingerprint() -> str:
    h = hashlib.sha256()
    for f in (LOCK, ROOT / "pyproject.toml"):
        h.update(f.read_bytes())
    return h.hexdigest()


def ensure_env() -> None:
    """Create the virtual environment and install the locked dependencies (idempotent)."""
    if sys.version_info[:2] != (3, 11):
        sys.exit(f"run.py: Python 3.11 is required, this is {sys.version.split()[0]}")
    if not _venv_bin("python").exists():
        print("run.py: creating .venv", flush=True)
        venv.EnvBuilder(with_pip=True).create(VENV)
    want = _fingerprint()
    if STAMP.exists() and STAMP.read_text() == want:
        return
    py = str(_venv_bin("python"))
    pip = [py, "-m", "pip", "--disable-pip-version-check", "-q"]
    print("run.py: installing locked dependencies (first run takes a minute)", flush=True)
    subprocess.run([*pip, "install", "-r", str(LOCK)], check=True)
    subprocess.run([*pip, "install", "--no-deps", "-e", str(ROOT)], check=True)
    STAMP.write_text(want)


def main(argv: list[str]) -> int:
    task, *rest = argv or ["help"]
    if task in {"help", "-h", "--help"}:
        print(__doc__)
        return 0
    ensure_env()
    py = str(_venv_bin("python"))
    if task == "test":
        cmd = [py, "-m", "pytest", *rest]
    elif task == "demo":
        cmd = [str(_venv_bin("legopt")), "demo", *rest]
    elif task == "bench":
        cmd = [py, str(ROOT / "benchmarks" / "run_all.py"), *rest]
    elif task == "legopt":
        cmd = [str(_venv_bin("legopt")), *rest]
    else:
        print(f"run.py: unknown task {task!r}\n{__doc__}", file=sys.stderr)
        return 2
    return subprocess.run(cmd, cwd=ROOT).returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
