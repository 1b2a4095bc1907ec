"""Robots by reference: a stored spec's robot document lives once in ``robot_documents``.

A job spec's ``robot`` is a catalog name or a robot document (an inline spec — a URDF string, DH
rows — or a stored robot's document, resolved by the API at submission so the job runs on the
robot as it was then). Copied into every job row, a 1 MB URDF costs 1 MB per job; stored here
it costs one row per distinct content, and a stored spec holds only the reference::

    {"robot": {"$robot_document": "<sha256 of the canonical JSON>", "name": "ur5"}}

(``name`` kept when the document has one, so listings label the job without reading the
document.) :func:`by_reference` replaces the document when a job or sweep is stored;
:func:`expand` puts it back when a spec is read (``repository.job_spec``, a sweep's base), so
everything above the store sees the spec that was validated. Rows are immutable and shared by
content: the same robot submitted by two keys is one row, and neither key can read it except
through its own jobs. Specs stored before revision 0007 hold their documents inline and read
back unchanged.
"""

from __future__ import annotations

import hashlib
import json
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from services.store.sql import insert_ignoring_duplicates
from services.store.tables import ROBOT_DOCUMENTS
from services.store.types import utcnow

#: The key of a reference in a stored spec's ``robot``.
REF_KEY = "$robot_document"


def canonical_json(doc: Any) -> bytes:
    """``doc`` as compact JSON with sorted keys: the bytes its hash is taken over."""
    return json.dumps(doc, sort_keys=True, separators=(",", ":"), ensure_ascii=False).encode()


def is_reference(robot: Any) -> bool:
    """True for a stored reference ``{"$robot_document": sha256, ...}``."""
    return isinstance(robot, dict) and isinstance(robot.get(REF_KEY), str)


def store_document(session: Session, doc: dict[str, Any]) -> str:
    """Store ``doc`` unless a row with its content exists; its SHA-256 (hex)."""
    raw = canonical_json(doc)
    sha = hashlib.sha256(raw).hexdigest()
    values = {"sha256": sha, "spec": doc, "size_bytes": len(raw), "created_at": utcnow()}
    insert_ignoring_duplicates(session, ROBOT_DOCUMENTS, values, ["sha256"])
    return sha


def by_reference(session: Session, spec: Any) -> Any:
    """``spec`` with its robot document (if it has one) stored and replaced by a reference; a
    new dict (``spec`` is not modified). Catalog names, ``None`` and references stay."""
    if not isinstance(spec, dict):
        return spec
    robot = spec.get("robot")
    if not isinstance(robot, dict) or is_reference(robot):
        return spec
    ref: dict[str, Any] = {REF_KEY: store_document(session, robot)}
    if isinstance(robot.get("name"), str):
        ref["name"] = robot["name"]
    return {**spec, "robot": ref}


def expand(session: Session, spec: Any) -> Any:
    """``spec`` with a robot reference replaced by its document (a new dict when replaced).

    Raises ``LookupError`` if the referenced document is missing (a damaged store)."""
    if not isinstance(spec, dict) or not is_reference(spec.get("robot")):
        return spec
    sha = spec["robot"][REF_KEY]
    doc = session.execute(
        select(ROBOT_DOCUMENTS.c.spec).where(ROBOT_DOCUMENTS.c.sha256 == sha)
    ).scalar_one_or_none()
    if doc is None:
        raise LookupError(f"robot document {sha} of a stored spec is missing")
    return {**spec, "robot": doc}


__all__ = ["REF_KEY", "by_reference", "canonical_json", "expand", "is_reference", "store_document"]
