"""The embedded default: API + N real Celery worker processes, no Redis, no PostgreSQL.

``legopt serve`` calls :func:`serve`; ``legopt demo`` and the integration tests start the same
thing as a subprocess. The broker is kombu's filesystem transport and the database a SQLite file,
both under ``./legopt-data`` (``LEGOPT_DATA_DIR``), unless ``LEGOPT_*`` variables point elsewhere.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

from services.store.settings import Settings, get_settings

API_KEY_FILE = "api-key"


def ensure_database(settings: Settings) -> None:
    """Create the data directory and migrate the database to head."""
    from services.store.migrate import upgrade

    Path(settings.data_dir).mkdir(parents=True, exist_ok=True)
    upgrade(settings.database_url)


def ensure_local_api_key(settings: Settings) -> tuple[str, bool]:
    """The local API key (``<data_dir>/api-key``), created on first start; (key, created)."""
    from services.store.keys import generate_api_key, hash_api_key
    from services.store.repository import create_api_key, get_api_key_by_hash
    from services.store.session import session_scope

    path = Path(settings.data_dir) / API_KEY_FILE
    if path.exists():
        raw = path.read_text().strip()
        with session_scope() as s:
            if get_api_key_by_hash(s, hash_api_key(raw)) is not None:
                return raw, False
    raw, key_hash = generate_api_key()
    with session_scope() as s:
        create_api_key(s, name="local", key_hash=key_hash)
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


def worker_env() -> dict[str, str]:
    """Environment of a worker: SIGTERM hands the job back; one numba thread per process."""
    env = dict(os.environ)
    env.setdefault("REMAP_SIGTERM", "SIGQUIT")
    env.setdefault("NUMBA_NUM_THREADS", "1")
    return env


def start_workers(n: int, loglevel: str = "INFO") -> list[subprocess.Popen[bytes]]:
    """Start ``n`` worker processes (each runs one job at a time)."""
    return [
        subprocess.Popen(worker_command(f"worker{i + 1}", 1, loglevel), env=worker_env())
        for i in range(n)
    ]


def stop_processes(procs: list[subprocess.Popen[bytes]], timeout: float = 10.0) -> None:
    """SIGTERM (→ warm shutdown, job handed back), then SIGKILL after ``timeout``."""
    for p in procs:
        if p.poll() is None:
            p.send_signal(signal.SIGTERM)
    for p in procs:
        try:
            p.wait(timeout)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()


def serve(
    host: str = "127.0.0.1", port: int = 8000, workers: int = 2, api_workers: int = 1
) -> None:
    """Migrate, ensure the API key, start ``workers`` worker processes and the API with
    ``api_workers`` processes (blocking)."""
    import uvicorn

    settings = get_settings()
    ensure_database(settings)
    key, created = ensure_local_api_key(settings)
    keyfile = Path(settings.data_dir) / API_KEY_FILE
    if created:
        print(f"created a local API key, kept in {keyfile}:\n  {key}", flush=True)
    else:
        print(f"API key in {keyfile}", flush=True)
    procs = start_workers(workers)
    try:
        print(f"LegOpt API on http://{host}:{port}/api/v1 ({workers} workers)", flush=True)
        uvicorn.run(
            "services.api.app:app",
            host=host,
            port=port,
            workers=api_workers,
            log_level="warning",
        )
    finally:
        stop_processes(procs)
