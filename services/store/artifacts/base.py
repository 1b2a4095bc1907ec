"""The artifact store's interface, shared by its backends (``local``, ``s3``).

An artifact is addressed by a relative path ``<job_id>/<attempt>/<kind><suffix>`` (or
``<job_id>/<kind><suffix>`` without an attempt), always ``/``-separated, validated here the same
way for every backend: names of letters, digits, ``.``, ``_``, ``-``; nothing absolute, no
``..``, no empty segment (``UnsafePathError``). The database records each artifact's relative
path, SHA-256 and size (``StoredFile``); a backend stores the bytes.

Errors: a recorded file or object that is gone raises ``ArtifactMissingError``; a store that
cannot be reached (or refuses access) ``ArtifactUnavailableError``; bytes that do not hash to
the recorded SHA-256 ``ChecksumMismatchError``.
"""

from __future__ import annotations

import hashlib
import os
import re
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING, BinaryIO, NamedTuple

from services.store.errors import ChecksumMismatchError, UnsafePathError

if TYPE_CHECKING:
    from services.store.settings import Settings

CHUNK = 1 << 20
KIND_SUFFIXES = {"recording": ".rrd", "csv": ".csv", "json": ".json"}
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,127}$")
_SUFFIX = re.compile(r"^(\.[A-Za-z0-9]{1,16})*$")

Source = str | os.PathLike[str] | bytes | BinaryIO


class StoredFile(NamedTuple):
    """Where ``ArtifactStore.put`` stored a file: ``(relative_path, sha256, size_bytes)``."""

    relative_path: str
    sha256: str
    size_bytes: int


def safe_name(value: str, what: str) -> str:
    """``value`` if it is a safe single path segment, else UnsafePathError."""
    if not _NAME.match(value) or ".." in value:
        raise UnsafePathError(f"invalid {what} {value!r}: use letters, digits, '.', '_', '-'")
    return value


def check_relative(relative_path: str) -> PurePosixPath:
    """The parsed relative path; UnsafePathError when it is empty, absolute, not normalised
    (``//``, ``./``), holds ``..``, a backslash or a NUL."""
    if not relative_path or "\\" in relative_path or "\x00" in relative_path:
        raise UnsafePathError(f"invalid artifact path {relative_path!r}")
    rel = PurePosixPath(relative_path)
    if (
        rel.is_absolute()
        or ".." in rel.parts
        or rel.as_posix() != relative_path
        or rel.as_posix() == "."
    ):
        raise UnsafePathError(f"artifact path {relative_path!r} leaves the artifact directory")
    return rel


def sha256_file(path: str | os.PathLike[str]) -> str:
    """Hex SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(CHUNK), b""):
            digest.update(chunk)
    return digest.hexdigest()


def check_digest(relative_path: str, actual: str, recorded: str) -> None:
    """ChecksumMismatchError unless ``actual`` is the ``recorded`` hex SHA-256."""
    if actual != recorded.lower():
        raise ChecksumMismatchError(
            f"artifact {relative_path!r} is corrupted: sha256 {actual} != recorded {recorded}"
        )


#: The factory of ``ArtifactStore.from_settings``: ``artifact_store``, set by the package on
#: import (it imports the backends, which import this module: no import circle).
_factory: Callable[[Settings], ArtifactStore] | None = None


def set_factory(factory: Callable[[Settings], ArtifactStore]) -> None:
    """Make ``factory`` the one ``ArtifactStore.from_settings`` calls."""
    global _factory
    _factory = factory


class ArtifactStore(ABC):
    """Files of jobs: one interface, two backends — a local directory
    (``LocalArtifactStore``, the embedded default) and S3-compatible object storage
    (``S3ArtifactStore``, ``LEGOPT_ARTIFACTS_URL=s3://bucket/prefix``).

    Writes are atomic (a reader sees the old bytes or the new ones, never a part) and land in
    the writing attempt's own directory, so a worker that lost its lease never replaces the
    files of the job's winner; ``finish_job`` makes them the job's by recording their path
    and SHA-256.
    """

    #: Where the store keeps its files, for messages (a directory or an ``s3://`` URL).
    location: str

    @classmethod
    def from_settings(cls, settings: Settings) -> ArtifactStore:
        """The store the settings choose (``services.store.artifacts.artifact_store``)."""
        if _factory is None:  # pragma: no cover - the package sets it on import
            raise RuntimeError("services.store.artifacts is not initialised")
        return _factory(settings)

    # ------------------------------------------------------------------ paths

    def relative_path(
        self, job_id: str, kind: str, suffix: str | None = None, attempt: str | None = None
    ) -> str:
        """The relative path of a job's artifact of ``kind`` (validated), under the directory
        of ``attempt`` when given."""
        safe_name(job_id, "job id")
        safe_name(kind, "artifact kind")
        suffix = KIND_SUFFIXES.get(kind, ".bin") if suffix is None else suffix
        if not _SUFFIX.match(suffix):
            raise UnsafePathError(f"invalid file suffix {suffix!r}")
        if attempt is not None:
            return f"{job_id}/{safe_name(attempt, 'attempt')}/{kind}{suffix}"
        return f"{job_id}/{kind}{suffix}"

    # ------------------------------------------------------------------ writing

    @abstractmethod
    def put(
        self,
        job_id: str,
        kind: str,
        src: Source,
        *,
        suffix: str | None = None,
        attempt: str | None = None,
    ) -> StoredFile:
        """Store ``src`` (a file path, bytes, or a binary stream) atomically as a job artifact.

        ``suffix`` defaults to the source file's suffix, else by kind (``.rrd`` for
        ``recording``, ``.csv`` for ``csv``, ``.bin`` otherwise); ``attempt`` puts it in that
        attempt's directory. Storing the same kind again (same attempt) replaces it
        atomically. Returns ``(relative_path, sha256, size_bytes)``.
        """

    # ------------------------------------------------------------------ reading

    @abstractmethod
    def verify(self, relative_path: str, sha256: str) -> int:
        """The stored size in bytes; ChecksumMismatchError unless the stored bytes hash to
        ``sha256`` (ArtifactMissingError when they are gone)."""

    @abstractmethod
    def read(self, relative_path: str, sha256: str | None = None) -> bytes:
        """The stored bytes, verified against ``sha256`` when given."""

    @abstractmethod
    def open(self, relative_path: str, sha256: str | None = None) -> BinaryIO:
        """A binary stream of the stored bytes, verified first against ``sha256`` when given."""

    @abstractmethod
    def exists(self, relative_path: str) -> bool:
        """True if the file is stored."""

    @abstractmethod
    def size(self, relative_path: str) -> int:
        """Stored size in bytes (ArtifactMissingError when it is gone)."""

    @abstractmethod
    def open_range(self, relative_path: str, start: int, stop: int) -> Iterator[bytes]:
        """Chunks of the stored bytes ``[start, stop)``. The file or object is opened before
        this returns (a missing one raises here, not while iterating)."""

    @abstractmethod
    def local_copy(
        self, relative_path: str, sha256: str | None = None
    ) -> AbstractContextManager[Path]:
        """A local file holding the stored bytes (verified when ``sha256`` is given) for as
        long as the context lasts: the file itself for the local backend, a temporary
        download for a remote one."""

    def local_path(self, relative_path: str) -> Path | None:
        """The file's path when the store is a local directory (served as a file), else None."""
        return None

    def presigned_url(self, relative_path: str, *, expires_s: int, filename: str) -> str | None:
        """A URL that downloads the object directly from the store for ``expires_s`` seconds
        (as ``filename``); None when the store has no such URLs (a local directory)."""
        return None

    # ------------------------------------------------------------------ removing

    @abstractmethod
    def delete_attempt(self, job_id: str, attempt: str) -> None:
        """Remove the files one attempt wrote (a worker that lost its lease cleans up); never
        raises for a store that is gone."""

    @abstractmethod
    def prune_attempts(self, job_id: str, keep: str) -> None:
        """Remove the attempt directories of a job other than ``keep`` (left by workers that
        died before finishing); called by the lease holder after its files became the job's."""

    @abstractmethod
    def delete_job(self, job_id: str) -> None:
        """Remove every artifact of a job (no error if it has none)."""


__all__ = [
    "CHUNK",
    "KIND_SUFFIXES",
    "ArtifactStore",
    "Source",
    "StoredFile",
    "check_digest",
    "check_relative",
    "safe_name",
    "set_factory",
    "sha256_file",
]
