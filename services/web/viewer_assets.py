"""The Rerun web viewer (``re_viewer.js`` + ``re_viewer_bg.wasm``), served by the API itself.

The viewer must be the one of the installed rerun-sdk (a recording opens only in a viewer of
its own version, and npm has no viewer of every SDK version). rerun-sdk keeps its web viewer
inside its native binary and serves it only over HTTP (``rerun --serve-web``), so on first use
the API starts that server on a free loopback port for a moment, downloads the two files from
it into ``<data_dir>/web-viewer/<rerun version>/`` (atomically) and stops it; from then on the
files are plain static files. Nothing is fetched from the internet, and no viewer server keeps
running. The viewer's own page loads web fonts from a CDN and is not used: the dashboard has
its own page (``static/viewer.html``) that boots the same module.
"""

from __future__ import annotations

import os
import socket
import subprocess
import tempfile
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path

__all__ = ["FILES", "ViewerAssetsError", "ensure_viewer_assets", "rerun_version"]

#: The viewer's files, as ``rerun --serve-web`` serves them.
FILES = ("re_viewer.js", "re_viewer_bg.wasm")
#: Longest wait for the temporary viewer server (s).
START_TIMEOUT_S = 60.0

_lock = threading.Lock()


class ViewerAssetsError(RuntimeError):
    """The web viewer's files could not be obtained from the installed rerun-sdk."""


def rerun_version() -> str:
    """The installed rerun-sdk's version (the cache directory's name)."""
    from importlib.metadata import version

    return version("rerun-sdk")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _fetch(url: str, target: Path) -> None:
    tmp = target.with_name(f".{target.name}.{os.getpid()}.part")
    try:
        with urllib.request.urlopen(url, timeout=60) as r, open(tmp, "wb") as out:  # noqa: S310
            while chunk := r.read(1 << 20):
                out.write(chunk)
        os.replace(tmp, target)
    finally:
        tmp.unlink(missing_ok=True)


def _extract(target: Path) -> None:
    from services.recording.replay import rerun_binary

    port, grpc = _free_port(), _free_port()
    cmd = [rerun_binary(), "--serve-web", "--bind", "127.0.0.1", "--web-viewer-port", str(port),
           "--port", str(grpc)]  # fmt: skip
    with tempfile.TemporaryFile() as log:
        proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT)
        try:
            base = f"http://127.0.0.1:{port}"
            deadline = time.monotonic() + START_TIMEOUT_S
            while True:
                if proc.poll() is not None:
                    log.seek(0)
                    raise ViewerAssetsError(
                        f"rerun --serve-web exited ({proc.returncode}): {log.read()[-500:]!r}"
                    )
                try:
                    with urllib.request.urlopen(f"{base}/", timeout=2):  # noqa: S310
                        break
                except (urllib.error.URLError, OSError):
                    if time.monotonic() > deadline:
                        raise ViewerAssetsError("rerun --serve-web did not answer") from None
                    time.sleep(0.1)
            for name in FILES:
                _fetch(f"{base}/{name}", target / name)
        finally:
            proc.terminate()
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


def ensure_viewer_assets(data_dir: Path) -> Path:
    """The directory holding :data:`FILES` for the installed rerun-sdk, extracted on first
    call (under ``data_dir``, or the temporary directory when that is not writable)."""
    version = rerun_version()
    candidates = [Path(data_dir) / "web-viewer" / version,
                  Path(tempfile.gettempdir()) / f"legopt-web-viewer-{version}"]  # fmt: skip
    with _lock:
        for directory in candidates:
            if all((directory / f).is_file() for f in FILES):
                return directory
        errors = []
        for directory in candidates:
            try:
                directory.mkdir(parents=True, exist_ok=True)
                _extract(directory)
                return directory
            except OSError as exc:
                errors.append(f"{directory}: {exc}")
        raise ViewerAssetsError("; ".join(errors))
