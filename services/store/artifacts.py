"""Artifact store on a local directory (``.rrd`` recordings, CSV exports).

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
``UnsafePathError``.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import os
import re
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path, PurePosixPath
from typing import BinaryIO, NamedTuple

from services.store.errors import ChecksumMismatchError, UnsafePathError
from services.store.settings import Settings

CHUNK = 1 << 20
KIND_SUFFIXES = {"recording": ".rrd", "csv": ".csv", "json": ".json"}
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,127}$")
_SUFFIX = re.compile(r"^(\.[A-Za-z0-9]{1,16})*$")


class StoredFile(NamedTuple):
    """Where ``ArtifactStore.put`` stored a file: ``(relative_path, sha256, size_bytes)``."""

    relative_path: str
    sha256: str
    size_bytes: int


def _safe_name(value: str, what: str) -> str:
    if not _NAME.match(value) or ".." in value:
        raise UnsafePathError(f"invalid {what} {value!r}: use letters, digits, '.', '_', '-'")
    return value


def sha256_file(path: str | os.PathLike[str]) -> str:
    """Hex SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(CHUNK), b""):
            digest.update(chunk)
    return digest.hexdigest()


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


class ArtifactStore:
    """Files of jobs under one root directory (created on first write)."""

    def __init__(self, root: str | os.PathLike[str]) -> None:
        self.root = Path(root)

    @classmethod
    def from_settings(cls, settings: Settings) -> ArtifactStore:
        """The store at ``settings.artifact_dir``."""
        return cls(settings.artifact_dir)

    # ------------------------------------------------------------------ paths

    def relative_path(
        self, job_id: str, kind: str, suffix: str | None = None, attempt: str | None = None
    ) -> str:
        """The relative path of a job's artifact of ``kind`` (validated), under the directory
        of ``attempt`` when given."""
        _safe_name(job_id, "job id")
        _safe_name(kind, "artifact kind")
        suffix = KIND_SUFFIXES.get(kind, ".bin") if suffix is None else suffix
        if not _SUFFIX.match(suffix):
            raise UnsafePathError(f"invalid file suffix {suffix!r}")
        if attempt is not None:
            return f"{job_id}/{_safe_name(attempt, 'attempt')}/{kind}{suffix}"
        return f"{job_id}/{kind}{suffix}"

    def path(self, relative_path: str) -> Path:
        """Absolute path of a stored file; UnsafePathError if it would leave the root."""
        if not relative_path or "\\" in relative_path or "\x00" in relative_path:
            raise UnsafePathError(f"invalid artifact path {relative_path!r}")
        rel = PurePosixPath(relative_path)
        if rel.is_absolute() or ".." in rel.parts or rel.as_posix() != relative_path:
            raise UnsafePathError(f"artifact path {relative_path!r} leaves the artifact directory")
        root = self.root.resolve()
        target = (root / Path(*rel.parts)).resolve()
        if target == root or not target.is_relative_to(root):
            raise UnsafePathError(f"artifact path {relative_path!r} leaves the artifact directory")
        return target

    # ------------------------------------------------------------------ writing

    def put(
        self,
        job_id: str,
        kind: str,
        src: str | os.PathLike[str] | bytes | BinaryIO,
        *,
        suffix: str | None = None,
        attempt: str | None = None,
    ) -> StoredFile:
        """Store ``src`` (a file path, bytes, or a binary stream) atomically as a job artifact.

        ``suffix`` defaults to the source file's suffix, else by kind (``.rrd`` for
        ``recording``, ``.csv`` for ``csv``, ``.bin`` otherwise); ``attempt`` puts it in that
        attempt's directory. Storing the same kind again replaces the file atomically.
        Returns ``(relative_path, sha256, size_bytes)``.
        """
        if suffix is None and isinstance(src, str | os.PathLike):
            suffix = Path(src).suffix or None
        rel = self.relative_path(job_id, kind, suffix, attempt)
        target = self.path(rel)
        target.parent.mkdir(parents=True, exist_ok=True)
        digest = hashlib.sha256()
        size = 0
        fd, tmp_name = tempfile.mkstemp(prefix=".tmp-", suffix=".part", dir=target.parent)
        try:
            with os.fdopen(fd, "wb") as out, self._reader(src) as reader:
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

    @staticmethod
    @contextlib.contextmanager
    def _reader(src: str | os.PathLike[str] | bytes | BinaryIO) -> Iterator[BinaryIO]:
        if isinstance(src, bytes | bytearray | memoryview):
            yield io.BytesIO(bytes(src))
        elif isinstance(src, str | os.PathLike):
            with open(src, "rb") as f:
                yield f
        else:
            yield src

    # ------------------------------------------------------------------ reading

    def verify(self, relative_path: str, sha256: str) -> None:
        """Raise ChecksumMismatchError unless the stored bytes hash to ``sha256``."""
        actual = sha256_file(self.path(relative_path))
        if actual != sha256.lower():
            raise ChecksumMismatchError(
                f"artifact {relative_path!r} is corrupted: sha256 {actual} != recorded {sha256}"
            )

    def read(self, relative_path: str, sha256: str | None = None) -> bytes:
        """The stored bytes, verified against ``sha256`` when given."""
        data = self.path(relative_path).read_bytes()
        if sha256 is not None and hashlib.sha256(data).hexdigest() != sha256.lower():
            raise ChecksumMismatchError(
                f"artifact {relative_path!r} is corrupted: sha256 does not match the record"
            )
        return data

    def open(self, relative_path: str, sha256: str | None = None) -> BinaryIO:
        """A binary stream of the stored file, verified first against ``sha256`` when given."""
        if sha256 is not None:
            self.verify(relative_path, sha256)
        return open(self.path(relative_path), "rb")

    def exists(self, relative_path: str) -> bool:
        """True if the file is stored."""
        return self.path(relative_path).is_file()

    def delete_attempt(self, job_id: str, attempt: str) -> None:
        """Remove the files one attempt wrote (a worker that lost its lease cleans up)."""
        directory = self.path(f"{_safe_name(job_id, 'job id')}/{_safe_name(attempt, 'attempt')}")
        shutil.rmtree(directory, ignore_errors=True)

    def prune_attempts(self, job_id: str, keep: str) -> None:
        """Remove the attempt directories of a job other than ``keep`` (left by workers that
        died before finishing); called by the lease holder after its files became the job's."""
        directory = self.path(_safe_name(job_id, "job id"))
        keep = _safe_name(keep, "attempt")
        if not directory.is_dir():
            return
        for child in directory.iterdir():
            if child.is_dir() and not child.is_symlink() and child.name != keep:
                shutil.rmtree(child, ignore_errors=True)

    def delete_job(self, job_id: str) -> None:
        """Remove every artifact of a job (no error if it has none)."""
        directory = self.path(_safe_name(job_id, "job id"))
        shutil.rmtree(directory, ignore_errors=True)
