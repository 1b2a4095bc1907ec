"""A real S3 API server for tests: moto's server mode (``python -m moto.server``) started as a
subprocess on 127.0.0.1 and a free port, reached over HTTP like a remote object store (not an
in-process patch). Tests that use it skip, saying why, when moto is not installed."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest

#: Credentials and region the server accepts (moto accepts any); set for boto3's chain.
AWS_ENV = {
    "AWS_ACCESS_KEY_ID": "testing",
    "AWS_SECRET_ACCESS_KEY": "testing",
    "AWS_DEFAULT_REGION": "us-east-1",
    "AWS_REGION": "us-east-1",
}
#: Longest the server may take to answer its first request (s).
START_TIMEOUT_S = 60.0


def require_moto() -> None:
    """Skip the calling test (or module) when moto's server is not installed."""
    pytest.importorskip("moto.server", reason="moto[server] is not installed (the dev extra)")
    pytest.importorskip("boto3", reason="boto3 is not installed")


def free_port() -> int:
    """A TCP port nothing listens on now (127.0.0.1)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _die_with_parent() -> None:
    """In the child: SIGTERM when the test process dies (a killed run leaves no server)."""
    import ctypes
    import signal

    ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


@contextmanager
def moto_server() -> Iterator[str]:
    """Start moto's S3 server; yield its endpoint URL once it answers; stop it after."""
    require_moto()
    port = free_port()
    log = tempfile.TemporaryFile()  # the server logs every request: never a full pipe
    proc = subprocess.Popen(
        [sys.executable, "-m", "moto.server", "-H", "127.0.0.1", "-p", str(port)],
        stdout=subprocess.DEVNULL,
        stderr=log,
        env={**os.environ, **AWS_ENV},
        preexec_fn=_die_with_parent if sys.platform == "linux" else None,
    )
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + START_TIMEOUT_S
        while True:  # poll until it answers (no fixed sleep)
            if proc.poll() is not None:
                log.seek(0)
                err = log.read().decode(errors="replace")
                raise RuntimeError(f"moto server exited ({proc.returncode}): {err[-500:]}")
            try:
                with urllib.request.urlopen(f"{url}/moto-api/", timeout=1):
                    break
            except (urllib.error.URLError, ConnectionError, TimeoutError) as exc:
                if time.monotonic() > deadline:
                    raise RuntimeError(
                        f"moto server did not answer in {START_TIMEOUT_S} s"
                    ) from exc
                time.sleep(0.05)
        yield url
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        log.close()


def s3_client(endpoint: str) -> Any:
    """A boto3 client of the server (its own credentials, not the environment's)."""
    import boto3

    return boto3.client(
        "s3",
        endpoint_url=endpoint,
        region_name=AWS_ENV["AWS_REGION"],
        aws_access_key_id=AWS_ENV["AWS_ACCESS_KEY_ID"],
        aws_secret_access_key=AWS_ENV["AWS_SECRET_ACCESS_KEY"],
    )


def aws_env(monkeypatch: pytest.MonkeyPatch) -> None:
    """Credentials of the test server for boto3's chain; no profile or config file of the
    machine's user is read."""
    for name, value in AWS_ENV.items():
        monkeypatch.setenv(name, value)
    for name in ("AWS_PROFILE", "AWS_SESSION_TOKEN", "AWS_ENDPOINT_URL", "AWS_ENDPOINT_URL_S3"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("AWS_CONFIG_FILE", os.devnull)
    monkeypatch.setenv("AWS_SHARED_CREDENTIALS_FILE", os.devnull)
