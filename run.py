#!/usr/bin/env python3
"""One entry point for a fresh clone: creates `.venv`, installs the lock, runs a task.

    python3 run.py demo          # the main job on the embedded default (no Redis/Postgres)
    python3 run.py test [ARGS]   # the test suite (ARGS go to pytest; see run_tests)
    python3 run.py test --quick  # the quick lane: unit tests without the slow ones
    python3 run.py bench         # the benchmark scripts in benchmarks/
    python3 run.py legopt ARGS   # any `legopt` command inside the environment

The first run installs `requirements.lock` as wheels only, with no dependency resolution (the
lock pins every package) and no up-front byte-compiling, showing one progress line; pip's
output is kept in .venv/install.log.
Only the standard library is used here, so it runs on a bare Python 3.11.
"""

from __future__ import annotations

import hashlib
import os
import re
import subprocess
import sys
import time
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
LOCK = ROOT / "requirements.lock"
STAMP = VENV / ".legopt-installed"
LOG = VENV / "install.log"


def _venv_bin(name: str) -> Path:
    return VENV / ("Scripts" if os.name == "nt" else "bin") / name


def _fingerprint() -> str:
    h = hashlib.sha256()
    for f in (LOCK, ROOT / "pyproject.toml"):
        h.update(f.read_bytes())
    return h.hexdigest()


def locked_packages() -> list[str]:
    """The ``name==version`` lines of the lock (comments and blank lines dropped)."""
    lines = (line.split("#", 1)[0].strip() for line in LOCK.read_text().splitlines())
    return [line for line in lines if line]


def _pip(args: list[str], total: int, what: str) -> None:
    """Run ``pip ARGS`` in the venv with one progress line (``[k/total] name``); the full
    output goes to .venv/install.log, whose tail is printed if pip fails."""
    cmd = [str(_venv_bin("python")), "-m", "pip", "--disable-pip-version-check", *args]
    tty = sys.stdout.isatty()
    done, t0, last = 0, time.monotonic(), 0.0
    with LOG.open("a") as log:
        log.write(f"$ {' '.join(cmd)}\n")
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        assert proc.stdout is not None
        for line in proc.stdout:
            log.write(line)
            m = re.match(r"(Collecting|Obtaining|Processing) (\S+)", line)
            if m:
                done += 1
                name = m.group(2).split("==")[0]
                msg = f"run.py: {what} [{done}/{total}] {name}"
            elif line.startswith("Installing collected packages"):
                msg = f"run.py: {what}: unpacking {done} packages"
            else:
                continue
            now = time.monotonic()
            if tty:
                print(f"\r\033[K{msg} ({now - t0:.0f} s)", end="", flush=True)
            elif now - last > 15 or "unpacking" in msg:
                print(f"{msg} ({now - t0:.0f} s)", flush=True)
                last = now
        code = proc.wait()
    if tty:
        print()
    if code:
        tail = LOG.read_text().splitlines()[-30:]
        print("\n".join(tail), file=sys.stderr)
        sys.exit(f"run.py: pip failed ({what}); full output in {LOG}")


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
    t0 = time.monotonic()
    packages = locked_packages()
    print(f"run.py: installing {len(packages)} locked packages into .venv (wheels only; "
          "once)", flush=True)  # fmt: skip
    # The lock pins every package: no resolver pass (--no-deps), only wheels (no builds), and
    # no byte-compiling of every module up front (Python compiles what it imports, once).
    _pip(["install", "--no-deps", "--only-binary=:all:", "--no-compile", "-r", str(LOCK)],
         len(packages), "installing")  # fmt: skip
    # LegOpt itself, editable: its code stays in this checkout; `.venv/bin/legopt` is created.
    _pip(["install", "--no-deps", "-e", str(ROOT)], 1, "installing legopt")
    STAMP.write_text(want)
    print(f"run.py: environment ready in {time.monotonic() - t0:.0f} s", flush=True)
    compile_kernels()


def compile_kernels() -> None:
    """Compile every numerical kernel the studies use into numba's cache, once per install, so
    that no first job, test or request waits for it (``python -m legcore.warmup``: a tiny job
    of every study kind and the numerical IK). Best effort: a failure only means a slower
    first run. ``LEGOPT_SKIP_WARMUP=1`` skips it."""
    if os.environ.get("LEGOPT_SKIP_WARMUP") == "1":
        return
    print("run.py: compiling the numerical kernels once (a few minutes on 2 cores; every "
          "later run starts warm)", flush=True)  # fmt: skip
    t0 = time.monotonic()
    cmd = [str(_venv_bin("python")), "-m", "legcore.warmup"]
    with LOG.open("a") as log:
        proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=log, text=True)
        assert proc.stdout is not None
        for line in proc.stdout:
            log.write(line)
            if line.startswith("warmup: "):
                print(f"run.py: compiled {line[len('warmup: '):].strip()}", flush=True)
        code = proc.wait()
    if code:
        print(f"run.py: compiling the kernels failed (exit {code}; see {LOG}); the first run "
              "compiles what it needs", flush=True)  # fmt: skip
    else:
        print(f"run.py: kernels compiled in {time.monotonic() - t0:.0f} s", flush=True)


#: pytest options whose value is the next argument (so it is not taken for a test path).
_VALUE_OPTIONS = {
    "-p", "-o", "-c", "-W", "--rootdir", "--confcutdir", "--basetemp", "--junitxml",
    "--durations", "--tb", "--maxfail", "--dist",
}  # fmt: skip
#: Options that choose which tests run, or how many processes run them.
_SELECTING = {"-k", "-m", "-n", "--lf", "--last-failed", "--ff", "--sw", "--stepwise",
              "--co", "--collect-only", "--numprocesses"}  # fmt: skip


def selects_tests(args: list[str]) -> bool:
    """True when pytest ARGS name tests, markers, keywords or a process count."""
    skip = False
    for arg in args:
        if skip:
            skip = False
            continue
        name = arg.split("=", 1)[0]
        if name in _VALUE_OPTIONS:
            skip = "=" not in arg
            continue
        short = arg[:2] in {"-k", "-m", "-n"} and not arg.startswith("--")
        if name in _SELECTING or short or not arg.startswith("-"):
            return True
    return False


def run_tests(py: str, args: list[str]) -> int:
    """The test suite. ARGS that choose tests run as given (one pytest). ``--quick``: the quick
    lane, the unit tests without the slow ones (``-m "not integration and not slow"``, a few
    minutes on 2 cores). Otherwise two phases, each spread over the machine's cores by test
    file (pytest-xdist): the unit tests, then the real-process tests (``-m integration``: API,
    workers, brokers, databases, browser), which each start their own services on free ports;
    each phase prints its 25 slowest tests. Returns the first failing exit code."""
    quick = "--quick" in args
    args = [a for a in args if a != "--quick"]
    if selects_tests(args) and not quick:
        return subprocess.run([py, "-m", "pytest", *args], cwd=ROOT).returncode
    n = str(max(1, min(os.cpu_count() or 1, 4)))
    phases = ["not integration and not slow"] if quick else ["not integration", "integration"]
    code = 0
    for marker in phases:
        burn = _cpu_burn() if marker == "integration" else 0
        print(f"run.py: pytest -m {marker!r} on {n} processes"
              + (f", {burn} CPU burners beside them" if burn else ""), flush=True)  # fmt: skip
        cmd = [py, "-m", "pytest", "-m", marker, "-n", n, "--dist", "loadfile",
               "--durations", "25", *args]  # fmt: skip
        burners = [_burner() for _ in range(burn)]
        try:
            rc = subprocess.run(cmd, cwd=ROOT).returncode
        finally:
            for b in burners:
                b.kill()
                b.wait()
        code = code or (0 if rc == 5 else rc)  # 5: nothing collected
    return code


#: A busy loop that ends when its parent (run.py) is gone, however that ended.
_BURN = ("import os\nparent = os.getppid()\nwhile os.getppid() == parent:\n"
         "    for _ in range(200000):\n        pass\n")


def _cpu_burn() -> int:
    """Busy processes to run beside the real-process tests: ``LEGOPT_TEST_CPU_BURN`` per core
    (0 by default). CI sets it to prove the suite fails only when the software is wrong, not
    when a shared machine is busy (``LEGOPT_TEST_CPU_BURN=2``: the CPU oversubscribed 3×)."""
    try:
        per_core = float(os.environ.get("LEGOPT_TEST_CPU_BURN", "0") or 0)
    except ValueError:
        print("run.py: LEGOPT_TEST_CPU_BURN must be a number of burners per core", file=sys.stderr)
        raise SystemExit(2) from None
    return max(0, round(per_core * (os.cpu_count() or 1)))


def _burner() -> subprocess.Popen[bytes]:
    return subprocess.Popen([sys.executable, "-c", _BURN], stdin=subprocess.DEVNULL)


def main(argv: list[str]) -> int:
    task, *rest = argv or ["help"]
    if task in {"help", "-h", "--help"}:
        print(__doc__)
        return 0
    ensure_env()
    py = str(_venv_bin("python"))
    if task == "test":
        return run_tests(py, rest)
    if task == "demo":
        cmd = [str(_venv_bin("legopt")), "demo", *rest]
    elif task == "bench":
        cmd = [py, str(ROOT / "benchmarks" / "run_all.py"), *rest]
    elif task == "legopt":
        cmd = [str(_venv_bin("legopt")), *rest]
    else:
        print(f"run.py: unknown task {task!r}\n{__doc__}", file=sys.stderr)
        return 2
    return become(cmd)


def become(cmd: list[str]) -> int:
    """Replace this process by ``cmd`` (run from the repository root): a signal sent to
    run.py (Ctrl-C, SIGTERM, kill) then reaches the command itself, which stops its own
    service processes, instead of leaving them running behind a dead parent. Where exec is
    not available (Windows) it runs ``cmd`` as a child and returns its exit code."""
    os.chdir(ROOT)
    sys.stdout.flush()
    sys.stderr.flush()
    if os.name == "nt":
        return subprocess.run(cmd).returncode
    os.execv(cmd[0], cmd)
    raise AssertionError("unreachable")  # pragma: no cover


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
