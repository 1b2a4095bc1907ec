"""The artifact store: results (``result.json``), Rerun recordings (``.rrd``) and other files of
jobs, addressed by job id, attempt and kind, each recorded in the database with its SHA-256.

One interface (``ArtifactStore``, in ``base``), two backends chosen by the settings
(:func:`artifact_store`):

- ``LocalArtifactStore`` (``local``): a directory, ``LEGOPT_ARTIFACT_DIR`` (the embedded
  default, ``<data_dir>/artifacts``);
- ``S3ArtifactStore`` (``s3``): S3-compatible object storage, ``LEGOPT_ARTIFACTS_URL=
  s3://bucket/prefix`` (endpoint ``LEGOPT_S3_ENDPOINT_URL``; credentials and region from
  boto3's usual chain), so workers on several hosts share their files.

``ArtifactStore.from_settings(settings)`` is the same as ``artifact_store(settings)``.
"""

from __future__ import annotations

import os
import threading

from services.store.artifacts.base import (
    CHUNK,
    KIND_SUFFIXES,
    ArtifactStore,
    StoredFile,
    set_factory,
    sha256_file,
)
from services.store.artifacts.local import LocalArtifactStore
from services.store.settings import Settings

_clients: dict[tuple[int, str], object] = {}
_lock = threading.Lock()


def s3_endpoint(settings: Settings) -> str | None:
    """The S3 endpoint URL: ``s3_endpoint_url``, else ``AWS_ENDPOINT_URL_S3`` or
    ``AWS_ENDPOINT_URL`` (boto3's own variables), else None (AWS)."""
    return (
        settings.s3_endpoint_url
        or os.environ.get("AWS_ENDPOINT_URL_S3")
        or os.environ.get("AWS_ENDPOINT_URL")
        or None
    )


def artifact_store(settings: Settings) -> ArtifactStore:
    """The artifact store of ``settings``: S3 when ``artifacts_url`` is ``s3://...``, else
    the local directory ``artifact_dir``. S3 clients are made once per process and endpoint
    (boto3 clients are thread-safe; a forked child makes its own)."""
    s3 = settings.artifacts_s3
    if s3 is None:
        return LocalArtifactStore(settings.artifact_dir)
    from services.store.artifacts.s3 import S3ArtifactStore, make_client

    endpoint = s3_endpoint(settings)
    cache_key = (os.getpid(), endpoint or "")
    with _lock:
        client = _clients.get(cache_key)
        if client is None:
            client = _clients[cache_key] = make_client(endpoint)
    bucket, prefix = s3
    return S3ArtifactStore(bucket, prefix, client=client)


set_factory(artifact_store)


__all__ = [
    "CHUNK",
    "KIND_SUFFIXES",
    "ArtifactStore",
    "LocalArtifactStore",
    "StoredFile",
    "artifact_store",
    "s3_endpoint",
    "sha256_file",
]
