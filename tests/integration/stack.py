"""Real-process service stacks for the integration tests.

``Stack`` starts the same processes a user runs — ``uvicorn services.api.app:app`` and
``celery … worker`` (via ``legopt worker``'s command line) — on either

- ``embedded``: SQLite file + kombu filesystem broker in a temp directory (always available), or
- ``services``: a fresh PostgreSQL database on 127.0.0.1:5432 and a private ``redis-server`` on a
  free port (skipped where PostgreSQL or the redis-server binary is absent).

In-process tests that need only a database take ``DATABASES`` (``sqlite``, ``postgresql``) and
``service_database``. ``LEGOPT_REQUIRE_SERVICES=1`` (CI sets it in ``.ci/run``) turns every
such skip into a failure naming what is missing: the PostgreSQL + Redis variants never silently
skip where they are required.

Leases are short (4 s) and every generation is checkpointed so that recovery tests run fast.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path
from typing import Any, NoReturn

import httpx
import pytest

from services.client import Client
from services.embedded import worker_command
from tests.patience import Patience, oversubscription

PG_ADMIN_URL = os.environ.get(
    "LEGOPT_TEST_POSTGRES_URL", "postgresql+psycopg://postgres@127.0.0.1:5432/test"
)
ROOT = Path(__file__).resolve().parents[2]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


#: Set to 1 where the PostgreSQL + Redis tests must run (CI): a missing service fails them.
REQUIRE_SERVICES_ENV = "LEGOPT_REQUIRE_SERVICES"


def services_required() -> bool:
    """``LEGOPT_REQUIRE_SERVICES=1``: a missing PostgreSQL or redis-server fails, never skips."""
    return os.environ.get(REQUIRE_SERVICES_ENV) == "1"


@lru_cache(maxsize=1)
def postgres_available() -> bool:
    """Whether the PostgreSQL server at ``LEGOPT_TEST_POSTGRES_URL`` answers (probed once)."""
    try:
        import psycopg

        url = PG_ADMIN_URL.replace("postgresql+psycopg://", "postgresql://")
        with psycopg.connect(url, connect_timeout=2):
            return True
    except Exception:
        return False


def redis_server_binary() -> str | None:
    return shutil.which("redis-server")


def postgres_missing() -> str | None:
    """Why the PostgreSQL tests cannot run here (None: they can)."""
    if postgres_available():
        return None
    return f"no PostgreSQL server answers at {PG_ADMIN_URL} (LEGOPT_TEST_POSTGRES_URL)"


def services_missing() -> str | None:
    """Why the ``services`` stack (PostgreSQL + redis-server) cannot run here (None: it can)."""
    reasons = [r for r in (postgres_missing(),) if r is not None]
    if redis_server_binary() is None:
        reasons.append("redis-server is not installed (apt-get install redis-server)")
    return "; ".join(reasons) or None


def services_available() -> bool:
    """Whether the ``services`` stack can run here. Where it cannot, its tests are skipped —
    unless ``LEGOPT_REQUIRE_SERVICES=1``: then they run and fail naming what is missing
    (``KINDS``, ``require_services``)."""
    return services_missing() is None


def unavailable(reason: str) -> NoReturn:
    """Skip the current test because ``reason``, or fail it where ``LEGOPT_REQUIRE_SERVICES=1``."""
    if services_required():
        pytest.fail(
            f"{REQUIRE_SERVICES_ENV}=1 requires the PostgreSQL + Redis tests to run here, but "
            f"{reason}",
            pytrace=False,
        )
    pytest.skip(reason)


def require_postgres() -> None:
    """Skip (or, where required, fail) the current test when PostgreSQL does not answer."""
    reason = postgres_missing()
    if reason is not None:
        unavailable(reason)


def require_services() -> None:
    """Skip (or, where required, fail) the current test when PostgreSQL or redis-server is
    missing."""
    reason = services_missing()
    if reason is not None:
        unavailable(reason)


def when_available(value: Any, missing: str | None, *, id: str | None = None) -> Any:
    """A ``pytest.param`` of ``value``: skipped with ``missing`` as the reason where that is
    not None — but never where ``LEGOPT_REQUIRE_SERVICES=1``: there the test runs, and its
    fixture (``postgres_database``, ``RedisServer.start``, ``service_database``) fails naming
    what is missing."""
    marks = [] if missing is None or services_required() else [pytest.mark.skip(reason=missing)]
    return pytest.param(value, marks=marks, id=id)


#: The stack kinds a service test runs on: ``embedded`` always, ``services`` (PostgreSQL +
#: Redis) where both are available (skipped with the reason otherwise; a failure where
#: ``LEGOPT_REQUIRE_SERVICES=1``).
KINDS = ["embedded", when_available("services", services_missing())]

#: The databases an in-process API test runs on (``service_database``): ``sqlite`` always,
#: ``postgresql`` as the ``services`` kind above.
DATABASES = ["sqlite", when_available("postgresql", postgres_missing())]


@contextmanager
def postgres_database() -> Iterator[str]:
    """A fresh PostgreSQL database (dropped afterwards); yields its SQLAlchemy URL. Skips the
    test (fails it where ``LEGOPT_REQUIRE_SERVICES=1``) when PostgreSQL does not answer."""
    require_postgres()
    import psycopg

    admin = PG_ADMIN_URL.replace("postgresql+psycopg://", "postgresql://")
    name = f"legopt_it_{uuid.uuid4().hex[:10]}"
    with psycopg.connect(admin, autocommit=True) as conn:
        conn.execute(f'CREATE DATABASE "{name}"')
    base = PG_ADMIN_URL.rsplit("/", 1)[0]
    try:
        yield f"{base}/{name}"
    finally:
        with psycopg.connect(admin, autocommit=True) as conn:
            conn.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')


@contextmanager
def service_database(kind: str, directory: Path) -> Iterator[str]:
    """An empty database of ``kind`` (``DATABASES``) for an in-process test; yields its URL:
    ``sqlite``, a new file in ``directory``; ``postgresql``, a fresh database
    (``postgres_database``: dropped afterwards, skipped or failed as there)."""
    if kind == "sqlite":
        directory.mkdir(parents=True, exist_ok=True)
        yield f"sqlite:///{(directory / 'legopt.db').as_posix()}"
    elif kind == "postgresql":
        with postgres_database() as url:
            yield url
    else:
        raise ValueError(f"unknown database kind {kind!r} (sqlite or postgresql)")


class RedisServer:
    """A private redis-server on a free port (restartable; keeps nothing on disk)."""

    def __init__(self, workdir: Path) -> None:
        self.port = free_port()
        self.workdir = workdir
        self.proc: subprocess.Popen[bytes] | None = None

    def start(self) -> None:
        """Start (or restart) the server; skips the test (fails it where
        ``LEGOPT_REQUIRE_SERVICES=1``) when PostgreSQL or redis-server is missing."""
        require_services()
        binary = redis_server_binary()
        assert binary is not None
        self.proc = subprocess.Popen(
            [binary, "--port", str(self.port), "--bind", "127.0.0.1", "--save", "",
             "--appendonly", "no", "--dir", str(self.workdir)],
            stdout=subprocess.DEVNULL,
        )  # fmt: skip
        patience = Patience(10)
        while not patience.expired():
            if self.proc.poll() is not None:
                raise RuntimeError(f"redis-server exited with {self.proc.returncode}")
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=0.2):
                    return
            except OSError:
                time.sleep(0.05)
        raise RuntimeError(f"redis-server did not start in {patience}")

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            self.proc.wait(10)

    def restart(self) -> None:
        self.stop()
        self.start()

    @property
    def url(self) -> str:
        return f"redis://127.0.0.1:{self.port}/0"


class Stack:
    """API + worker processes on one database and broker; see the module docstring."""

    def __init__(self, kind: str, tmp: Path, database_url: str, broker_url: str) -> None:
        self.kind = kind
        self.tmp = tmp
        self.env = dict(os.environ)
        self.env.update(
            LEGOPT_DATA_DIR=str(tmp / "data"),
            LEGOPT_DATABASE_URL=database_url,
            LEGOPT_BROKER_URL=broker_url,
            LEGOPT_ARTIFACT_DIR=str(tmp / "data" / "artifacts"),
            LEGOPT_LEASE_SECONDS="4",
            LEGOPT_HEARTBEAT_SECONDS="1",
            LEGOPT_CHECKPOINT_EVERY="1",
            # The worker warm-up (seconds of CPU per worker start) is not under test here and
            # the suites start hundreds of workers; the demo test keeps it on.
            LEGOPT_WORKER_WARMUP="false",
            LEGOPT_API_WARMUP="false",  # likewise the API's (tests/integration/test_api_warmup.py)
            NUMBA_NUM_THREADS="1",
            PYTHONUNBUFFERED="1",
        )
        self.port = free_port()
        self.api: subprocess.Popen[bytes] | None = None
        self.workers: list[subprocess.Popen[bytes]] = []
        self.key = ""
        self.logs = tmp / "logs"
        self.logs.mkdir(parents=True, exist_ok=True)

    # ------------------------------------------------------------------ processes
    def _spawn(self, cmd: list[str], log_name: str) -> subprocess.Popen[bytes]:
        log = open(self.logs / log_name, "ab")  # noqa: SIM115 - closed with the process
        return subprocess.Popen(cmd, env=self.env, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT)

    def migrate_and_key(self) -> None:
        out = subprocess.run(
            [sys.executable, "-m", "services.cli", "db", "upgrade"],
            env=self.env, cwd=ROOT, capture_output=True, text=True, timeout=120,
        )  # fmt: skip
        assert out.returncode == 0, out.stderr
        out = subprocess.run(
            [sys.executable, "-m", "services.cli", "keys", "create", "--name", "it"],
            env=self.env, cwd=ROOT, capture_output=True, text=True, timeout=120,
        )  # fmt: skip
        assert out.returncode == 0, out.stderr
        self.key = out.stdout.strip().splitlines()[-1]

    def start_api(self, workers: int = 1) -> None:
        self.api = self._spawn(
            [sys.executable, "-m", "uvicorn", "services.api.app:app", "--host", "127.0.0.1",
             "--port", str(self.port), "--log-level", "warning", "--workers", str(workers)],
            "api.log",
        )  # fmt: skip
        patience = Patience(60)
        while not patience.expired():
            if self.api.poll() is not None:
                raise RuntimeError(f"API exited: {(self.logs / 'api.log').read_text()[-2000:]}")
            try:
                if httpx.get(f"{self.url}/api/v1/health", timeout=1).status_code == 200:
                    return
            except httpx.HTTPError:
                pass
            time.sleep(0.2)
        raise RuntimeError(f"API did not start in {patience}")

    def stop_api(self) -> None:
        """SIGTERM (uvicorn finishes its requests), then SIGKILL if it outlasts 20 s of a quiet
        machine: a stuck request must not turn the teardown into an error."""
        if self.api is not None and self.api.poll() is None:
            self.api.terminate()
            try:
                self.api.wait(20 * oversubscription())
            except subprocess.TimeoutExpired:
                self.api.kill()
                self.api.wait(20)

    def start_worker(self) -> subprocess.Popen[bytes]:
        i = len(self.workers) + 1
        proc = self._spawn(worker_command(f"w{i}", 1, "INFO"), f"worker{i}.log")
        self.workers.append(proc)
        return proc

    def kill_worker(self, proc: subprocess.Popen[bytes]) -> None:
        proc.send_signal(signal.SIGKILL)
        proc.wait(10)

    def worker_by_pid(self, pid: int) -> subprocess.Popen[bytes]:
        for w in self.workers:
            if w.pid == pid:
                return w
        raise KeyError(pid)

    def stop(self) -> None:
        self.stop_api()
        for w in self.workers:
            if w.poll() is None:
                w.send_signal(signal.SIGTERM)
        for w in self.workers:
            try:
                w.wait(20)
            except subprocess.TimeoutExpired:
                w.kill()
                w.wait()

    def log_tail(self, n: int = 3000) -> str:
        return "\n".join(
            f"--- {p.name}\n{p.read_text(errors='replace')[-n:]}"
            for p in sorted(self.logs.iterdir())
        )

    # ------------------------------------------------------------------ client
    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def client(self) -> Client:
        return Client(self.url, self.key, timeout=30)

    def wait_for(self, job_id: str, pred: Any, timeout_s: float = 120.0) -> dict[str, Any]:
        """Poll job ``job_id`` until ``pred(job)``; fails with the logs after ``timeout_s``
        quiet-machine seconds (``tests.patience``)."""
        patience = Patience(timeout_s)
        with self.client() as c:
            while True:
                job = c.job(job_id)
                if pred(job):
                    return job
                if patience.expired():
                    raise AssertionError(
                        f"timeout ({patience}) waiting for {job_id}: {job}\n{self.log_tail()}"
                    )
                time.sleep(0.2)


@contextmanager
def embedded_stack(tmp: Path, env: dict[str, str] | None = None) -> Iterator[Stack]:
    """The embedded service (SQLite + filesystem broker, API + one worker) on a fresh data
    directory under ``tmp``; ``env``: extra environment of its processes. Stopped on exit."""
    (tmp / "data").mkdir(parents=True, exist_ok=True)
    st = Stack("embedded", tmp, f"sqlite:///{tmp / 'data' / 'legopt.db'}", "filesystem://")
    st.env.update(env or {})
    st.migrate_and_key()
    st.start_api()
    st.start_worker()
    try:
        yield st
    finally:
        st.stop()
