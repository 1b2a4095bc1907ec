"""Dotted paths into spec documents (``optimizer.params.pop_size``, ``robot.joints.1.mass``):
read one, set one, and build a document with overrides applied copy-on-write.

A path addresses mapping keys by name and list items by index. These are the one way to address
a stored spec: the API expands sweeps with ``with_overrides`` and the store reads a sweep's jobs
back with the same function (:mod:`services.store.specs`), so a stored job reads back exactly the
spec validated at submission.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any


def split_path(path: str) -> list[str]:
    """Segments of a dotted path; ValueError for an empty path or an empty segment."""
    if not isinstance(path, str) or not path:
        raise ValueError("a path must be a non-empty dotted string like 'optimizer.params.x'")
    segments = path.split(".")
    if any(not s for s in segments):
        raise ValueError(f"path {path!r} has an empty segment")
    return segments


def get_path(doc: Any, path: str, default: Any = None) -> Any:
    """The value at ``path`` in ``doc`` (``default`` when any segment is missing)."""
    current = doc
    for seg in split_path(path):
        if isinstance(current, Mapping) and seg in current:
            current = current[seg]
        elif isinstance(current, list) and seg.isdigit() and int(seg) < len(current):
            current = current[int(seg)]
        else:
            return default
    return current


def set_path(doc: dict[str, Any], path: str, value: Any) -> None:
    """Set ``path`` in ``doc`` in place (creating missing mapping keys).

    ValueError naming the path when it runs through a scalar (e.g. ``robot.joints.1.mass`` on a
    catalog robot name) or past the end of a list.
    """
    _set_owned(doc, path, copy.deepcopy(value), None)


class OverrideError(ValueError):
    """An override that cannot be set; ``path`` is the override's dotted path."""

    def __init__(self, path: str, message: str) -> None:
        super().__init__(message)
        self.path = path


def with_overrides(base: Mapping[str, Any], overrides: Mapping[str, Any]) -> dict[str, Any]:
    """``base`` with every ``dotted.path -> value`` of ``overrides`` set, copy-on-write.

    Equal to ``set_path`` applied in order on a deep copy of ``base``, but only the containers
    along the overridden paths are copied (shallowly): the result shares every untouched subtree
    with ``base`` and the override values themselves, so building N points of a 2 MB base costs
    O(N × path length), not O(N × 2 MB), and the shared subtrees keep their identity (the
    validation cache keys them by it). Treat the result as read-only, like ``base``.

    Raises ``OverrideError`` (a ValueError naming the path) like ``set_path``.
    """
    spec = dict(base)
    owned: set[int] = {id(spec)}  # containers of this result (safe to write)
    for path, value in overrides.items():
        try:
            _set_owned(spec, path, value, owned)
        except ValueError as exc:
            raise OverrideError(path, str(exc)) from None
    return spec


def _own(container: Any, owned: set[int] | None) -> Any:
    """``container`` itself when this result created it (or ``owned`` is None: the whole
    document is the caller's), else a shallow copy it now owns."""
    if owned is None or id(container) in owned:
        return container
    copied = dict(container) if isinstance(container, dict) else list(container)
    owned.add(id(copied))
    return copied


def _set_owned(doc: dict[str, Any], path: str, value: Any, owned: set[int] | None) -> None:
    """Set ``path`` to ``value``; each container on the way is ``_own``-ed (copy-on-write),
    or, with ``owned`` None, written in place."""
    segments = split_path(path)
    current: Any = doc
    for depth, seg in enumerate(segments):
        last = depth == len(segments) - 1
        where = ".".join(segments[:depth]) or "the spec"
        if isinstance(current, dict):
            if last:
                current[seg] = value
                return
            nxt = current.get(seg)
            if nxt is None:
                nxt = {}
                if owned is not None:
                    owned.add(id(nxt))
            elif isinstance(nxt, dict | list):
                nxt = _own(nxt, owned)
            current[seg] = nxt
            current = nxt
        elif isinstance(current, list):
            if not seg.isdigit() or int(seg) >= len(current):
                raise ValueError(
                    f"{where} is a list of {len(current)} items: no index {seg!r} in {path!r}"
                )
            if last:
                current[int(seg)] = value
                return
            nxt = current[int(seg)]
            if isinstance(nxt, dict | list):
                nxt = current[int(seg)] = _own(nxt, owned)
            current = nxt
        else:
            raise ValueError(_not_an_object(segments, depth, current, path))


def _not_an_object(segments: list[str], depth: int, current: Any, path: str) -> str:
    where = ".".join(segments[:depth]) or "the spec"
    hint = ""
    if segments[0] == "robot" and depth == 1:
        hint = (
            "; robot parameters can only be swept for an inline robot spec or a "
            "stored robot, not a catalog name"
        )
    shown = repr(current)
    if len(shown) > 60:
        shown = f"{shown[:45]}... ({type(current).__name__} of {len(current)})"
    return f"{where} is {shown}, not an object: cannot set {path!r}{hint}"


__all__ = ["OverrideError", "get_path", "set_path", "split_path", "with_overrides"]
