"""Process control for the chaos suite, on top of ``tests/integration/stack.py``.

``ChaosStack`` is a ``Stack`` that

- starts solo AND prefork workers (``--pool prefork -c N``) and waits until each is ready;
- finds a prefork worker's pool children and kills them (``kill -9``), kills a worker parent,
  the API (``kill -9``, restart on the same port) and Redis (``ChaosRedis``: ``kill -9``,
  restart on the same port), pauses a worker (SIGSTOP) and resumes it (SIGCONT);
- logs every fault (``Fault``: what, when, for how long, whether it stopped the workers
  from getting work) and every change of the workers' capacity (job slots that are up), which
  the invariant checker uses to tell a job waiting for a busy or broken service from a job
  that is wedged;
- remembers every process it started and their descendants (``track_tree``), so that
  ``leftover_processes`` can prove that nothing survives the stack (no orphans).

Times are timezone-aware UTC datetimes, comparable with the database's.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import subprocess
import time
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import psutil

from services.embedded import worker_command
from tests.integration.stack import RedisServer, Stack
from tests.patience import Patience

#: Extra environment of every chaos process: the chaos suite is not about rate limits (ignored
#: by a service that has none: unknown ``LEGOPT_*`` variables are ignored); faulthandler on.
CHAOS_ENV = {
    "LEGOPT_RATE_LIMIT_PER_S": "100000",
    "LEGOPT_RATE_LIMIT_BURST": "100000",
    "PYTHONFAULTHANDLER": "1",  # SIGABRT of a stuck process logs its Python stacks
}
READY_TIMEOUT_S = 90.0


def utcnow() -> datetime:
    return datetime.now(UTC)


def _tail(path: Path, n: int = 4000) -> str:
    return path.read_text(errors="replace")[-n:] if path.exists() else "(no log)"


@dataclass
class Fault:
    """One injected fault. ``blocks_workers``: no worker could get work while it lasted
    (broker down), so queue waits inside it are excused; other faults (a killed worker, a
    killed API) are excused only through the capacity log, not as a whole."""

    kind: str
    target: str
    start: datetime
    end: datetime | None = None
    blocks_workers: bool = False
    victims: list[str] = field(default_factory=list)

    def close(self) -> None:
        if self.end is None:
            self.end = utcnow()


@dataclass
class Worker:
    """A worker process started by the harness: ``slots`` job slots (1 solo, N prefork)."""

    name: str
    proc: subprocess.Popen[bytes]
    slots: int
    log: Path
    ready_at: datetime | None = None
    up: bool = False

    @property
    def pid(self) -> int:
        return self.proc.pid


class ChaosRedis(RedisServer):
    """``RedisServer`` that can also be killed with SIGKILL (and restarted on its port)."""

    def kill(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGKILL)
            self.proc.wait(10)


class ChaosStack(Stack):
    """A ``Stack`` with fault injection, a fault/capacity log and process tracking."""

    def __init__(self, kind: str, tmp: Path, database_url: str, broker_url: str) -> None:
        super().__init__(kind, tmp, database_url, broker_url)
        self.env.update(CHAOS_ENV)
        self.redis: ChaosRedis | None = None
        self.chaos_workers: list[Worker] = []
        self.faults: list[Fault] = []
        self.capacity_log: list[tuple[datetime, int]] = []  # (when, total slots up)
        self.tracked: dict[int, float] = {}  # pid -> create_time of everything we started
        self._n = 0

    # ------------------------------------------------------------------ tracking
    def _spawn(self, cmd: list[str], log_name: str) -> subprocess.Popen[bytes]:
        proc = super()._spawn(cmd, log_name)
        self.track_tree(proc.pid)
        return proc

    def track_tree(self, pid: int) -> None:
        """Remember ``pid`` and all its current descendants (pid + create time)."""
        try:
            root = psutil.Process(pid)
            procs = [root, *root.children(recursive=True)]
        except psutil.Error:
            return
        for p in procs:
            with contextlib.suppress(psutil.Error):
                self.tracked.setdefault(p.pid, p.create_time())

    def track_all(self) -> None:
        """Refresh the descendants of every live tracked process (call it periodically)."""
        for pid in list(self.tracked):
            self.track_tree(pid)

    @staticmethod
    def _with_descendants(pids: set[int]) -> set[int]:
        out = set(pids)
        for pid in pids:
            with contextlib.suppress(psutil.Error):
                out.update(c.pid for c in psutil.Process(pid).children(recursive=True))
        return out

    def leftover_processes(self, exclude: set[int] | None = None) -> list[str]:
        """Live processes we started (or their descendants), and any process whose environment
        holds this stack's ``LEGOPT_DATA_DIR``; ``exclude``: pids allowed to live (and theirs)."""
        allowed = self._with_descendants(exclude or set())
        out = []
        for pid, created in self.tracked.items():
            if pid in allowed:
                continue
            with contextlib.suppress(psutil.Error):
                p = psutil.Process(pid)
                if abs(p.create_time() - created) < 0.01 and p.status() != psutil.STATUS_ZOMBIE:
                    out.append(f"pid {pid} {p.status()} {' '.join(p.cmdline())[:160]}")
        marker = f"LEGOPT_DATA_DIR={self.env['LEGOPT_DATA_DIR']}"
        for p in psutil.process_iter(["pid"]):
            if p.pid in allowed or p.pid in self.tracked or p.pid == os.getpid():
                continue
            with contextlib.suppress(psutil.Error, OSError):
                if p.status() == psutil.STATUS_ZOMBIE:
                    continue
                environ = Path(f"/proc/{p.pid}/environ").read_bytes().split(b"\0")
                if marker.encode() in environ:
                    out.append(f"pid {p.pid} (has our data dir) {' '.join(p.cmdline())[:160]}")
        return out

    # ------------------------------------------------------------------ capacity and faults
    def _capacity_changed(self) -> None:
        self.capacity_log.append((utcnow(), sum(w.slots for w in self.chaos_workers if w.up)))

    def fault(self, kind: str, target: str, *, blocks_workers: bool = False) -> Fault:
        f = Fault(kind, target, utcnow(), blocks_workers=blocks_workers)
        self.faults.append(f)
        return f

    # ------------------------------------------------------------------ workers
    def start_worker(self, concurrency: int = 1, *, wait: bool = True) -> subprocess.Popen[bytes]:
        """Start a solo (``concurrency=1``) or prefork worker; with ``wait``, until it is ready
        (its log says ``ready.`` and a prefork pool has all its children)."""
        self._n += 1
        name = f"c{self._n}"
        log_name = f"worker-{name}-{'solo' if concurrency == 1 else f'prefork{concurrency}'}.log"
        proc = self._spawn(worker_command(name, concurrency, "INFO"), log_name)
        self.workers.append(proc)
        w = Worker(name, proc, concurrency, self.logs / log_name)
        self.chaos_workers.append(w)
        if wait:
            self.wait_ready(w)
        return proc

    def worker(self, proc_or_pid: subprocess.Popen[bytes] | int) -> Worker:
        pid = proc_or_pid if isinstance(proc_or_pid, int) else proc_or_pid.pid
        for w in self.chaos_workers:
            if w.pid == pid:
                return w
        raise KeyError(pid)

    def wait_ready(self, w: Worker, timeout_s: float = READY_TIMEOUT_S) -> None:
        patience = Patience(timeout_s)
        while not patience.expired():
            if w.proc.poll() is not None:
                raise AssertionError(f"worker {w.name} exited:\n{_tail(w.log)}")
            text = w.log.read_text(errors="replace") if w.log.exists() else ""
            if re.search(r"@\S+ ready\.", text) and len(self.pool_children(w.proc)) >= (
                w.slots if w.slots > 1 else 0
            ):
                w.ready_at, w.up = utcnow(), True
                self.track_tree(w.pid)
                self._capacity_changed()
                return
            time.sleep(0.01)
        raise AssertionError(f"worker {w.name} not ready in {patience}\n{_tail(w.log)}")

    def pool_children(self, proc: subprocess.Popen[bytes]) -> list[psutil.Process]:
        """The live pool processes of a prefork worker (none for a solo worker)."""
        try:
            kids = psutil.Process(proc.pid).children()
        except psutil.Error:
            return []
        live = []
        for k in kids:
            with contextlib.suppress(psutil.Error):
                if k.status() != psutil.STATUS_ZOMBIE:
                    live.append(k)
        return live

    def kill_pool_child(self, proc: subprocess.Popen[bytes], pid: int | None = None) -> int:
        """``kill -9`` one pool child (``pid`` or the first); returns its pid. The parent is
        expected to fork a replacement: this is logged as a fault of no duration."""
        kids = self.pool_children(proc)
        assert kids, f"worker {proc.pid} has no pool children"
        victim = next((k for k in kids if k.pid == pid), kids[0]) if pid else kids[0]
        f = self.fault("kill -9 pool child", f"{victim.pid} of {proc.pid}")
        with contextlib.suppress(psutil.Error):
            victim.send_signal(signal.SIGKILL)
        f.close()
        return victim.pid

    def kill_worker(self, proc: subprocess.Popen[bytes]) -> None:
        """``kill -9`` a worker's main process (its pool children die with it: pdeathsig)."""
        w = self.worker(proc)
        self.track_tree(w.pid)
        f = self.fault("kill -9 worker", w.name)
        w.proc.send_signal(signal.SIGKILL)
        w.proc.wait(10)
        w.up = False
        self._capacity_changed()
        f.close()

    def pause_worker(self, proc: subprocess.Popen[bytes]) -> Fault:
        """SIGSTOP a worker and its children; the fault stays open until ``resume_worker``."""
        w = self.worker(proc)
        f = self.fault("SIGSTOP worker", w.name)
        for p in [psutil.Process(w.pid), *self.pool_children(w.proc)]:
            p.send_signal(signal.SIGSTOP)
        w.up = False
        self._capacity_changed()
        return f

    def resume_worker(self, proc: subprocess.Popen[bytes], f: Fault) -> None:
        w = self.worker(proc)
        for p in [psutil.Process(w.pid), *self.pool_children(w.proc)]:
            p.send_signal(signal.SIGCONT)
        w.up = True
        self._capacity_changed()
        f.close()

    def stop_worker(self, proc: subprocess.Popen[bytes], timeout_s: float = 20.0) -> None:
        """SIGCONT then SIGTERM (warm handback), SIGKILL after ``timeout_s``."""
        w = self.worker(proc)
        self.track_tree(w.pid)
        if proc.poll() is None:
            with contextlib.suppress(psutil.Error):
                for p in [psutil.Process(w.pid), *self.pool_children(proc)]:
                    p.send_signal(signal.SIGCONT)
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout_s)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(10)
        if w.up:
            w.up = False
            self._capacity_changed()

    # ------------------------------------------------------------------ API and broker
    def kill_api(self) -> Fault:
        """``kill -9`` the API; the fault stays open until ``restart_api``."""
        assert self.api is not None
        f = self.fault("kill -9 API", f"pid {self.api.pid}")
        self.api.send_signal(signal.SIGKILL)
        self.api.wait(10)
        return f

    def restart_api(self, f: Fault | None = None) -> None:
        self.start_api()
        assert self.api is not None
        self.track_tree(self.api.pid)
        if f is not None:
            f.close()

    def ensure_api(self) -> None:
        """Restart the API if a failed test left it dead."""
        if self.api is None or self.api.poll() is not None:
            self.start_api()
            assert self.api is not None
            self.track_tree(self.api.pid)

    def kill_redis(self) -> Fault:
        """``kill -9`` Redis (services stack); every message in it is lost (no persistence)."""
        assert self.redis is not None, "no Redis on this stack"
        f = self.fault("kill -9 Redis", f"port {self.redis.port}", blocks_workers=True)
        self.redis.kill()
        return f

    def restart_redis(self, f: Fault | None = None) -> None:
        assert self.redis is not None
        self.redis.start()
        assert self.redis.proc is not None
        self.track_tree(self.redis.proc.pid)
        if f is not None:
            f.close()

    # ------------------------------------------------------------------ shutdown
    def stop(self) -> None:
        """Stop every worker (resuming paused ones first), then the API."""
        for w in self.chaos_workers:
            self.stop_worker(w.proc)
        self.stop_api()

    def kill_leftovers(self, exclude: set[int] | None = None) -> None:
        """Last resort after a failure: SIGKILL everything we started that still runs
        (but ``exclude``)."""
        allowed = self._with_descendants(exclude or set())
        for pid, created in self.tracked.items():
            if pid in allowed:
                continue
            with contextlib.suppress(psutil.Error):
                p = psutil.Process(pid)
                if abs(p.create_time() - created) < 0.01 and pid != os.getpid():
                    p.send_signal(signal.SIGCONT)
                    p.kill()
