"""Downloads of stored artifacts (recordings) from either artifact store backend, with HTTP
Range support (the Rerun viewer fetches ranges of a recording).

- Local directory: the file itself (``FileResponse``: ranges, ``sendfile`` where available).
- S3: streamed through the API from ``GetObject`` (``Range: bytes=a-b`` answered 206 with
  ``Content-Range``; an unsatisfiable range 416), or — with ``LEGOPT_ARTIFACTS_PRESIGN=1`` — a
  307 redirect to a presigned URL of the object, which the store serves (ranges included).

Every download is checked against its recorded SHA-256 first (``ArtifactStore.verify``) and
carries it as ``X-Checksum-SHA256``. A recorded artifact whose file or object is gone is a 404
naming it; an unreachable store a 503 (``services.api.errors``).
"""

from __future__ import annotations

import re
from typing import Any
from urllib.parse import quote

from fastapi.responses import FileResponse, PlainTextResponse, RedirectResponse, Response
from starlette.concurrency import iterate_in_threadpool, run_in_threadpool
from starlette.datastructures import Headers, MutableHeaders
from starlette.types import Receive, Scope, Send

from services.api.deps import ApiContext
from services.store.artifacts import ArtifactStore
from services.store.errors import ArtifactMissingError

MEDIA_TYPE = "application/octet-stream"
_RANGE = re.compile(r"^\s*bytes\s*=\s*(\d*)\s*-\s*(\d*)\s*$")


def byte_range(header: str | None, size: int) -> tuple[int, int] | None:
    """``(start, stop)`` of a single-range ``Range`` header on ``size`` bytes, None to send
    everything (no header, a malformed one or several ranges: RFC 9110 lets a server ignore
    it); ValueError when the range cannot be satisfied (416)."""
    if not header:
        return None
    m = _RANGE.match(header)
    if m is None:
        return None
    first, last = m.group(1), m.group(2)
    if not first and not last:
        return None
    if not first:  # the last N bytes
        n = int(last)
        if n == 0:
            raise ValueError("empty suffix range")
        return max(size - n, 0), size
    start = int(first)
    stop = size if not last else min(int(last) + 1, size)
    if last and int(last) < start:
        return None  # invalid: ignored
    if start >= size:
        raise ValueError(f"range starts at {start}, the file has {size} bytes")
    return start, stop


class StoredObjectResponse(Response):
    """An artifact streamed from its store, whole (200) or one byte range (206)."""

    def __init__(
        self, store: ArtifactStore, relative_path: str, size: int, headers: dict[str, str]
    ) -> None:
        self.store = store
        self.relative_path = relative_path
        self.size = size
        self.status_code = 200
        self.media_type = MEDIA_TYPE
        self.background = None
        self.init_headers({**headers, "accept-ranges": "bytes", "content-length": str(size)})

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        try:
            span = byte_range(Headers(scope=scope).get("range"), self.size)
        except ValueError:
            unsatisfiable = PlainTextResponse(
                "range not satisfiable",
                status_code=416,
                headers={"Content-Range": f"bytes */{self.size}"},
            )
            await unsatisfiable(scope, receive, send)
            return
        start, stop = span or (0, self.size)
        headers = MutableHeaders(raw=list(self.raw_headers))
        headers["content-length"] = str(stop - start)
        if span is not None:
            headers["content-range"] = f"bytes {start}-{stop - 1}/{self.size}"
        # opened before the response starts: a missing object or an unreachable store is
        # still answered by the error handlers (404 / 503)
        chunks = await run_in_threadpool(self.store.open_range, self.relative_path, start, stop)
        await send(
            {
                "type": "http.response.start",
                "status": 206 if span is not None else 200,
                "headers": headers.raw,
            }
        )
        try:
            async for chunk in iterate_in_threadpool(chunks):
                await send({"type": "http.response.body", "body": chunk, "more_body": True})
            await send({"type": "http.response.body", "body": b"", "more_body": False})
        finally:
            close = getattr(chunks, "close", None)
            if close is not None:
                await run_in_threadpool(close)


def artifact_response(ctx: ApiContext, artifact: Any, *, filename: str, what: str) -> Response:
    """The download of ``artifact`` (an ``ArtifactRecord``: relative path and SHA-256) as
    ``filename``: verified, then a file, a stream or a redirect (module docstring). ``what``
    names it in the 404 when it is gone, e.g. ``"the recording of job <id>"``."""
    store = ctx.artifacts
    rel, sha256 = artifact.relative_path, artifact.sha256
    try:
        size = store.verify(rel, sha256)
    except ArtifactMissingError:
        raise ArtifactMissingError(
            f"{what} is missing from the artifact store (recorded as {rel}; the rest of the "
            "job is still in the database)"
        ) from None
    headers = {"X-Checksum-SHA256": sha256}
    path = store.local_path(rel)
    if path is not None:
        return FileResponse(path, media_type=MEDIA_TYPE, filename=filename, headers=headers)
    settings = ctx.settings
    if settings.artifacts_presign:
        url = store.presigned_url(
            rel, expires_s=settings.artifacts_presign_seconds, filename=filename
        )
        if url is not None:
            return RedirectResponse(url, status_code=307, headers=headers)
    return StoredObjectResponse(
        store, rel, size, {**headers, "content-disposition": _disposition(filename)}
    )


def _disposition(filename: str) -> str:
    """``Content-Disposition`` of a download named ``filename`` (as ``FileResponse`` makes it)."""
    quoted = quote(filename)
    if quoted != filename:
        return f"attachment; filename*=utf-8''{quoted}"
    return f'attachment; filename="{filename}"'


__all__ = ["StoredObjectResponse", "artifact_response", "byte_range"]
