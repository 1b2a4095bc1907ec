"""JSON documents the API makes on demand from a succeeded job and keeps as the job's
artifacts (the front's metrics, the study's extras): made once, on the point thread of
:mod:`services.api.points` (one piece of work at a time per process, 503 + Retry-After past
``WAIT_S``), stored inside the directory of the attempt whose result they describe (deleted
with the job, counted against the key's storage quota). A stored file whose file or object is
gone or corrupted is made again."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

from services.api.deps import ApiContext
from services.api.points import attempt_dir, run_point_work
from services.store import output_queries as oq
from services.store.errors import ArtifactMissingError, ChecksumMismatchError
from services.store.records import ArtifactRecord

__all__ = ["cached_json", "read_stored_json"]


def read_stored_json(ctx: ApiContext, art: ArtifactRecord | None) -> dict[str, Any] | None:
    """The stored document of ``art``; None when there is none, or its file or object is gone
    or corrupted (its row is then removed: it is made again). Raises ``ArtifactError`` when
    the store cannot be reached."""
    if art is None:
        return None
    try:
        doc = json.loads(ctx.artifacts.read(art.relative_path, art.sha256))
    except (ArtifactMissingError, ChecksumMismatchError, json.JSONDecodeError):
        with ctx.write() as session:
            oq.forget_artifact(session, art.job_id, art.kind, art.sha256)
        return None
    return doc if isinstance(doc, dict) else None


def cached_json(
    ctx: ApiContext, job_id: str, kind: str, make: Callable[[], dict[str, Any]]
) -> dict[str, Any]:
    """The job's JSON artifact ``kind``: the stored one, or ``make()`` run on the point thread
    (shared by concurrent requests for it), stored as ``<kind>.json`` and returned. ``make``
    raises HTTPException for what the caller answers (409: the job cannot be decoded again);
    503 when the work takes longer than a request waits (its result is kept)."""
    with ctx.read() as session:
        existing = oq.get_artifact(session, job_id, kind)
    stored = read_stored_json(ctx, existing)
    if stored is not None:
        return stored

    def work() -> dict[str, Any]:
        with ctx.read() as session:
            done = oq.get_artifact(session, job_id, kind)
        again = read_stored_json(ctx, done)
        if again is not None:
            return again
        doc = make()
        data = json.dumps(doc, allow_nan=False, separators=(",", ":")).encode()
        put = ctx.artifacts.put(
            job_id, kind, data, suffix=".json", attempt=attempt_dir(ctx, job_id)
        )
        with ctx.write() as session:  # a concurrent copy (another API process) is identical
            oq.add_artifact(session, job_id, kind, *put)
        return doc

    return run_point_work((job_id, kind), work)
