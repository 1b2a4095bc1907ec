"""Job spec documents as stored: a sweep's jobs keep only their overrides of the sweep's base.

``apply_overrides(base, overrides)`` is the one way to turn them back into a job's spec; the
API expands sweeps with the same ``with_overrides`` (:mod:`services.store.spec_paths`), so a
stored job reads back exactly the spec that was validated at submission.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Mapping
from typing import Any

from services.store.spec_paths import get_path, with_overrides


def apply_overrides(base: Mapping[str, Any], overrides: Mapping[str, Any]) -> dict[str, Any]:
    """A fresh spec: ``base`` with every ``dotted.path -> value`` of ``overrides`` set (a deep
    copy: the caller may modify it)."""
    return copy.deepcopy(with_overrides(base, overrides))


def spec_value(base: Any, overrides: Mapping[str, Any] | None, path: str) -> Any:
    """The value at dotted ``path`` of ``base`` with ``overrides`` applied, without copying the
    base (for listings: a job's name or study kind). None when absent."""
    overrides = overrides or {}
    segments = path.split(".")
    for depth in range(len(segments), 0, -1):  # the longest overridden prefix wins
        prefix = ".".join(segments[:depth])
        if prefix in overrides:
            rest = ".".join(segments[depth:])
            value = overrides[prefix]
            return value if not rest else get_path(value, rest)
    return get_path(base, path)


def shown_value(base: Any, overrides: Mapping[str, Any] | None, path: str) -> Any:
    """``spec_value`` for a table cell: a stored robot reference shown as the robot's name and
    the first 8 hex digits of its content hash (two robots of one name stay apart)."""
    from services.store.robot_documents import REF_KEY, is_reference

    value = spec_value(base, overrides, path)
    if is_reference(value):
        return " ".join(filter(None, [value.get("name"), value[REF_KEY][:8]]))
    return value


def json_size(value: Any) -> int:
    """Bytes of ``value`` as compact JSON (what a stored spec costs against a storage quota)."""
    return len(json.dumps(value, separators=(",", ":"), default=str).encode())


__all__ = ["apply_overrides", "json_size", "shown_value", "spec_value"]
