"""The artifact store on S3-compatible object storage (``LEGOPT_ARTIFACTS_URL=s3://bucket/p``).

Keys mirror the local layout under the URL's prefix: ``<prefix>/<job_id>/<attempt>/<kind>
<suffix>``. A write is one ``PutObject`` (atomic: a reader sees the old object or the new one),
sent with the bytes' SHA-256 (``x-amz-checksum-sha256``: the store checks the upload against it
and keeps it), into the writing attempt's own prefix — so, as with files, a worker that lost its
lease never replaces the objects of the job's winner. ``verify`` compares the SHA-256 the store
kept (one ``HeadObject``) with the recorded one, and hashes the object's bytes when the store
kept none; ``read``, ``open`` and ``local_copy`` hash what they download.

The client is boto3's, with its usual configuration chain for credentials and region
(``AWS_ACCESS_KEY_ID``/``AWS_SECRET_ACCESS_KEY``, ``AWS_PROFILE``, ``AWS_DEFAULT_REGION``, instance
roles, ...); the endpoint is ``LEGOPT_S3_ENDPOINT_URL``, else boto3's own
(``AWS_ENDPOINT_URL_S3``/``AWS_ENDPOINT_URL``, else AWS). A missing object raises
``ArtifactMissingError``; an unreachable store (network, 5xx, credentials, no such bucket)
``ArtifactUnavailableError``.
"""

from __future__ import annotations

import base64
import contextlib
import hashlib
import io
import logging
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any, BinaryIO, cast

import boto3
from botocore.config import Config
from botocore.exceptions import BotoCoreError, ClientError

from services.store.artifacts.base import (
    CHUNK,
    ArtifactStore,
    Source,
    StoredFile,
    check_digest,
    check_relative,
    safe_name,
)
from services.store.errors import (
    ArtifactError,
    ArtifactMissingError,
    ArtifactUnavailableError,
    ChecksumMismatchError,
)

log = logging.getLogger("legopt.artifacts")

#: Bytes a stream being uploaded is kept in memory before it spills to a temporary file.
SPOOL_BYTES = 8 << 20
_MISSING = {"404", "NoSuchKey", "NotFound"}
_UNAVAILABLE = {
    "NoSuchBucket", "AccessDenied", "InvalidAccessKeyId", "SignatureDoesNotMatch",
    "ExpiredToken", "InvalidToken", "SlowDown", "ServiceUnavailable", "InternalError",
    "RequestTimeout", "RequestTimeTooSkewed",
}  # fmt: skip


def make_client(endpoint_url: str | None = None) -> Any:
    """A boto3 S3 client (short timeouts, a few retries; path-style addressing for a custom
    endpoint such as MinIO's)."""
    config = Config(
        connect_timeout=5,
        read_timeout=60,
        retries={"max_attempts": 3, "mode": "standard"},
        s3={"addressing_style": "path" if endpoint_url else "auto"},
        signature_version="s3v4",  # presigned URLs too (every AWS region accepts SigV4)
        request_checksum_calculation="when_required",
        response_checksum_validation="when_required",
    )
    return boto3.session.Session().client("s3", endpoint_url=endpoint_url or None, config=config)


def _b64(sha256_hex: str) -> str:
    return base64.b64encode(bytes.fromhex(sha256_hex)).decode()


class S3ArtifactStore(ArtifactStore):
    """Objects of jobs under ``s3://<bucket>/<prefix>/``."""

    def __init__(self, bucket: str, prefix: str = "", *, client: Any = None) -> None:
        self.bucket = bucket
        self.prefix = prefix.strip("/")
        self.client = client if client is not None else make_client()
        self.location = f"s3://{bucket}/{self.prefix}".rstrip("/")

    # ------------------------------------------------------------------ keys and errors

    def key(self, relative_path: str) -> str:
        """The object key of a relative path (validated like a local path)."""
        rel = check_relative(relative_path).as_posix()
        return f"{self.prefix}/{rel}" if self.prefix else rel

    @contextlib.contextmanager
    def _errors(self, relative_path: str) -> Iterator[None]:
        """boto3's errors as the store's: missing object, unreachable store, other."""
        try:
            yield
        except ClientError as exc:
            err = exc.response.get("Error", {})
            code = str(err.get("Code", ""))
            status = int(exc.response.get("ResponseMetadata", {}).get("HTTPStatusCode") or 0)
            what = f"artifact {relative_path!r}"
            if code in _UNAVAILABLE or status >= 500 or status in (401, 403):
                log.warning("%s on %s: %s", self.location, what, exc)
                raise ArtifactUnavailableError(
                    f"the artifact store refused {what}: {code or status}"
                ) from None
            if code in _MISSING:
                raise ArtifactMissingError(f"{what} is missing from the artifact store") from None
            raise ArtifactError(
                f"artifact store error on {what}: {code} {err.get('Message', '')}".rstrip()
            ) from exc
        except BotoCoreError as exc:  # no connection, timeout, no credentials, ...
            log.warning("%s cannot be reached for %r: %s", self.location, relative_path, exc)
            raise ArtifactUnavailableError(
                f"the artifact store cannot be reached ({type(exc).__name__})"
            ) from None

    def _head(self, relative_path: str) -> dict[str, Any]:
        key = self.key(relative_path)
        with self._errors(relative_path):
            return cast(
                dict[str, Any],
                self.client.head_object(Bucket=self.bucket, Key=key, ChecksumMode="ENABLED"),
            )

    def _get(self, relative_path: str, byte_range: str | None = None) -> Any:
        """The ``GetObject`` response's body (a stream)."""
        key = self.key(relative_path)
        kwargs = {"Range": byte_range} if byte_range else {}
        with self._errors(relative_path):
            return self.client.get_object(Bucket=self.bucket, Key=key, **kwargs)["Body"]

    def _download(self, relative_path: str, out: IO[bytes] | None, sha256: str | None) -> str:
        """Copy the object into ``out`` (None: only hash it); its hex SHA-256, checked against
        ``sha256`` when given."""
        body = self._get(relative_path)
        digest = hashlib.sha256()
        with self._errors(relative_path), contextlib.closing(body):
            for chunk in body.iter_chunks(CHUNK):
                digest.update(chunk)
                if out is not None:
                    out.write(chunk)
        actual = digest.hexdigest()
        if sha256 is not None:
            check_digest(relative_path, actual, sha256)
        return actual

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
        key = self.key(rel)
        with _spooled(src) as (body, sha256, size), self._errors(rel):
            self.client.put_object(
                Bucket=self.bucket,
                Key=key,
                Body=body,
                ContentLength=size,
                ChecksumAlgorithm="SHA256",
                ChecksumSHA256=_b64(sha256),
                ContentType="application/octet-stream",
            )
        return StoredFile(rel, sha256, size)

    # ------------------------------------------------------------------ reading

    def verify(self, relative_path: str, sha256: str) -> int:
        head = self._head(relative_path)
        kept = head.get("ChecksumSHA256")
        if kept and "-" not in kept:  # the whole object's (a multipart one ends "-<parts>")
            if kept != _b64(sha256.lower()):
                raise ChecksumMismatchError(
                    f"artifact {relative_path!r} is corrupted: the store's sha256 "
                    f"{base64.b64decode(kept).hex()} != recorded {sha256}"
                )
        else:
            self._download(relative_path, None, sha256)
        return int(head.get("ContentLength") or 0)

    def read(self, relative_path: str, sha256: str | None = None) -> bytes:
        out = io.BytesIO()
        self._download(relative_path, out, sha256)
        return out.getvalue()

    def open(self, relative_path: str, sha256: str | None = None) -> BinaryIO:
        out = tempfile.SpooledTemporaryFile(max_size=SPOOL_BYTES)
        try:
            self._download(relative_path, out, sha256)
        except BaseException:
            out.close()
            raise
        out.seek(0)
        return cast(BinaryIO, out)

    def exists(self, relative_path: str) -> bool:
        try:
            self._head(relative_path)
        except ArtifactMissingError:
            return False
        return True

    def size(self, relative_path: str) -> int:
        return int(self._head(relative_path).get("ContentLength") or 0)

    def open_range(self, relative_path: str, start: int, stop: int) -> Iterator[bytes]:
        if stop <= start:
            self._head(relative_path)  # a missing object still raises
            return iter(())
        body = self._get(relative_path, f"bytes={start}-{stop - 1}")
        return self._chunks(relative_path, body)

    def _chunks(self, relative_path: str, body: Any) -> Iterator[bytes]:
        with self._errors(relative_path), contextlib.closing(body):
            yield from body.iter_chunks(CHUNK)

    @contextlib.contextmanager
    def local_copy(self, relative_path: str, sha256: str | None = None) -> Iterator[Path]:
        with tempfile.TemporaryDirectory(prefix="legopt-s3-") as tmp:
            path = Path(tmp) / (Path(relative_path).name or "artifact")
            with open(path, "wb") as out:
                self._download(relative_path, out, sha256)
            yield path

    def presigned_url(self, relative_path: str, *, expires_s: int, filename: str) -> str | None:
        key = self.key(relative_path)
        with self._errors(relative_path):
            return cast(
                str,
                self.client.generate_presigned_url(
                    "get_object",
                    Params={
                        "Bucket": self.bucket,
                        "Key": key,
                        "ResponseContentDisposition": f'attachment; filename="{filename}"',
                    },
                    ExpiresIn=expires_s,
                ),
            )

    # ------------------------------------------------------------------ removing

    def _delete_prefix(self, relative_dir: str, keep: str | None = None) -> None:
        """Delete every object under ``relative_dir/`` (but those under ``keep/`` when given);
        a store that is gone is logged, not raised (like ``rmtree(ignore_errors=True)``)."""
        prefix = self.key(relative_dir) + "/"
        skip = self.key(f"{relative_dir}/{keep}") + "/" if keep else None
        try:
            with self._errors(relative_dir):
                pages = self.client.get_paginator("list_objects_v2").paginate(
                    Bucket=self.bucket, Prefix=prefix
                )
                batch: list[dict[str, str]] = []
                for page in pages:
                    for obj in page.get("Contents", []):
                        if skip is not None and str(obj["Key"]).startswith(skip):
                            continue
                        if skip is not None and "/" not in str(obj["Key"])[len(prefix) :]:
                            continue  # a file beside the attempts (no attempt) stays
                        batch.append({"Key": obj["Key"]})
                        if len(batch) == 1000:
                            self._delete_batch(batch)
                            batch = []
                if batch:
                    self._delete_batch(batch)
        except ArtifactError as exc:
            log.warning("could not delete %s/ from %s: %s", relative_dir, self.location, exc)

    def _delete_batch(self, batch: list[dict[str, str]]) -> None:
        self.client.delete_objects(Bucket=self.bucket, Delete={"Objects": batch, "Quiet": True})

    def delete_attempt(self, job_id: str, attempt: str) -> None:
        self._delete_prefix(f"{safe_name(job_id, 'job id')}/{safe_name(attempt, 'attempt')}")

    def prune_attempts(self, job_id: str, keep: str) -> None:
        self._delete_prefix(safe_name(job_id, "job id"), keep=safe_name(keep, "attempt"))

    def delete_job(self, job_id: str) -> None:
        self._delete_prefix(safe_name(job_id, "job id"))


@contextlib.contextmanager
def _spooled(src: Source) -> Iterator[tuple[IO[bytes], str, int]]:
    """``(seekable body, sha256, size)`` of ``src``: a file is hashed then read again, bytes
    are wrapped, a stream is copied into a spooled temporary file while hashed."""
    if isinstance(src, bytes | bytearray | memoryview):
        data = bytes(src)
        yield io.BytesIO(data), hashlib.sha256(data).hexdigest(), len(data)
        return
    if isinstance(src, str | os.PathLike):
        with open(src, "rb") as f:
            digest = hashlib.sha256()
            for chunk in iter(lambda: f.read(CHUNK), b""):
                digest.update(chunk)
            size = f.tell()
            f.seek(0)
            yield f, digest.hexdigest(), size
        return
    with tempfile.SpooledTemporaryFile(max_size=SPOOL_BYTES) as spool:
        digest = hashlib.sha256()
        size = 0
        for chunk in iter(lambda: src.read(CHUNK), b""):
            digest.update(chunk)
            size += len(chunk)
            spool.write(chunk)
        spool.seek(0)
        yield cast(IO[bytes], spool), digest.hexdigest(), size


__all__ = ["S3ArtifactStore", "make_client"]
