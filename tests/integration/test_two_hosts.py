"""Two hosts, nothing shared but the database, the broker and an object store (issue 20).

The layout of a user who outgrows one machine: an API "host" and two worker "hosts", each with
its own private data directory (``LEGOPT_DATA_DIR``, ``LEGOPT_ARTIFACT_DIR``, ``TMPDIR``: no
shared file system), sharing only PostgreSQL, Redis and an S3 endpoint — moto's server mode,
started here on 127.0.0.1 and reached over HTTP as a remote store is (``tests/s3_server.py``).

1. A sweep runs across both worker hosts; every result and recording in the object store is
   byte-identical to the hash the database recorded, and the recordings the API serves too.
   No host's private directory keeps an artifact: they live in the object store only.
2. ``kill -9`` of the worker host running a long job mid-run: its lease expires and the job
   resumes on the other host from its checkpoint (checkpoints live in the database, which
   every host reaches), then its artifacts are in the store as above.
"""

from __future__ import annotations

import hashlib
import re
import shutil
import signal
import subprocess
import tempfile
import time
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pytest

from services.embedded import worker_command
from tests.chaos.dbview import DbView, Monitor, owner_pid
from tests.chaos.workload import job_spec
from tests.integration.stack import RedisServer, Stack, postgres_database, require_services
from tests.patience import Patience
from tests.s3_server import AWS_ENV, moto_server, require_moto, s3_client

pytestmark = pytest.mark.integration

BUCKET = "legopt-two-hosts"
PREFIX = "artifacts"
TERMINAL = {"succeeded", "failed", "cancelled"}


class TwoHosts(Stack):
    """A ``Stack`` whose workers run as separate "hosts": each its own private directories."""

    def __init__(self, tmp: Path, database_url: str, broker_url: str, endpoint: str) -> None:
        super().__init__("services", tmp, database_url, broker_url)
        self.env.update(AWS_ENV)
        self.env.update(
            LEGOPT_ARTIFACTS_URL=f"s3://{BUCKET}/{PREFIX}",
            LEGOPT_S3_ENDPOINT_URL=endpoint,
            AWS_CONFIG_FILE="/dev/null",
            AWS_SHARED_CREDENTIALS_FILE="/dev/null",
        )
        for name in ("AWS_PROFILE", "AWS_SESSION_TOKEN", "AWS_ENDPOINT_URL"):
            self.env.pop(name, None)
        self.tmpdirs: list[Path] = []
        self.env.update(self._private("api-host"))
        self.hosts: dict[int, str] = {}  # worker pid -> host name

    def _private(self, host: str) -> dict[str, str]:
        root = self.tmp / host
        for sub in ("data", "artifacts"):
            (root / sub).mkdir(parents=True, exist_ok=True)
        # a short temporary directory of its own: the validation forkserver's Unix socket lives
        # there, and a socket path may not exceed 107 bytes (pytest's tmp_path can)
        tmp = Path(tempfile.mkdtemp(prefix=f"legopt-{host}-"))
        self.tmpdirs.append(tmp)
        return {
            "LEGOPT_DATA_DIR": str(root / "data"),
            "LEGOPT_ARTIFACT_DIR": str(root / "artifacts"),
            "TMPDIR": str(tmp),
        }

    def stop(self) -> None:
        super().stop()
        for tmp in self.tmpdirs:
            shutil.rmtree(tmp, ignore_errors=True)

    def start_host_worker(self, host: str) -> subprocess.Popen[bytes]:
        """A solo worker on "host" ``host`` (its own directories); returns once it is ready."""
        env = {**self.env, **self._private(host)}
        log = self.logs / f"worker-{host}.log"
        proc = subprocess.Popen(
            worker_command(host, 1, "INFO"), env=env, cwd=Path(__file__).resolve().parents[2],
            stdout=open(log, "ab"), stderr=subprocess.STDOUT,  # noqa: SIM115 - closed with it
        )  # fmt: skip
        self.workers.append(proc)
        self.hosts[proc.pid] = host
        patience = Patience(90)
        while not re.search(r"@\S+ ready\.", log.read_text(errors="replace")):
            assert proc.poll() is None, f"worker {host} exited:\n{self.log_tail()}"
            assert not patience.expired(), f"worker {host} not ready in {patience}"
            time.sleep(0.05)
        return proc

    def host_of(self, owner: str | None) -> str | None:
        pid = owner_pid(owner)
        return None if pid is None else self.hosts.get(pid)


@pytest.fixture
def hosts(tmp_path: Path) -> Iterator[TwoHosts]:
    require_services()
    require_moto()
    redis = RedisServer(tmp_path)
    redis.start()
    try:
        with moto_server() as endpoint, postgres_database() as url:
            s3_client(endpoint).create_bucket(Bucket=BUCKET)
            st = TwoHosts(tmp_path, url, redis.url, endpoint)
            st.migrate_and_key()
            st.start_api()
            try:
                yield st
            finally:
                st.stop()
    finally:
        redis.stop()


def _wait(st: TwoHosts, what: str, pred: Any, timeout_s: float = 180.0) -> None:
    patience = Patience(timeout_s)
    while not pred():
        assert not patience.expired(), f"{what}: not in {patience}\n{st.log_tail()}"
        time.sleep(0.1)


def _artifacts_match(st: TwoHosts, view: DbView, job_ids: list[str]) -> None:
    """Every recorded artifact of ``job_ids`` is in the object store byte-identical to its
    hash; each recording the API serves is too; no host keeps a copy on its own disk."""
    s3 = s3_client(st.env["LEGOPT_S3_ENDPOINT_URL"])
    rows = view.artifact_rows(job_ids)
    kinds: dict[str, set[str]] = {j: set() for j in job_ids}
    for row in rows:
        body = s3.get_object(Bucket=BUCKET, Key=f"{PREFIX}/{row['relative_path']}")["Body"]
        data = body.read()
        assert hashlib.sha256(data).hexdigest() == row["sha256"], row
        assert len(data) == row["size_bytes"], row
        kinds[row["job_id"]].add(row["kind"])
    assert all(k == {"result", "recording"} for k in kinds.values()), kinds
    recorded = {(r["job_id"], r["kind"]): r["sha256"] for r in rows}
    with st.client() as c:
        for job_id in job_ids:
            served = c.recording(job_id)
            assert hashlib.sha256(served).hexdigest() == recorded[(job_id, "recording")]
            assert c.result(job_id)["objectives"] is not None  # from the database
    roots = [*(st.tmp / host for host in ("api-host", *st.hosts.values())), *st.tmpdirs]
    on_disk = [
        p
        for root in roots
        for p in root.rglob("*")
        if p.is_file() and any(j in str(p) for j in job_ids)
    ]
    assert not on_disk, f"artifacts left on a host's private disk: {on_disk}"


def test_a_sweep_across_two_hosts_and_a_killed_host_resumes_on_the_other(
    hosts: TwoHosts,
) -> None:
    st = hosts
    since = datetime.now(UTC)
    first = st.start_host_worker("host-a")
    second = st.start_host_worker("host-b")
    view = DbView(st.env["LEGOPT_DATABASE_URL"])
    monitor = Monitor(view, since)
    monitor.start()
    try:
        # 1. a sweep across both hosts
        spec = job_spec(generations=30, record=True)
        with st.client() as c:
            ids = [str(j) for j in c.sweep({"base": spec, "seeds": list(range(1, 7))})["job_ids"]]
        assert len(ids) == 6
        _wait(st, "the sweep drains", lambda: all(
            (o := monitor.state(j)) is not None and o.status in TERMINAL for j in ids
        ))  # fmt: skip
        rows = view.job_rows(ids)
        assert {r["status"] for r in rows} == {"succeeded"}, st.log_tail()
        ran_on = {st.host_of(o) for o in monitor.owners(ids)}
        assert ran_on == {"host-a", "host-b"}, ran_on
        _artifacts_match(st, view, ids)

        # 2. kill -9 the host running a long job mid-run: it resumes on the other host
        with st.client() as c:
            long_id = c.submit(job_spec(seed=42, generations=400, record=True))["id"]

        def running_past_3() -> bool:
            o = monitor.state(long_id)
            return o is not None and o.status == "running" and o.generation >= 3

        _wait(st, "the long job runs past generation 3", running_past_3)
        victim_owner = monitor.state(long_id).owner  # type: ignore[union-attr]
        victim = st.host_of(victim_owner)
        assert victim is not None, victim_owner
        proc = first if victim == "host-a" else second
        proc.send_signal(signal.SIGKILL)
        proc.wait(10)
        survivor = "host-b" if victim == "host-a" else "host-a"
        _wait(st, "the killed host's job finishes on the other", lambda: (
            (o := monitor.state(long_id)) is not None and o.status in TERMINAL
        ), timeout_s=300)  # fmt: skip
        (row,) = view.job_rows([long_id])
        assert row["status"] == "succeeded", st.log_tail()
        assert row["attempt_count"] == 2, row
        owners = {st.host_of(o) for o in monitor.owners([long_id])}
        assert owners == {victim, survivor}, owners
        with st.client() as c:
            warnings = c.job(long_id)["warnings"]
        resumed = [w for w in warnings if w.startswith("resumed from the checkpoint")]
        assert resumed, warnings
        generation = int(re.search(r"generation (\d+)", resumed[0]).group(1))  # type: ignore[union-attr]
        assert generation >= 3, resumed
        _artifacts_match(st, view, [long_id])
    except Exception as exc:  # a failure says what the hosts logged
        raise AssertionError(f"{type(exc).__name__}: {exc}\n{st.log_tail()}") from exc
    finally:
        monitor.stop()
        view.close()
