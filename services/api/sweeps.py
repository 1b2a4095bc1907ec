"""Pure expansion of a sweep request into job spec documents (no I/O, no validation of specs).

A sweep is a base job spec plus

- ``grid``: ``{"dotted.path": [v1, v2, ...], ...}`` — the cartesian product of its axes;
- ``list``: ``[{"dotted.path": value, ...}, ...]`` — explicit override sets;
- ``seeds``: ``[s1, s2, ...]`` — each point repeated once per seed.

The jobs are ``grid points × list entries × seeds`` (an empty part counts as one neutral
factor), in that nesting order. A dotted path addresses any field of the spec document: mapping
keys by name and list items by index, e.g. ``optimizer.params.mutation_rate``,
``problem.weights.0``, ``robot.joints.1.mass`` (inline or stored robots only). Missing mapping
keys along a path are created, so ``optimizer.params.pop_size`` works on a base without
``optimizer.params`` (the result is validated afterwards like any job spec).

Points are built copy-on-write (``with_overrides``): each shares every subtree its overrides do
not touch with the base, so expansion costs O(points × path length) whatever the size of the
base (an inline URDF robot of 2 MB is never copied). Point specs are read-only.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from services.store.settings import Settings
from services.store.spec_paths import OverrideError, split_path, with_overrides

Loc = tuple[str | int, ...]

#: Default limit on the number of jobs one sweep may create (``Settings.max_sweep_jobs``).
MAX_SWEEP_JOBS: int = Settings.model_fields["max_sweep_jobs"].default

class SweepError(ValueError):
    """A sweep request that cannot be expanded; ``loc`` is relative to the request body."""

    def __init__(self, loc: Loc, message: str) -> None:
        super().__init__(message)
        self.loc = loc
        self.message = message


@dataclass(frozen=True)
class SweepPoint:
    """One job of a sweep: its overrides (dotted path -> value), the spec, and where each
    override came from in the request: ``("grid", path, i)`` (the i-th value of an axis),
    ``("list", k, path)`` or ``("seeds", j)``."""

    index: int
    overrides: dict[str, Any]
    spec: dict[str, Any]
    sources: dict[str, Loc] = field(default_factory=dict)

    def source_of(self, loc: Sequence[str | int]) -> Loc | None:
        """The request location of the override that set ``loc`` (a spec location), if any."""
        parts = [str(p) for p in loc]
        best: tuple[int, Loc] | None = None
        for path, source in self.sources.items():
            segs = path.split(".")
            if parts[: len(segs)] == segs and (best is None or len(segs) > best[0]):
                best = (len(segs), source)
        return None if best is None else best[1]


def count_points(
    grid: Mapping[str, Sequence[Any]], entries: Sequence[Any], seeds: Sequence[Any]
) -> int:
    """Number of jobs ``expand`` would create (computed without creating them)."""
    n_grid = math.prod(len(values) for values in grid.values()) if grid else 1
    return n_grid * max(1, len(entries)) * max(1, len(seeds))


def _check_axes(
    grid: Mapping[str, Sequence[Any]], entries: Sequence[Mapping[str, Any]], seeds: Sequence[Any]
) -> None:
    for path, values in grid.items():
        try:
            split_path(path)
        except ValueError as exc:
            raise SweepError(("grid", path), str(exc)) from None
        if len(values) == 0:
            raise SweepError(("grid", path), "an axis needs at least one value")
    for k, entry in enumerate(entries):
        for path in entry:
            try:
                split_path(path)
            except ValueError as exc:
                raise SweepError(("list", k, path), str(exc)) from None
            if path in grid:
                raise SweepError(
                    ("list", k, path), f"{path!r} is also a grid axis; sweep it in one place"
                )
    if seeds:
        if "seed" in grid:
            raise SweepError(("seeds",), "'seed' is also a grid axis; use one or the other")
        for k, entry in enumerate(entries):
            if "seed" in entry:
                raise SweepError(("list", k, "seed"), "'seed' is also given by 'seeds'")


def expand(
    base: Mapping[str, Any],
    grid: Mapping[str, Sequence[Any]] | None = None,
    entries: Sequence[Mapping[str, Any]] | None = None,
    seeds: Sequence[Any] | None = None,
    *,
    max_jobs: int = MAX_SWEEP_JOBS,
) -> list[SweepPoint]:
    """All job spec documents of a sweep (see the module docstring), in order.

    Raises ``SweepError`` (with the request location) for an empty axis, a malformed path, a
    path swept in two places, more than ``max_jobs`` jobs, or an override that cannot be set.
    """
    grid = dict(grid or {})
    entries = list(entries or [])
    seeds = list(seeds or [])
    _check_axes(grid, entries, seeds)
    n = count_points(grid, entries, seeds)
    if n > max_jobs:
        raise SweepError((), f"the sweep would create {n} jobs; the limit is {max_jobs} per sweep")

    axes = list(grid.items())
    grid_points = itertools.product(*(range(len(values)) for _, values in axes))
    entry_options: list[tuple[int | None, Mapping[str, Any]]] = (
        list(enumerate(entries)) if entries else [(None, {})]
    )
    seed_options: list[tuple[int | None, Any]] = list(enumerate(seeds)) if seeds else [(None, None)]

    points: list[SweepPoint] = []
    for combo in grid_points:
        for k, entry in entry_options:
            for j, seed in seed_options:
                overrides: dict[str, Any] = {}
                sources: dict[str, Loc] = {}
                for (path, values), i in zip(axes, combo, strict=True):
                    overrides[path] = values[i]
                    sources[path] = ("grid", path, i)
                for path, value in entry.items():
                    overrides[path] = value
                    sources[path] = ("list", k if k is not None else 0, path)
                if j is not None:
                    overrides["seed"] = seed
                    sources["seed"] = ("seeds", j)
                try:
                    spec = with_overrides(base, overrides)
                except OverrideError as exc:
                    raise SweepError(sources[exc.path], str(exc)) from None
                points.append(SweepPoint(len(points), overrides, spec, sources))
    return points


def swept_paths(
    grid: Mapping[str, Any] | None,
    entries: Sequence[Mapping[str, Any]] | None,
    seeds: Sequence[Any] | None,
) -> list[str]:
    """The columns of a sweep's table: every path it varies, in request order."""
    paths: list[str] = list(grid or {})
    for entry in entries or []:
        paths.extend(p for p in entry if p not in paths)
    if seeds and "seed" not in paths:
        paths.append("seed")
    return paths


__all__ = [
    "MAX_SWEEP_JOBS",
    "SweepError",
    "SweepPoint",
    "count_points",
    "expand",
    "swept_paths",
]
