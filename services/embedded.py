"""The embedded default: API + N real Celery worker processes, no Redis, no PostgreSQL.

``legopt serve`` calls :func:`serve`; ``legopt demo`` and the integration tests start the same
thing as a subprocess. The broker is kombu's filesystem transport and the database a SQLite file,
both under ``./legopt-data`` (``LEGOPT_DATA_DIR``), unless ``LEGOPT_*`` variables point elsewhere.

``serve`` is a supervisor (:mod:`services.supervisor`): the API (uvicorn, ``api_workers``
processes) and every worker are its child processes; a child that dies is restarted, SIGTERM /
SIGINT stop them all, and none outlives ``serve`` even when it is killed with SIGKILL. Everything
``legopt`` writes is private to its user (:func:`restrict_umask`, data directory 0700).
"""

from __future__ import annotations

import logging
import os
import signal
import socket
import subprocess
import sys
from pathlib import Path
from typing import Any

from services.store.settings import Settings, get_settings
from services.supervisor import ChildSpec, Supervisor, die_with_parent, stop_requested

API_KEY_FILE = "api-key"
PRIVATE_UMASK = 0o077  # files 0600, directories 0700
STOP_TIMEOUT_S = 10.0  # s a worker gets to finish its job on shutdown before SIGKILL
UVICORN_STARTUP_FAILURE = 3  # uvicorn.config.STARTUP_FAILURE: restarting cannot help

log = logging.getLogger("legopt.serve")


def restrict_umask() -> int:
    """Make every file and directory this process (and its children) creates private to its
    user: umask 077. Returns the previous umask. Called once by the ``legopt`` command."""
    return os.umask(PRIVATE_UMASK)


def ensure_data_dir(settings: Settings) -> Path:
    """Create the data directory, private to its owner (mode 0700, also when it existed)."""
    path = Path(settings.data_dir)
    path.mkdir(parents=True, exist_ok=True)
    try:
        path.chmod(0o700)
    except PermissionError:  # not ours (e.g. a mounted volume): its owner decides
        log.warning("cannot restrict %s to its owner (mode 0700)", path)
    return path


def ensure_database(settings: Settings) -> None:
    """Create the data directory and migrate the database to head."""
    from services.store.migrate import upgrade

    ensure_data_dir(settings)
    upgrade(settings.database_url)


def ensure_local_api_key(settings: Settings) -> tuple[str, bool]:
    """The local API key (``<data_dir>/api-key``, an admin key: the machine owner's), created
    on first start; (key, created)."""
    from services.store.api_keys import create_api_key, get_api_key_by_hash
    from services.store.keys import generate_api_key, hash_api_key
    from services.store.session import session_scope

    path = Path(settings.data_dir) / API_KEY_FILE
    if path.exists():
        raw = path.read_text().strip()
        with session_scope() as s:
            if get_api_key_by_hash(s, hash_api_key(raw)) is not None:
                return raw, False
    raw, key_hash = generate_api_key()
    with session_scope() as s:
        create_api_key(s, name="local", key_hash=key_hash, role="admin")
    path.write_text(raw + "\n")
    path.chmod(0o600)
    return raw, True


def worker_command(name: str, concurrency: int = 1, loglevel: str = "INFO") -> list[str]:
    """The command line of one Celery worker process (the same one compose runs)."""
    pool = ["--pool", "solo"] if concurrency == 1 else ["--pool", "prefork", "-c", str(concurrency)]
    return [
        sys.executable, "-m", "celery", "-A", "services.worker.celery_app:app", "worker",
        "-Q", "legopt", "-n", f"{name}@%h", "--loglevel", loglevel, "--without-gossip",
        "--without-mingle", "--without-heartbeat", *pool,
    ]  # fmt: skip


def worker_env(concurrency: int = 1) -> dict[str, str]:
    """Environment of a worker: one numba thread per process, and what SIGTERM does.

    Prefork (``concurrency`` > 1): ``REMAP_SIGTERM=SIGQUIT``, a cold shutdown that kills the pool
    child and hands its message back. Solo (1, what ``serve`` runs): no remapping, SIGTERM is a
    warm shutdown — the job in hand runs on until it ends or the supervisor's SIGKILL, after
    which its lease expires and another worker resumes it from its checkpoint. (A cold shutdown
    of a solo worker raises inside the running job and ends it ``failed``.)"""
    env = dict(os.environ)
    if concurrency == 1:
        env.pop("REMAP_SIGTERM", None)
    else:
        env.setdefault("REMAP_SIGTERM", "SIGQUIT")
    env.setdefault("NUMBA_NUM_THREADS", "1")
    for name, value in get_settings().cache_environment().items():  # warm starts (issue 12)
        env.setdefault(name, value)
    return env


def api_app() -> Any:
    """ASGI app factory of the API processes ``serve`` starts (``uvicorn --factory``).

    With ``--workers N`` > 1 uvicorn's own supervisor spawns the API processes; each one here
    asks the kernel for SIGTERM when that supervisor dies, so none outlives ``serve``."""
    import multiprocessing

    parent = multiprocessing.parent_process()
    if parent is not None and parent.pid is not None:
        die_with_parent(signal.SIGTERM, parent.pid)
    from services.api.app import app

    return app


def api_command(host: str, port: int, api_workers: int = 1) -> list[str]:
    """The command line of the API (uvicorn; ``api_workers`` processes)."""
    return [
        sys.executable, "-m", "uvicorn", "services.embedded:api_app", "--factory",
        "--host", host, "--port", str(port), "--workers", str(api_workers),
        "--log-level", "warning", "--timeout-graceful-shutdown", "5",
    ]  # fmt: skip


def service_specs(host: str, port: int, workers: int, api_workers: int) -> list[ChildSpec]:
    """The processes of ``serve``: the API and ``workers`` solo Celery workers."""
    api = ChildSpec(
        "api",
        api_command(host, port, api_workers),
        fatal_exit_codes=frozenset({UVICORN_STARTUP_FAILURE}),
    )
    return [api] + [
        # SIGKILL when serve dies: a warm shutdown would let an orphan run its job to the end
        ChildSpec(f"worker{i + 1}", worker_command(f"worker{i + 1}", 1), worker_env(1),
                  death_signal=signal.SIGKILL)
        for i in range(workers)
    ]  # fmt: skip


def port_in_use(host: str, port: int) -> str | None:
    """Why ``host:port`` cannot be bound (as uvicorn binds it), or None if it can."""
    try:
        with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as s:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            s.bind((host, port))
    except OSError as exc:
        return str(exc)
    return None


def stop_processes(procs: list[subprocess.Popen[bytes]], timeout: float = 10.0) -> None:
    """SIGTERM (``serve``: stop its children), then SIGKILL after ``timeout`` s."""
    for p in procs:
        if p.poll() is None:
            p.send_signal(signal.SIGTERM)
    for p in procs:
        try:
            p.wait(timeout)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()


def _log_to_stderr() -> None:
    """The supervisor's lines (``legopt.*`` loggers, INFO and up) on stderr, beside the
    workers' own log lines."""
    logger = logging.getLogger("legopt")
    if not logger.handlers:
        handler = logging.StreamHandler()
        handler.setFormatter(
            logging.Formatter("[%(asctime)s: %(levelname)s/legopt-serve] %(message)s")
        )
        logger.addHandler(handler)
        logger.setLevel(logging.INFO)


def serve(
    host: str = "127.0.0.1",
    port: int = 8000,
    workers: int = 2,
    api_workers: int = 1,
    stop_timeout_s: float = STOP_TIMEOUT_S,
) -> int:
    """Migrate, ensure the API key, then supervise the API (``api_workers`` processes) and
    ``workers`` worker processes until SIGTERM / SIGINT / SIGHUP (blocking). Returns the exit
    code: 0 after a requested stop, 1 if the port is taken or a child cannot be kept running."""
    _log_to_stderr()
    settings = get_settings()
    ensure_database(settings)
    key, created = ensure_local_api_key(settings)
    keyfile = Path(settings.data_dir) / API_KEY_FILE
    if created:
        print(f"created a local API key, kept in {keyfile}:\n  {key}", flush=True)
    else:
        print(f"API key in {keyfile}", flush=True)
    busy = port_in_use(host, port)
    if busy is not None:
        print(f"error: cannot listen on {host}:{port}: {busy}", file=sys.stderr, flush=True)
        return 1
    supervisor = Supervisor(
        service_specs(host, port, workers, api_workers), stop_timeout_s=stop_timeout_s
    )
    with stop_requested() as should_stop:
        supervisor.start()
        print(
            f"LegOpt dashboard on http://{host}:{port}/  (API http://{host}:{port}/api/v1, "
            f"docs /api/v1/docs; {workers} workers)",
            flush=True,
        )
        return supervisor.run(should_stop)
