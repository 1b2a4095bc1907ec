"""Compiled kernels cached by numba are dropped when legcore's source changes.

numba invalidates a cached kernel when the file that defines it changes, not when a kernel it
calls from another file changes: after an edit of ``legcore/ik/newton.py`` alone, or an upgrade
that keeps a persistent cache (``NUMBA_CACHE_DIR``, e.g. ``<data_dir>/cache/numba`` of the
service), a caller's cached machine code would still run the old callee — a wrong result that
looks right. So the first import of legcore compares a hash of all its ``.py`` files with the
one stamped in the cache; on a difference it deletes the cached kernels (``*.nbi``, ``*.nbc``)
and stamps the new hash, and numba compiles afresh (once, as on a first install).

Where the cache is: ``NUMBA_CACHE_DIR`` when set (every kernel file under it is deleted on a
change: the directory is the service's own), else numba's default next to the package
(``legcore/**/__pycache__``). The check reads ~1.5 MB of source: ~5 ms per process.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

__all__ = ["STAMP_NAME", "check_kernel_cache", "source_hash"]

PACKAGE = Path(__file__).resolve().parent
STAMP_NAME = "legcore-source.sha256"
_KERNEL_SUFFIXES = (".nbi", ".nbc")


def source_hash(package: Path = PACKAGE) -> str:
    """SHA-256 of the package's ``.py`` files (relative paths and contents, sorted)."""
    h = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        h.update(path.relative_to(package).as_posix().encode())
        h.update(b"\0")
        h.update(path.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


def _cache_root(package: Path) -> tuple[Path, list[Path]]:
    """(where the stamp lives, the folders holding this package's cached kernels)."""
    env = os.environ.get("NUMBA_CACHE_DIR")
    if env:
        root = Path(env)
        return root, [root]
    return package / "__pycache__", [package]


def check_kernel_cache(package: Path = PACKAGE) -> bool:
    """Delete the cached kernels if the source changed since they were stamped; True if it
    deleted (or found nothing stamped and stamped it). Never raises: an unwritable cache is
    numba's business (it then compiles in memory)."""
    stamp_dir, roots = _cache_root(package)
    stamp = stamp_dir / STAMP_NAME
    try:
        current = source_hash(package)
        if stamp.is_file() and stamp.read_text().strip() == current:
            return False
        for root in roots:
            if not root.is_dir():
                continue
            for path in root.rglob("*"):
                if path.suffix in _KERNEL_SUFFIXES and path.is_file():
                    path.unlink(missing_ok=True)
        stamp_dir.mkdir(parents=True, exist_ok=True)
        tmp = stamp.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(current + "\n")
        os.replace(tmp, stamp)
        return True
    except OSError:
        return False
