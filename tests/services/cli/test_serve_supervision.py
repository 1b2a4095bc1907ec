"""``legopt serve`` / ``demo`` supervise their processes and leave nothing behind (issue 8, defects
8 and 12): a killed worker is restarted, SIGTERM stops everything and exits 0, SIGKILL of
``serve`` or ``demo`` leaves no orphan, and every file under the data directory is private.

Real processes: ``python -m services.cli serve`` with its data directory in a temp directory and
the short leases of ``tests/integration/stack.py``; descendants are found with psutil. The unit
tests at the end drive :class:`services.supervisor.Supervisor` on tiny ``python -c`` children.
"""

from __future__ import annotations

import logging
import os
import signal
import stat
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import psutil
import pytest
import yaml

from services.client import TERMINAL, Client
from services.supervisor import ChildSpec, Supervisor, describe_exit
from tests.integration.stack import ROOT, free_port
from tests.patience import Patience

START_TIMEOUT_S = 120.0  # the service answers /health and runs all its workers
GONE_TIMEOUT_S = 30.0  # every descendant has exited after a stop or a kill
JOB_TIMEOUT_S = 240.0


def _wait(pred: Callable[[], Any], timeout_s: float, what: str, log: Path | None = None) -> Any:
    """Poll ``pred`` every 0.2 s until it returns a true value; fail naming ``what``."""
    patience = Patience(timeout_s)
    while True:
        value = pred()
        if value:
            return value
        if patience.expired():
            tail = log.read_text(errors="replace")[-4000:] if log and log.exists() else ""
            raise AssertionError(f"timeout ({patience}) waiting for {what}\n{tail}")
        time.sleep(0.2)


def _env(tmp: Path) -> dict[str, str]:
    env = dict(os.environ)
    for k in list(env):
        if k.startswith("LEGOPT_"):
            del env[k]
    env.update(
        LEGOPT_DATA_DIR=str(tmp / "data"),  # created by serve itself (its mode is checked)
        LEGOPT_LEASE_SECONDS="4",
        LEGOPT_HEARTBEAT_SECONDS="1",
        LEGOPT_CHECKPOINT_EVERY="1",
        LEGOPT_WORKER_WARMUP="false",  # not under test here; the demo test keeps it on
        NUMBA_NUM_THREADS="1",
        PYTHONUNBUFFERED="1",
    )
    return env


def _is_worker(p: psutil.Process) -> bool:
    try:
        cmd = p.cmdline()
    except psutil.Error:
        return False
    return "celery" in cmd and "worker" in cmd


def _alive(procs: list[psutil.Process]) -> list[psutil.Process]:
    out = []
    for p in procs:
        try:
            if p.is_running() and p.status() != psutil.STATUS_ZOMBIE:
                out.append(p)
        except psutil.NoSuchProcess:
            pass
    return out


class Service:
    """One ``python -m services.cli ARGS`` process tree (serve or demo) with its log;
    ``launcher``: another command prefix (``python3 run.py legopt``)."""

    def __init__(
        self, tmp: Path, args: list[str], log_name: str, launcher: list[str] | None = None
    ) -> None:
        self.tmp = tmp
        self.env = _env(tmp)
        self.log = tmp / log_name
        self.seen: dict[int, psutil.Process] = {}
        with self.log.open("ab") as out:
            self.proc = subprocess.Popen(
                [*(launcher or [sys.executable, "-m", "services.cli"]), *args],
                env=self.env, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT,
            )  # fmt: skip
        self.root = psutil.Process(self.proc.pid)

    def descendants(self) -> list[psutil.Process]:
        """The live descendants now (remembered, to check later that they are gone)."""
        try:
            kids = self.root.children(recursive=True)
        except psutil.NoSuchProcess:
            kids = []
        for k in kids:
            self.seen.setdefault(k.pid, k)
        return _alive(kids)

    def workers(self) -> list[psutil.Process]:
        return [p for p in self.descendants() if _is_worker(p)]

    def assert_all_gone(self) -> None:
        _wait(
            lambda: not _alive(list(self.seen.values())),
            GONE_TIMEOUT_S,
            "every process of the service to exit; alive: "
            + str([(p.pid, p.cmdline()[:6]) for p in _alive(list(self.seen.values()))]),
            self.log,
        )

    def cleanup(self) -> None:
        """Kill whatever is left (a failed test must not leak processes)."""
        self.descendants()
        for p in [self.root, *self.seen.values()]:
            try:
                p.kill()  # psutil checks the pid was not reused
            except psutil.Error:
                pass
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            pass


class Serve(Service):
    def __init__(
        self,
        tmp: Path,
        workers: int = 2,
        api_workers: int = 1,
        log_name: str = "serve.log",
        stop_timeout_s: float = 10.0,
        launcher: list[str] | None = None,
    ) -> None:
        self.port = free_port()
        args = ["serve", "--workers", str(workers), "--api-workers", str(api_workers)]
        args += ["--stop-timeout", str(stop_timeout_s), "--port", str(self.port)]
        super().__init__(tmp, args, log_name, launcher)
        self.url = f"http://127.0.0.1:{self.port}"
        self.n_workers = workers

    def wait_ready(self) -> None:
        def ready() -> bool:
            if self.proc.poll() is not None:
                raise AssertionError(f"serve exited: {self.log.read_text()[-3000:]}")
            try:
                up = httpx.get(f"{self.url}/api/v1/health", timeout=2).status_code == 200
            except httpx.HTTPError:
                return False
            return up and len(self.workers()) >= self.n_workers

        _wait(ready, START_TIMEOUT_S, "serve to answer /health with all its workers", self.log)
        self.descendants()

    def client(self) -> Client:
        key = (self.tmp / "data" / "api-key").read_text().strip()
        return Client(self.url, key, timeout=30)

    def stop(self, sig: int) -> int | None:
        """Send ``sig`` to serve; its exit code (None for SIGKILL: nothing to wait for)."""
        self.descendants()
        self.proc.send_signal(sig)
        try:
            return self.proc.wait(GONE_TIMEOUT_S + 30)
        except subprocess.TimeoutExpired:
            raise AssertionError(f"serve still runs after {sig!r}") from None


@pytest.fixture
def services(tmp_path: Path) -> Iterator[list[Service]]:
    started: list[Service] = []
    yield started
    for s in started:
        s.cleanup()


def _spec(generations: int) -> dict[str, Any]:
    spec = yaml.safe_load((ROOT / "examples" / "000_swing_energy_flat.yaml").read_text())
    spec["budget"] = {"generations": generations}
    spec["record"] = False
    return dict(spec)


def _job(c: Client, job_id: str, pred: Callable[[dict[str, Any]], bool], log: Path) -> Any:
    def check() -> Any:
        job = c.job(job_id)
        return job if pred(job) else None

    return _wait(check, JOB_TIMEOUT_S, f"job {job_id}", log)


def _assert_private(root: Path) -> None:
    """No file or directory under ``root`` (nor ``root``) is readable by group or others."""
    loose = [
        f"{p.relative_to(root.parent)} {stat.filemode(p.lstat().st_mode)}"
        for p in [root, *root.rglob("*")]
        if p.lstat().st_mode & 0o077
    ]
    assert not loose, f"group/world-accessible under the data directory: {loose}"


@pytest.mark.integration
def test_killed_workers_are_restarted_files_private_sigterm_exits_0(
    tmp_path: Path, services: list[Service]
) -> None:
    serve = Serve(tmp_path)
    services.append(serve)
    serve.wait_ready()
    victims = serve.workers()
    assert len(victims) == 2, [p.cmdline() for p in victims]
    for v in victims:
        v.kill()
    old = {v.pid for v in victims}
    _wait(
        lambda: len([w for w in serve.workers() if w.pid not in old]) == 2,
        START_TIMEOUT_S,
        "two new worker processes after kill -9 of both",
        serve.log,
    )
    text = serve.log.read_text(errors="replace")
    # serve tells the user where the dashboard is (issue 10): its own address, the API and docs
    assert f"LegOpt dashboard on {serve.url}/  (API {serve.url}/api/v1, docs /api/v1/docs" in (
        text
    ), text[-3000:]
    for v in victims:
        assert f"(pid {v.pid}) was killed by SIGKILL; restarting it" in text, text[-3000:]
    with serve.client() as c:
        job_id = c.submit(_spec(3))["id"]
        job = _job(c, job_id, lambda j: j["status"] in TERMINAL, serve.log)
    assert job["status"] == "succeeded", job
    _assert_private(tmp_path / "data")
    assert serve.stop(signal.SIGTERM) == 0, serve.log.read_text()[-3000:]
    serve.assert_all_gone()


@pytest.mark.integration
def test_sigterm_mid_job_hands_it_back_and_sigkill_leaves_no_orphan(
    tmp_path: Path, services: list[Service]
) -> None:
    # 1 s to finish on shutdown: too short for this job, whose worker is then SIGKILLed
    first = Serve(tmp_path, log_name="serve1.log", stop_timeout_s=1.0)
    services.append(first)
    first.wait_ready()
    with first.client() as c:
        job_id = c.submit(_spec(80))["id"]
        _job(c, job_id, lambda j: j["status"] == "running" and j["generation"] >= 2, first.log)
    assert first.stop(signal.SIGTERM) == 0, first.log.read_text()[-3000:]
    first.assert_all_gone()
    assert "did not stop in 1 s: SIGKILL" in first.log.read_text()  # the busy worker
    # a second serve on the same data: the job was handed back through its lease (not failed
    # by the shutdown) and is resumed from its checkpoint
    second = Serve(tmp_path, api_workers=2, log_name="serve2.log")
    services.append(second)
    second.wait_ready()
    with second.client() as c:
        job = _job(c, job_id, lambda j: j["status"] in TERMINAL, second.log)
    assert job["status"] == "succeeded", job
    assert job["attempts"] == 2, job
    assert any("resumed from the checkpoint" in w for w in job["warnings"]), job["warnings"]
    # kill -9 of uvicorn's own supervisor: its API processes do not outlive it, a new API serves
    (master,) = [p for p in second.root.children() if "uvicorn" in p.cmdline()]
    api_procs = _wait(lambda: master.children(), 30, "uvicorn's API processes", second.log)
    master.kill()
    _wait(lambda: not _alive(api_procs), GONE_TIMEOUT_S, "the API processes to exit", second.log)
    second.wait_ready()
    assert second.stop(signal.SIGKILL) == -signal.SIGKILL
    second.assert_all_gone()


@pytest.mark.integration
def test_ctrl_c_stops_serve_and_its_workers(tmp_path: Path, services: list[Service]) -> None:
    """SIGINT (Ctrl-C in the terminal) stops like SIGTERM: exit 0, no process left."""
    serve = Serve(tmp_path, log_name="serve-int.log")
    services.append(serve)
    serve.wait_ready()
    assert len(serve.workers()) == 2
    assert serve.stop(signal.SIGINT) == 0, serve.log.read_text()[-3000:]
    serve.assert_all_gone()


@pytest.mark.integration
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_run_py_serve_stopped_leaves_no_process(
    tmp_path: Path, services: list[Service], sig: int
) -> None:
    """`python3 run.py legopt serve`, the documented start, stopped by a signal to run.py (kill,
    Ctrl-C): the signal reaches serve itself (run.py becomes it), which stops every process."""
    launcher = [sys.executable, str(ROOT / "run.py"), "legopt"]
    serve = Serve(tmp_path, workers=1, log_name="run-py-serve.log", launcher=launcher)
    services.append(serve)
    serve.wait_ready()
    assert serve.workers(), "serve runs its worker"
    assert serve.stop(sig) == 0, serve.log.read_text()[-3000:]
    serve.assert_all_gone()


@pytest.mark.integration
def test_demo_killed_leaves_no_process(tmp_path: Path, services: list[Service]) -> None:
    port = free_port()
    demo = Service(
        tmp_path,
        ["demo", "--workers", "1", "--port", str(port), "--examples", "000_swing_energy_flat*"],
        "demo.log",
    )
    services.append(demo)

    def up() -> bool:
        try:
            ok = httpx.get(f"http://127.0.0.1:{port}/api/v1/health", timeout=2).status_code == 200
        except httpx.HTTPError:
            return False
        return ok and bool(demo.workers())

    _wait(up, START_TIMEOUT_S, "demo's service to answer with its worker", demo.log)
    demo.descendants()
    demo.proc.send_signal(signal.SIGKILL)
    demo.proc.wait(30)
    demo.assert_all_gone()


# ---------------------------------------------------------------------- the supervisor itself


def _py(code: str) -> list[str]:
    return [sys.executable, "-c", code]


def _supervise(sup: Supervisor, until: Callable[[], bool], timeout_s: float = 30.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not until():
        assert sup.check(), "the supervisor gave up"
        assert time.monotonic() < deadline, "timeout"
        time.sleep(0.05)


def test_supervisor_restarts_a_child_that_exits_0_with_a_log_line(
    caplog: pytest.LogCaptureFixture,
) -> None:
    sup = Supervisor([ChildSpec("w", _py("pass"))], backoff_s=0.01)
    caplog.set_level(logging.INFO, "legopt.supervisor")
    sup.start()
    try:
        _supervise(sup, lambda: len(sup.children[0].old_pids) >= 2)
    finally:
        sup.stop()
    first = sup.children[0].old_pids[0]
    assert f"w (pid {first}) exited with code 0; restarting it in" in caplog.text
    assert "w restarted as pid" in caplog.text
    assert sup.children[0].quick_deaths == 0  # exit 0 is not a failure: no growing backoff


def test_supervisor_gives_up_on_a_child_that_keeps_crashing() -> None:
    sup = Supervisor([ChildSpec("bad", _py("raise SystemExit(7)"))], backoff_s=0.01,
                     give_up_after=3)  # fmt: skip
    sup.start()
    assert sup.run(lambda: False) == 1
    assert len(sup.children[0].old_pids) == 2


def test_supervisor_stop_escalates_to_sigkill_of_the_group() -> None:
    stubborn = "import signal, time; signal.signal(signal.SIGTERM, signal.SIG_IGN); time.sleep(60)"
    spawner = f"import subprocess, sys, time; subprocess.Popen([sys.executable, '-c', {stubborn!r}]); time.sleep(60)"  # noqa: E501
    sup = Supervisor([ChildSpec("s", _py(stubborn)), ChildSpec("p", _py(spawner))],
                     stop_timeout_s=1.0)  # fmt: skip
    sup.start()
    procs = [psutil.Process(pid) for pid in sup.pids().values()]
    grandchildren = _wait(procs[1].children, 30, "the grandchild")
    sup.stop()
    _wait(lambda: not _alive(procs + grandchildren), GONE_TIMEOUT_S, "children and grandchild")


def test_describe_exit() -> None:
    assert describe_exit(-9) == "was killed by SIGKILL"
    assert describe_exit(0) == "exited with code 0"
    assert describe_exit(2) == "exited with code 2"
