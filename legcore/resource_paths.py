"""Confine a resource name from a robot file (a URDF ``<mesh filename=…>``) to allow-listed roots.

DESIGN §5: uploaded content is data, never a path. A name from a robot file is resolved only
inside an explicit list of root directories (``roots``); with no roots — what the worker and the
API pass for every robot — nothing is resolved and no file is touched at all.

Accepted names, looked up under each root in order (the first regular file wins):

- ``package://<package>/<rel>`` — the package name is not used to choose the root;
- a plain relative name ``<rel>`` (``meshes/leg.stl``).

Refused without touching the file system: no roots, an empty name, NUL bytes, backslashes,
absolute paths, any other URI scheme (``file://``, ``http://``, …), and any ``..`` segment.

The remaining name is then walked one component at a time like ``realpath`` — but a component
is only ``lstat``-ed once its path is known to be inside a root, and a symlink's target is
followed only while it stays inside a root (or on the way down to one, along the root's own
real path, which is never stat-ed). So a symlink inside a root that points outside is refused
without even a ``stat`` of its target. :func:`read_resource` then opens the file with
``O_NOFOLLOW`` and checks that the opened file is the one the walk found (same device and inode,
a regular file), so swapping the last component for a symlink after the walk is caught.
Directories inside the roots are trusted not to be replaced concurrently (they are package data).
"""

from __future__ import annotations

import os
import re
import stat
from collections.abc import Sequence
from pathlib import Path, PurePosixPath

__all__ = ["NO_FILE_ACCESS", "ResourceRefused", "confine_resource", "read_resource"]

#: Reason given when there are no roots (uploaded robots).
NO_FILE_ACCESS = "uploaded robots get no file access"

_SCHEME_RE = re.compile(r"^[A-Za-z][A-Za-z0-9+.\-]*:")
_MAX_SYMLINKS = 40

PathLike = str | os.PathLike[str]


class ResourceRefused(ValueError):
    """A resource name that is not resolved; ``reason`` says why in words meant for the user."""

    def __init__(self, name: str, reason: str) -> None:
        super().__init__(f"{name!r} not read: {reason}")
        self.name = name
        self.reason = reason


def _relative_parts(name: str) -> list[str]:
    """The path components of ``name`` below a root, or :class:`ResourceRefused` (no I/O)."""
    if "\x00" in name:
        raise ResourceRefused(name, "the name contains a NUL byte")
    if "\\" in name:
        raise ResourceRefused(name, "the name contains a backslash (separate folders with '/')")
    rel = name
    if name.startswith("package://"):
        package, _, rel = name[len("package://") :].partition("/")
        if not package:
            raise ResourceRefused(name, "the package name is missing (package://<package>/<path>)")
    elif _SCHEME_RE.match(name):
        scheme = name.split(":", 1)[0]
        raise ResourceRefused(
            name,
            f"{scheme}: names are never opened (give package://<package>/<path> or a path "
            "relative to the mesh roots)",
        )
    if rel.startswith("/") or name.startswith("/"):
        raise ResourceRefused(
            name, "absolute paths are never opened (give a path relative to the mesh roots)"
        )
    parts = [p for p in PurePosixPath(rel).parts if p != "."]
    if ".." in rel.split("/"):
        raise ResourceRefused(name, "'..' segments are not allowed")
    if not parts:
        raise ResourceRefused(name, "the name gives no file")
    return parts


def _inside(path: Path, root: Path) -> bool:
    return path == root or root in path.parents


def _walk(
    name: str, root: Path, parts: list[str], roots: list[Path]
) -> tuple[Path, os.stat_result]:
    """Resolve ``root/parts`` like realpath, stat-ing only paths inside ``roots``.

    ``root`` and ``roots`` are real paths. Returns the real path of a regular file and its
    ``lstat``; raises :class:`ResourceRefused` (outside the roots, loop) or FileNotFoundError.
    """
    current = root
    pending = list(parts)
    hops = 0
    st: os.stat_result | None = None
    while pending:
        part = pending.pop(0)
        if part in ("", "."):
            continue
        if part == "..":  # only from a symlink's target; ``current`` is a real path
            current = current.parent
            st = None
            continue
        candidate = current / part
        if any(_inside(candidate, r) for r in roots):
            st = os.lstat(candidate)  # FileNotFoundError / NotADirectoryError propagate
            if stat.S_ISLNK(st.st_mode):
                hops += 1
                if hops > _MAX_SYMLINKS:
                    raise ResourceRefused(name, "too many levels of symbolic links")
                target = os.readlink(candidate)
                if target.startswith("/"):
                    current = Path("/")
                pending[:0] = [p for p in target.split("/") if p]
                st = None
                continue
            current = candidate
        elif any(candidate in r.parents for r in roots):  # on a root's own real path: no stat
            current = candidate
            st = None
        else:
            raise ResourceRefused(name, "it resolves outside the mesh roots (symbolic link)")
    if st is None or not any(_inside(current, r) for r in roots):
        raise ResourceRefused(name, "it resolves outside the mesh roots (symbolic link)")
    if not stat.S_ISREG(st.st_mode):
        raise ResourceRefused(name, "it is not a regular file")
    return current, st


def _confine(name: str, roots: Sequence[PathLike]) -> tuple[Path, os.stat_result]:
    if not roots:
        raise ResourceRefused(name, NO_FILE_ACCESS)
    parts = _relative_parts(name)
    real_roots = [Path(os.path.realpath(os.fspath(r))) for r in roots]
    for root in real_roots:
        try:
            return _walk(name, root, parts, real_roots)
        except (FileNotFoundError, NotADirectoryError):
            continue
        except OSError as exc:
            raise ResourceRefused(name, f"it could not be read ({exc.strerror})") from None
    raise ResourceRefused(name, "no such file under the mesh roots")


def confine_resource(name: str, roots: Sequence[PathLike]) -> Path:
    """The real path of the regular file that ``name`` (a robot file's resource name) designates
    inside one of ``roots`` (see the module docstring for what is accepted).

    Raises :class:`ResourceRefused` — with no roots always, without any file system access."""
    return _confine(name, roots)[0]


def read_resource(name: str, roots: Sequence[PathLike], *, max_bytes: int) -> tuple[Path, bytes]:
    """(real path, contents) of the file ``name`` designates inside ``roots``, at most
    ``max_bytes`` bytes long (else :class:`ResourceRefused`). The file is opened with
    ``O_NOFOLLOW`` and must be the very file the confinement walk found."""
    path, found = _confine(name, roots)
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(path, flags | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise ResourceRefused(name, f"it could not be opened ({exc.strerror})") from None
    with os.fdopen(fd, "rb") as f:
        st = os.fstat(f.fileno())
        if (st.st_dev, st.st_ino) != (found.st_dev, found.st_ino) or not stat.S_ISREG(st.st_mode):
            raise ResourceRefused(name, "the file changed while it was being opened")
        if st.st_size > max_bytes:
            raise ResourceRefused(
                name, f"it is {st.st_size / 1e6:.1f} MB, over the {max_bytes / 1e6:.1f} MB limit"
            )
        data = f.read(max_bytes + 1)
    if len(data) > max_bytes:
        raise ResourceRefused(name, f"it is over the {max_bytes / 1e6:.1f} MB limit")
    return path, data
