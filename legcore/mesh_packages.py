"""The directories a robot's ``package://`` meshes may be read from: installed robot-description
packages on an allow-list, plus roots the operator configures — never a path a user wrote.

A URDF from ``example-robot-data`` names its meshes
``package://example-robot-data/robots/solo_description/meshes/stl/solo12/…``; that package's
wheel installs them under ``<site-packages>/cmeel.prefix/share/example-robot-data``. This
module finds such directories through the installed distributions' metadata
(``importlib.metadata``) for the packages of :data:`MESH_PACKAGES` only; the operator adds others
with ``LEGOPT_MESH_ROOTS`` (``Settings.mesh_roots``). :mod:`legcore.resource_paths` then
confines every mesh name to these roots (no ``..``, no absolute path, no other scheme, no
symbolic link out), and :mod:`legcore.recording` reads only mesh formats it can draw, each at
most ``MAX_MESH_BYTES``. Pure lookups, no file is opened here.
"""

from __future__ import annotations

import importlib.metadata
import os
from collections.abc import Sequence
from functools import cache
from pathlib import Path

__all__ = ["MESH_PACKAGES", "installed_mesh_roots", "mesh_roots"]

#: Robot-description distributions whose installed mesh folders may be read: distribution name
#: -> the folder inside it that ``package://<package>/`` names resolve against.
MESH_PACKAGES: dict[str, str] = {
    "example-robot-data": "cmeel.prefix/share/example-robot-data",
}


@cache
def installed_mesh_roots() -> tuple[Path, ...]:
    """The mesh folders of the installed distributions of :data:`MESH_PACKAGES` (those that
    are installed and have the folder), in the order of that table."""
    roots: list[Path] = []
    for dist_name, folder in MESH_PACKAGES.items():
        try:
            dist = importlib.metadata.distribution(dist_name)
        except importlib.metadata.PackageNotFoundError:
            continue
        path = Path(str(dist.locate_file(folder)))
        if path.is_dir():
            roots.append(path)
    return tuple(roots)


def mesh_roots(configured: Sequence[str | os.PathLike[str]] = ()) -> tuple[Path, ...]:
    """Every root a mesh may be read from: the installed packages' (:func:`installed_mesh_roots`)
    then the ``configured`` ones that are directories (an operator's setting, not user input)."""
    extra = tuple(Path(p) for p in configured if Path(p).is_dir())
    return installed_mesh_roots() + extra
