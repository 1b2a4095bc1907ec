"""The artifact store on a local directory (the embedded default: ``LEGOPT_ARTIFACT_DIR``).

Layout: ``<root>/<job_id>/<attempt>/<kind><suffix>``, e.g.
``<root>/<job id>/a2-3f9c01/recording.rrd``: each attempt of a worker at a job writes under its
own directory, and its files become the job's only when the worker's lease-checked
``finish_job`` records their relative path (always ``/``-separated) with the SHA-256 and the
size. A stale worker that lost its lease can therefore never overwrite the winner's files; it
removes its own attempt directory (``delete_attempt``). Files stored without an attempt go to
``<root>/<job_id>/<kind><suffix>``. Writes are atomic: bytes go to a temporary file in the
target directory, are fsync'ed, then ``os.replace``d over the final name, so a reader sees the
old file or the new one, never half of one. Reads verify the checksum when one is given. Paths
that would leave the root (absolute, ``..``, symlinks out) are rejected with
``UnsafePathError``; a recorded file that is gone raises ``ArtifactMissingError``.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

from services.store.artifacts.base import (
    CHUNK,
    ArtifactStore,
    Source,
    StoredFile,
    check_digest,
    check_relative,
    safe_name,
    sha256_file,
)
from services.store.errors import ArtifactMissingError, UnsafePathError
from services.store.settings import Settings


def _fsync_dir(path: Path) -> None:
    """Persist a rename in ``path`` (no-op where directories cannot be opened, e.g. Windows)."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


@contextlib.contextmanager
def _missing_as_error(relative_path: str) -> Iterator[None]:
    """A file that is gone (or a directory where a file was) -> ArtifactMissingError."""
    try:
        yield
    except (FileNotFoundError, IsADirectoryError, NotADirectoryError):
        raise ArtifactMissingError(
            f"artifact {relative_path!r} is missing from the artifact directory"
        ) from None


class LocalArtifactStore(ArtifactStore):
    """Files of jobs under one root directory (created on first write)."""

    def __init__(self, root: str | os.PathLike[str]) -> None:
        self.root = Path(root)
        self.location = str(self.root)

    @classmethod
    def from_settings(cls, settings: Settings) -> LocalArtifactStore:
        """The store at ``settings.artifact_dir`` (whatever ``artifacts_url`` says)."""
        return cls(settings.artifact_dir)

    def path(self, relative_path: str) -> Path:
        """Absolute path of a stored file; UnsafePathError if it would leave the root."""
        rel = check_relative(relative_path)
        root = self.root.resolve()
        target = (root / Path(*rel.parts)).resolve()
        if target == root or not target.is_relative_to(root):
            raise UnsafePathError(f"artifact path {relative_path!r} leaves the artifact directory")
        return target

    def local_path(self, relative_path: str) -> Path | None:
        return self.path(relative_path)

    # ------------------------------------------------------------------ writing

    def put(
        self,
        job_id: str,
        kind: str,
        src: Source,
        *,
        suffix: str | None = None,
        attempt: str | None = None,
    ) -> StoredFile:
        if suffix is None and isinstance(src, str | os.PathLike):
            suffix = Path(src).suffix or None
        rel = self.relative_path(job_id, kind, suffix, attempt)
        target = self.path(rel)
        target.parent.mkdir(parents=True, exist_ok=True)
        digest = hashlib.sha256()
        size = 0
        fd, tmp_name = tempfile.mkstemp(prefix=".tmp-", suffix=".part", dir=target.parent)
        try:
            with os.fdopen(fd, "wb") as out, _reader(src) as reader:
                for chunk in iter(lambda: reader.read(CHUNK), b""):
                    digest.update(chunk)
                    size += len(chunk)
                    out.write(chunk)
                out.flush()
                os.fsync(out.fileno())
            os.replace(tmp_name, target)
        except BaseException:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp_name)
            raise
        _fsync_dir(target.parent)
        return StoredFile(rel, digest.hexdigest(), size)

    # ------------------------------------------------------------------ reading

    def verify(self, relative_path: str, sha256: str) -> int:
        path = self.path(relative_path)
        with _missing_as_error(relative_path):
            check_digest(relative_path, sha256_file(path), sha256)
            return path.stat().st_size

    def read(self, relative_path: str, sha256: str | None = None) -> bytes:
        path = self.path(relative_path)
        with _missing_as_error(relative_path):
            data = path.read_bytes()
        if sha256 is not None:
            check_digest(relative_path, hashlib.sha256(data).hexdigest(), sha256)
        return data

    def open(self, relative_path: str, sha256: str | None = None) -> BinaryIO:
        if sha256 is not None:
            self.verify(relative_path, sha256)
        path = self.path(relative_path)
        with _missing_as_error(relative_path):
            return open(path, "rb")

    def exists(self, relative_path: str) -> bool:
        return self.path(relative_path).is_file()

    def size(self, relative_path: str) -> int:
        path = self.path(relative_path)
        with _missing_as_error(relative_path):
            if not path.is_file():
                raise FileNotFoundError(relative_path)
            return path.stat().st_size

    def open_range(self, relative_path: str, start: int, stop: int) -> Iterator[bytes]:
        path = self.path(relative_path)
        with _missing_as_error(relative_path):
            f = open(path, "rb")
        return _chunks(f, start, stop)

    @contextlib.contextmanager
    def local_copy(self, relative_path: str, sha256: str | None = None) -> Iterator[Path]:
        if sha256 is not None:
            self.verify(relative_path, sha256)
        elif not self.exists(relative_path):
            raise ArtifactMissingError(
                f"artifact {relative_path!r} is missing from the artifact directory"
            )
        yield self.path(relative_path)

    # ------------------------------------------------------------------ removing

    def delete_attempt(self, job_id: str, attempt: str) -> None:
        directory = self.path(f"{safe_name(job_id, 'job id')}/{safe_name(attempt, 'attempt')}")
        shutil.rmtree(directory, ignore_errors=True)

    def prune_attempts(self, job_id: str, keep: str) -> None:
        directory = self.path(safe_name(job_id, "job id"))
        keep = safe_name(keep, "attempt")
        if not directory.is_dir():
            return
        for child in directory.iterdir():
            if child.is_dir() and not child.is_symlink() and child.name != keep:
                shutil.rmtree(child, ignore_errors=True)

    def delete_job(self, job_id: str) -> None:
        directory = self.path(safe_name(job_id, "job id"))
        shutil.rmtree(directory, ignore_errors=True)


@contextlib.contextmanager
def _reader(src: Source) -> Iterator[BinaryIO]:
    if isinstance(src, bytes | bytearray | memoryview):
        yield io.BytesIO(bytes(src))
    elif isinstance(src, str | os.PathLike):
        with open(src, "rb") as f:
            yield f
    else:
        yield src


def _chunks(f: BinaryIO, start: int, stop: int) -> Iterator[bytes]:
    with f:
        f.seek(start)
        left = stop - start
        while left > 0:
            chunk = f.read(min(CHUNK, left))
            if not chunk:
                return
            left -= len(chunk)
            yield chunk


__all__ = ["LocalArtifactStore"]
