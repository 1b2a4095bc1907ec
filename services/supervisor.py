"""A small process supervisor: ``legopt serve`` runs its API and worker processes under it.

- **Restart on death.** A child that ends while the service runs — killed, crashed, or exiting by
  itself with code 0 (a recycled worker) — is logged with its exit code or signal and started
  again after a short backoff: ``backoff_s`` after a child that ran at least ``stable_s``,
  doubling (up to ``max_backoff_s``) while it keeps dying soon after its start. After
  ``give_up_after`` such quick deaths in a row the supervisor stops everything and reports
  failure rather than loop on a broken install.
- **Clean shutdown.** :meth:`Supervisor.stop` sends SIGTERM to every child, waits up to
  ``stop_timeout_s`` and then SIGKILLs the process group of any that is left; last it sweeps each
  child's process group, so nothing a child started (uvicorn's API processes, Celery's pool)
  outlives the supervisor. Each child is the leader of its own process group, so a Ctrl-C at
  the terminal reaches only the supervisor, which then stops the children in this order.
- **No orphans when the supervisor is killed.** On Linux every child is started with
  ``PR_SET_PDEATHSIG`` (:func:`die_with_parent`): the kernel sends it ``death_signal`` when the
  supervisor dies, even by SIGKILL. The signal is tied to the *thread* that forked the child,
  so the supervisor starts and restarts children only from the thread that runs it (the main
  thread of ``legopt serve``).

The supervisor polls its children every ``poll_s`` seconds from one thread; it holds no lock
and starts no thread.
"""

from __future__ import annotations

import ctypes
import logging
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from types import FrameType

log = logging.getLogger("legopt.supervisor")

PR_SET_PDEATHSIG = 1  # linux/prctl.h
STOP_SIGNALS = (signal.SIGTERM, signal.SIGINT, signal.SIGHUP)


def _load_libc() -> ctypes.CDLL | None:
    if not sys.platform.startswith("linux"):
        return None
    try:
        return ctypes.CDLL(None, use_errno=True)
    except OSError:  # pragma: no cover - no libc symbols in this process
        return None


_LIBC = _load_libc()


def set_parent_death_signal(sig: int) -> bool:
    """Ask the kernel to send ``sig`` to this process when its parent (the thread that forked
    it) dies. Linux only; returns False where it is not supported."""
    if _LIBC is None:
        return False
    return int(_LIBC.prctl(PR_SET_PDEATHSIG, ctypes.c_ulong(sig), 0, 0, 0)) == 0


def die_with_parent(sig: int, parent_pid: int | None = None) -> None:
    """Set the parent-death signal of this process to ``sig``; if the parent (``parent_pid``,
    default the current parent) is already gone, deliver ``sig`` to this process at once.

    Call it in a child between fork and exec (``preexec_fn``) or first thing in a child
    process; it allocates nothing and takes no lock."""
    expected = os.getppid() if parent_pid is None else parent_pid
    if set_parent_death_signal(sig) and os.getppid() != expected:
        os.kill(os.getpid(), sig)  # the parent died before the prctl: nobody will send it


def describe_exit(returncode: int) -> str:
    """``'was killed by SIGKILL'`` or ``'exited with code 0'`` for a Popen return code."""
    if returncode < 0:
        try:
            name = signal.Signals(-returncode).name
        except ValueError:
            name = f"signal {-returncode}"
        return f"was killed by {name}"
    return f"exited with code {returncode}"


def signal_group(pid: int, sig: int) -> None:
    """Send ``sig`` to the process group led by ``pid`` (nothing if it is empty or not ours)."""
    try:
        os.killpg(pid, sig)
    except (ProcessLookupError, PermissionError):
        pass


@dataclass(frozen=True)
class ChildSpec:
    """One supervised process: a name for the log, its command line and environment.

    ``death_signal``: what the kernel sends the child when the supervisor dies (SIGKILL for a
    process that would otherwise run on, e.g. a Celery solo worker in the middle of a job).
    ``fatal_exit_codes``: exit codes that mean "restarting cannot help" (the supervisor stops).
    """

    name: str
    argv: Sequence[str]
    env: Mapping[str, str] | None = None
    death_signal: int = signal.SIGTERM
    fatal_exit_codes: frozenset[int] = frozenset()


@dataclass
class _Child:
    spec: ChildSpec
    proc: subprocess.Popen[bytes] | None = None
    started_at: float = 0.0
    quick_deaths: int = 0
    restart_at: float | None = None
    old_pids: list[int] = field(default_factory=list)


class Supervisor:
    """Start the processes of ``specs``, restart any that ends, stop them all on :meth:`stop`.

    Times are seconds (``time.monotonic``). Use from one thread only: the thread that calls
    :meth:`start` must live as long as the children (see the module docstring)."""

    def __init__(
        self,
        specs: Sequence[ChildSpec],
        *,
        stop_timeout_s: float = 10.0,
        backoff_s: float = 0.5,
        max_backoff_s: float = 30.0,
        stable_s: float = 30.0,
        give_up_after: int = 5,
        poll_s: float = 0.2,
    ) -> None:
        names = [s.name for s in specs]
        if len(set(names)) != len(names):
            raise ValueError(f"child names must be unique: {names}")
        self.children = [_Child(s) for s in specs]
        self.stop_timeout_s = stop_timeout_s
        self.backoff_s = backoff_s
        self.max_backoff_s = max_backoff_s
        self.stable_s = stable_s
        self.give_up_after = give_up_after
        self.poll_s = poll_s
        self.exit_code = 0

    # ------------------------------------------------------------------ processes
    def _spawn(self, child: _Child) -> None:
        spec = child.spec
        parent = os.getpid()
        child.proc = subprocess.Popen(
            list(spec.argv),
            env=None if spec.env is None else dict(spec.env),
            preexec_fn=lambda: die_with_parent(spec.death_signal, parent),
            process_group=0,
        )
        child.started_at = time.monotonic()
        child.restart_at = None

    def start(self) -> None:
        """Start every child."""
        for child in self.children:
            self._spawn(child)
            log.info("started %s (pid %d)", child.spec.name, self.pid(child))

    @staticmethod
    def pid(child: _Child) -> int:
        return child.proc.pid if child.proc is not None else -1

    def pids(self) -> dict[str, int]:
        """Name → pid of each running child."""
        return {
            c.spec.name: c.proc.pid
            for c in self.children
            if c.proc is not None and c.proc.poll() is None
        }

    def check(self) -> bool:
        """One supervision pass: note children that ended, start those whose backoff is over.
        Returns False when the supervisor gave up (see ``exit_code``)."""
        now = time.monotonic()
        for child in self.children:
            proc = child.proc
            if proc is not None and child.restart_at is None:
                rc = proc.poll()
                if rc is None:
                    continue
                signal_group(proc.pid, signal.SIGKILL)  # whatever it started goes with it
                if not self._schedule_restart(child, rc, now):
                    return False
            if child.restart_at is not None and now >= child.restart_at:
                old = self.pid(child)
                self._spawn(child)
                child.old_pids.append(old)
                log.warning("%s restarted as pid %d", child.spec.name, self.pid(child))
        return True

    def _schedule_restart(self, child: _Child, rc: int, now: float) -> bool:
        name, pid = child.spec.name, self.pid(child)
        what = describe_exit(rc)
        if rc in child.spec.fatal_exit_codes:
            log.error("%s (pid %d) %s: cannot be restarted; stopping", name, pid, what)
            self.exit_code = 1
            return False
        if rc == 0 or now - child.started_at >= self.stable_s:
            child.quick_deaths = 0
        delay = min(self.backoff_s * 2**child.quick_deaths, self.max_backoff_s)
        if rc != 0:
            child.quick_deaths += 1
            if child.quick_deaths >= self.give_up_after:
                log.error(
                    "%s (pid %d) %s; it died %d times in a row within %.0f s of its start: "
                    "giving up, stopping everything",
                    name, pid, what, child.quick_deaths, self.stable_s,
                )  # fmt: skip
                self.exit_code = 1
                return False
        log.warning("%s (pid %d) %s; restarting it in %.1f s", name, pid, what, delay)
        child.restart_at = now + delay
        return True

    def run(self, should_stop: Callable[[], bool]) -> int:
        """Supervise until ``should_stop()`` or giving up, then :meth:`stop` everything.
        Returns the exit code: 0, or 1 when the supervisor gave up."""
        try:
            while not should_stop():
                if not self.check():
                    break
                time.sleep(self.poll_s)
        finally:
            self.stop()
        return self.exit_code

    def stop(self) -> None:
        """SIGTERM every child, SIGKILL (its whole process group) what is left after
        ``stop_timeout_s``, then sweep each child's process group."""
        running = [(c.spec.name, c.proc) for c in self.children if c.proc is not None]
        for c in self.children:
            c.restart_at = None
        for _, p in running:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        deadline = time.monotonic() + self.stop_timeout_s
        for name, p in running:
            try:
                p.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                log.warning(
                    "%s (pid %d) did not stop in %g s: SIGKILL", name, p.pid, self.stop_timeout_s
                )
                signal_group(p.pid, signal.SIGKILL)
                p.wait()
        for _, p in running:
            signal_group(p.pid, signal.SIGKILL)


@contextmanager
def stop_requested(signals: Sequence[int] = STOP_SIGNALS) -> Iterator[Callable[[], bool]]:
    """Within the block, SIGTERM / SIGINT / SIGHUP only set a flag; yields a function that
    tells whether one came. A signal that was ignored when the block began (e.g. SIGHUP under
    ``nohup``) stays ignored. The previous handlers come back on exit."""
    received: list[int] = []

    def handler(signum: int, _frame: FrameType | None) -> None:
        if not received:
            log.warning("%s received: stopping", signal.Signals(signum).name)
        received.append(signum)

    previous: dict[int, object] = {}
    for sig in signals:
        current = signal.getsignal(sig)
        if current == signal.SIG_IGN and sig != signal.SIGTERM:
            continue
        previous[sig] = signal.signal(sig, handler)
    try:
        yield lambda: bool(received)
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)  # type: ignore[arg-type]
