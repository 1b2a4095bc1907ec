"""Exceptions of the store (the API maps them to HTTP statuses)."""

from __future__ import annotations


class StoreError(Exception):
    """Base class of the store's errors."""


class NotFoundError(StoreError):
    """The row addressed does not exist (or belongs to another owner)."""


class ConflictError(StoreError):
    """A unique constraint would be violated (e.g. a robot name already used by the owner)."""


class LeaseLostError(StoreError):
    """The worker no longer owns the job's lease (reclaimed, cancelled or finished): stop."""


class ArtifactError(StoreError):
    """Base class of artifact store errors."""


class UnsafePathError(ArtifactError, ValueError):
    """A relative path, job id or kind that would leave the artifact directory."""


class ChecksumMismatchError(ArtifactError):
    """An artifact's bytes do not match the sha256 recorded for it."""


class ArtifactMissingError(ArtifactError, FileNotFoundError):
    """A recorded artifact's file or object is not in the artifact store (the API: 404
    naming it; the database's rows stay readable)."""


class ArtifactUnavailableError(ArtifactError):
    """The artifact store cannot be reached or refuses access (object store down, network,
    credentials, no such bucket): the API answers 503 with ``Retry-After``."""
