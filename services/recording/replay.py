"""Replay of a stored ``.rrd``: the native viewer, or the bundled web viewer in a child process
bound to 127.0.0.1 to which this process pushes the file."""

from __future__ import annotations

import importlib.util
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import IO, TYPE_CHECKING
from urllib.parse import quote

import rerun as rr
import rerun.blueprint as rrb
import rerun_bindings
from rerun.chunk import RrdReader

from services.recording.blueprint import blueprint_for, read_entities
from services.recording.writer import APP_ID, _with_default_blueprint, release_streams

if TYPE_CHECKING:
    pass

# ---------------------------------------------------------------------------------------------
# replay
# ---------------------------------------------------------------------------------------------

__all__ = [
    "ViewerHandle",
    "has_display",
    "open_viewer",
    "rerun_binary",
    "serve_web",
    "viewer_url",
]


def has_display() -> bool:
    """True where a native viewer window can open (macOS/Windows, or DISPLAY/WAYLAND_DISPLAY)."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def rerun_binary() -> str:
    """Path of the Rerun viewer/CLI executable bundled with rerun-sdk (``RERUN_CLI_PATH``
    overrides). The ``rerun`` console script is a Python wrapper whose child would outlive a
    terminated wrapper, so the binary is run directly."""
    env = os.environ.get("RERUN_CLI_PATH")
    if env:
        return env
    spec = importlib.util.find_spec("rerun_cli")
    if spec is not None and spec.origin:
        exe = Path(spec.origin).parent / ("rerun.exe" if sys.platform == "win32" else "rerun")
        if exe.exists():
            return str(exe)
    found = shutil.which("rerun")
    if found:
        return found
    raise FileNotFoundError("the rerun viewer binary was not found (is rerun-sdk installed?)")


def viewer_url(web_port: int, grpc_url: str, host: str = "127.0.0.1") -> str:
    """The web viewer page that connects to ``grpc_url``."""
    return f"http://{host}:{web_port}/?url={quote(grpc_url, safe='')}"


@dataclass
class ViewerHandle:
    """A viewer running in a child process: ``url`` is the web viewer page (None for the
    native viewer). ``wait()`` blocks until it exits, ``stop()`` ends it; usable in ``with``."""

    process: subprocess.Popen[bytes]
    url: str | None
    log: IO[bytes] | None = None

    def wait(self, timeout: float | None = None) -> int:
        return self.process.wait(timeout)

    def stop(self, timeout: float = 5.0) -> None:
        """Terminate the viewer process (SIGTERM, then SIGKILL after ``timeout`` s)."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout)
        if self.log is not None:
            self.log.close()

    def __enter__(self) -> ViewerHandle:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def _free_port(host: str = "127.0.0.1") -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])


def _push(path: Path, grpc_url: str) -> None:
    """Send the recording ``path`` (with its blueprint, rebuilt from its entities) to the gRPC
    server at ``grpc_url``; the server keeps it for viewers that connect later."""
    reader = RrdReader(path)
    stores = reader.recordings()
    rid = stores[0].recording_id if stores else str(uuid.uuid4())
    ents = read_entities(path)
    jobs = sorted({e.split("/")[1] for e in ents if e.startswith("jobs/") and e.count("/") >= 2})
    try:
        _push_stream(reader, rid, grpc_url, blueprint_for(ents, jobs=jobs))
    finally:
        release_streams()


def _push_stream(reader: RrdReader, rid: str, grpc_url: str, blueprint: rrb.Blueprint) -> None:
    stream = rr.RecordingStream(APP_ID, recording_id=rid)  # dropped when this returns
    try:
        _with_default_blueprint(
            blueprint, lambda bp: rerun_bindings.connect_grpc(grpc_url, bp, stream.to_native())
        )
        stream.send_chunks(c for c in reader.stream() if not c.entity_path.startswith("/__"))
        stream.flush()
    finally:
        stream.disconnect()


def serve_web(
    path: Path,
    port: int | None = 9090,
    *,
    grpc_port: int | None = None,
    bind: str = "127.0.0.1",
    timeout: float = 30.0,
) -> ViewerHandle:
    """Serve the recording ``path`` in the Rerun web viewer on ``http://<bind>:<port>/``.

    Starts the bundled ``rerun --serve-web`` (web viewer over HTTP + a gRPC proxy on
    ``grpc_port``; both bound to ``bind``, free ports when None) in a child process, waits until
    the page answers HTTP 200, then sends the file's data and blueprint to the proxy, which
    keeps them for every browser that connects. Returns the handle (``handle.url`` is the page
    to open; ``handle.stop()`` or a ``with`` block ends the server).

    (The file is pushed from here instead of passed to ``rerun --serve-web FILE`` because that
    file loader keeps a core busy for as long as it serves.)
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"recording not found: {path}")
    port = port or _free_port(bind)
    grpc_port = grpc_port or _free_port(bind)
    cmd = [
        rerun_binary(),
        "--serve-web",
        "--bind",
        bind,
        "--web-viewer-port",
        str(port),
        "--port",
        str(grpc_port),
    ]
    log = tempfile.TemporaryFile()  # not a pipe: a long session must never block on its log
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT)
    host = "127.0.0.1" if bind in ("0.0.0.0", "::") else bind  # noqa: S104
    grpc_url = f"rerun+http://{host}:{grpc_port}/proxy"
    handle = ViewerHandle(proc, viewer_url(port, grpc_url, host), log)
    try:
        _wait_http(f"http://{host}:{port}/", proc, timeout, log)
        _push(path, grpc_url)
    except BaseException:
        handle.stop()
        raise
    return handle


def _wait_http(url: str, proc: subprocess.Popen[bytes], timeout: float, log: IO[bytes]) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            log.seek(0)
            err = log.read().decode(errors="replace")
            raise RuntimeError(
                f"rerun web viewer exited ({proc.returncode}): {err.strip()[-2000:]}"
            )
        try:
            with urllib.request.urlopen(url, timeout=1.0) as r:
                if r.status == 200:
                    return
        except (urllib.error.URLError, OSError):
            pass
        time.sleep(0.1)
    raise TimeoutError(f"rerun web viewer did not answer at {url} within {timeout} s")


def open_viewer(path: Path, *, web: bool | None = None, port: int = 9090) -> ViewerHandle:
    """Open the recording ``path``: the native Rerun viewer (``rerun FILE``) where there is a
    display, else (or with ``web=True``) the web viewer served on ``127.0.0.1:port`` from a
    child process. Returns the handle: ``handle.url`` is the page to open (web), ``wait()``
    blocks until the viewer exits, ``stop()`` ends it."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"recording not found: {path}")
    if web is None:
        web = not has_display()
    if web:
        return serve_web(path, port)
    proc = subprocess.Popen([rerun_binary(), str(path)])
    return ViewerHandle(proc, None)
