"""Catalog of the seed papers' robots, by name.

    >>> from legcore.robots import catalog
    >>> catalog.names()
    ('animatronic_quadruped', 'articulated_5dof', 'calderon_leg', 'citedi_hexapod', 'puma560')
    >>> catalog.get("puma560").nq
    6

Each entry's module docstring names its source (seed paper, table) and every assumed value.
Serial robots come back as :class:`~legcore.robots.model.Robot`, multi-legged ones as
:class:`~legcore.robots.legged.LeggedRobot`.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from functools import cache
from typing import Any

from legcore.robots.legged import LeggedRobot
from legcore.robots.model import Robot

__all__ = ["get", "names", "source"]

_ENTRIES: dict[str, str] = {
    "animatronic_quadruped": "legcore.robots.catalog.animatronic_quadruped",
    "articulated_5dof": "legcore.robots.catalog.articulated_5dof",
    "calderon_leg": "legcore.robots.catalog.calderon_leg",
    "citedi_hexapod": "legcore.robots.catalog.citedi_hexapod",
    "puma560": "legcore.robots.catalog.puma560",
}


def names() -> tuple[str, ...]:
    """The catalog names, sorted."""
    return tuple(sorted(_ENTRIES))


def _module(name: str) -> Any:
    if name not in _ENTRIES:
        raise KeyError(f"unknown catalog robot {name!r}; known: {', '.join(names())}")
    return importlib.import_module(_ENTRIES[name])


@cache
def get(name: str) -> Robot | LeggedRobot:
    """Build (once, then cached — robots are immutable) the catalog robot ``name``."""
    build: Callable[[], Robot | LeggedRobot] = _module(name).build
    return build()


def source(name: str) -> str:
    """The provenance text (module docstring) of catalog entry ``name``."""
    return (_module(name).__doc__ or "").strip()
