"""A small on-disk cache of JSON results keyed by content hash (issue 12, warm starts).

The numeric code stays free of IO: a caller computes a key with :func:`content_key` from
everything the result depends on (inputs and :func:`code_version` of the modules that compute
it) and wraps its computation in :func:`cached`. The directory is an argument, or
``LEGOPT_CACHE_DIR`` (its ``results/`` subfolder); with neither, nothing is read or written.
Entries are written atomically (temporary file + rename), so concurrent workers at worst
compute the same entry twice; an unreadable or malformed entry is recomputed.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from collections.abc import Callable, Iterable
from functools import lru_cache
from importlib import import_module
from pathlib import Path
from typing import Any

__all__ = ["cache_dir", "cached", "code_version", "content_key"]

ENV = "LEGOPT_CACHE_DIR"


def cache_dir(directory: str | os.PathLike[str] | None = None) -> Path | None:
    """The results folder: ``directory``, else ``$LEGOPT_CACHE_DIR/results``, else None."""
    if directory is not None:
        return Path(directory)
    root = os.environ.get(ENV, "")
    return Path(root) / "results" if root else None


@lru_cache(maxsize=8)
def code_version(package: str = "legcore") -> str:
    """sha256 of every ``.py`` file of ``package`` (a dotted name): changes with its code."""
    h = hashlib.sha256()
    init = getattr(import_module(package), "__file__", None)
    if init is None:
        return h.hexdigest()
    root = Path(init).parent
    for path in sorted(root.rglob("*.py")):
        h.update(path.relative_to(root).as_posix().encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def content_key(kind: str, parts: Iterable[Any]) -> str:
    """A file-name-safe key: ``kind`` + sha256 of the JSON of ``parts`` (sorted keys)."""
    blob = json.dumps(list(parts), sort_keys=True, default=str).encode()
    return f"{kind}-{hashlib.sha256(blob).hexdigest()[:32]}"


def cached(
    key: str,
    compute: Callable[[], dict[str, Any]],
    directory: str | os.PathLike[str] | None = None,
) -> dict[str, Any]:
    """``compute()`` (a JSON-able dict), read from / written to ``<dir>/<key>.json``."""
    folder = cache_dir(directory)
    if folder is None:
        return compute()
    path = folder / f"{key}.json"
    try:
        value = json.loads(path.read_text())
        if isinstance(value, dict):
            return value
    except (OSError, ValueError):
        pass
    value = compute()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{key}.", suffix=".tmp")
        with os.fdopen(fd, "w") as f:
            json.dump(value, f)
        os.replace(tmp, path)
    except OSError:  # a read-only or full disk: the result is still returned
        pass
    return value
