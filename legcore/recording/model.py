"""Items of a recording (what is logged, independent of Rerun) and its constants."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    pass

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
#: Directories that URDF mesh names may resolve into (:mod:`legcore.resource_paths`).
MeshRoots = Sequence[str | os.PathLike[str]]

#: Mesh formats a recording can show (Rerun ``Asset3D``); other names are noted, never opened.
MESH_SUFFIXES = frozenset({".stl", ".obj", ".glb", ".gltf"})
#: Largest mesh file embedded in a recording (bytes).
MAX_MESH_BYTES = 8_000_000

#: Samples per displayed signal / pose track unless told otherwise.
DEFAULT_MAX_SAMPLES = 2000

#: Joint signals of a Motion: (attribute, unit, label).
SIGNALS: tuple[tuple[str, str, str], ...] = (
    ("q", "rad", "joint position"),
    ("qd", "rad/s", "joint velocity"),
    ("qdd", "rad/s²", "joint acceleration"),
    ("jerk", "rad/s³", "joint jerk"),
    ("tau", "N·m", "joint torque"),
    ("power", "W", "joint power"),
)

#: The signals a baseline is recorded with by default (``record_run(baseline_signals=...)``):
#: what the default blueprint shows of it — its joint positions (one view for all baselines)
#: and its total energy (overlaid on the best motion's). Each further signal costs a small
#: recording ~4 kB per baseline and ~4 kB for its entity (docs/recording.md §3); ``None``
#: records them all.
BASELINE_SIGNALS: tuple[str, ...] = ("q", "energy/total")

# colours (RGB 0-255) for the items the writer draws
C_PATH = (255, 140, 0)
C_BASELINE = (150, 150, 150)
C_TARGET = (30, 144, 255)
C_OBSTACLE = (220, 50, 47)
C_SUPPORT = (46, 160, 67)
C_LINK = (120, 130, 150)
C_BODY = (90, 100, 120)
C_TOOL = (255, 215, 0)
C_FRONT = (38, 139, 210)
C_BEST = (220, 50, 47)
C_GROUND = (160, 140, 110)


# ---------------------------------------------------------------------------------------------
# items
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Series:
    """One scalar signal on a timeline: ``index`` (N,) is time in s (``timeline == "time"``) or
    the generation number (``"generation"``); ``values`` (N,) in ``unit``. ``source_samples`` is
    the length before downsampling. ``group``: the entity under which the writer logs this
    series together with its siblings of the same group (the joints of one signal, which share
    their ``index``): one ``Scalars`` batch per sample, one series per joint; None: its own
    entity at ``path``."""

    path: str
    timeline: str
    index: FloatArray
    values: FloatArray
    label: str
    unit: str
    source_samples: int
    group: str | None = None

    @property
    def n_samples(self) -> int:
        return int(self.values.shape[0])


@dataclass(frozen=True, eq=False)
class PoseTrack:
    """A rigid pose ``world ← entity`` over time (``t`` (N,), ``translation`` (N, 3),
    ``rotation`` (N, 3, 3)), or static when ``t`` is None (then N = 1).

    ``geometry`` is what is drawn in the entity's own frame: ``"axes"`` (a link frame, axes of
    ``axis_length``), ``"capsule"`` (a link: from the origin along +z, ``length``, ``radius``),
    ``"box"`` (centred, ``half_size``) or ``"mesh"`` (the bytes ``mesh_data`` of the file
    ``mesh``, read inside the mesh roots by :mod:`legcore.resource_paths`; scale ``half_size``).
    A writer logs ``mesh_data`` and never opens ``mesh``: it only names the file and its format.
    """

    path: str
    t: FloatArray | None
    translation: FloatArray
    rotation: FloatArray
    geometry: str
    axis_length: float = 0.0
    length: float = 0.0
    radius: float = 0.0
    half_size: tuple[float, float, float] = (0.0, 0.0, 0.0)
    color: tuple[int, int, int] = C_LINK
    source_samples: int = 1
    mesh: str = ""  # geometry "mesh": the mesh file's real path (for its name and format only)
    mesh_data: bytes = b""  # geometry "mesh": its contents, read inside the mesh roots

    @property
    def n_samples(self) -> int:
        return int(self.translation.shape[0])


@dataclass(frozen=True, eq=False)
class PointTrack:
    """Moving points: ``positions`` (N, P, 3) — P points at each of the times ``t`` (N,)."""

    path: str
    t: FloatArray
    positions: FloatArray
    radius: float
    color: tuple[int, int, int] = C_TOOL
    source_samples: int = 1


@dataclass(frozen=True, eq=False)
class Polyline:
    """A static line strip ``points`` (P, 3) (closed: the first point is repeated at the end)."""

    path: str
    points: FloatArray
    radius: float
    color: tuple[int, int, int] = C_PATH
    source_samples: int = 0


@dataclass(frozen=True, eq=False)
class PolylineTrack:
    """A line strip over time: ``strips[i]`` (P_i, 3) at time ``t[i]`` (N strips)."""

    path: str
    t: FloatArray
    strips: list[FloatArray]
    radius: float
    color: tuple[int, int, int] = C_SUPPORT
    source_samples: int = 1


@dataclass(frozen=True, eq=False)
class PointSet:
    """Static points ``points`` (M, 3)."""

    path: str
    points: FloatArray
    radius: float
    color: tuple[int, int, int] = C_TARGET


@dataclass(frozen=True, eq=False)
class BoxSet:
    """Static axis-aligned boxes: ``centers`` (B, 3), ``half_sizes`` (B, 3)."""

    path: str
    centers: FloatArray
    half_sizes: FloatArray
    color: tuple[int, int, int] = C_OBSTACLE


@dataclass(frozen=True, eq=False)
class FrontTrack:
    """Points in objective space per generation: ``points[g]`` (k_g, d) at ``generations[g]``.

    ``d`` = 2 or 3 (the first three objectives when there are more); ``objective_names`` the d
    names; ``source``: ``"per_generation"`` or ``"final_only"`` (see the module docstring);
    ``source_sizes[g]``: points before capping."""

    path: str
    generations: IntArray
    points: list[FloatArray]
    objective_names: tuple[str, ...]
    source: str
    source_sizes: list[int]
    radius: float
    color: tuple[int, int, int] = C_FRONT

    @property
    def dims(self) -> int:
        return int(self.points[0].shape[1]) if self.points else 0


@dataclass(frozen=True, eq=False)
class MotionRecording:
    """Everything logged for one decoded motion (the best solution or a baseline)."""

    name: str
    n_source: int
    max_samples: int
    series: list[Series] = field(default_factory=list)
    poses: list[PoseTrack] = field(default_factory=list)
    points: list[PointTrack] = field(default_factory=list)
    polylines: list[Polyline] = field(default_factory=list)
    polyline_tracks: list[PolylineTrack] = field(default_factory=list)
    point_sets: list[PointSet] = field(default_factory=list)
    boxes: list[BoxSet] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def series_at(self, path: str) -> Series:
        for s in self.series:
            if s.path == path:
                return s
        raise KeyError(path)

    def entity_paths(self) -> list[str]:
        items: list[Any] = [
            *self.series,
            *self.poses,
            *self.points,
            *self.polylines,
            *self.polyline_tracks,
            *self.point_sets,
            *self.boxes,
        ]
        return [i.path for i in items]


@dataclass(frozen=True, eq=False)
class RunRecording:
    """Everything logged for one job: the best motion, baselines, optimisation history, front."""

    title: str
    best: MotionRecording | None
    baselines: dict[str, MotionRecording]
    optimization: list[Series]
    front: FrontTrack | None
    best_point: FrontTrack | None
    properties: dict[str, Any]
    notes: list[str] = field(default_factory=list)

    def motions(self) -> list[MotionRecording]:
        return ([self.best] if self.best is not None else []) + list(self.baselines.values())

    def entity_paths(self) -> list[str]:
        out: list[str] = []
        for m in self.motions():
            out.extend(m.entity_paths())
        out.extend(s.path for s in self.optimization)
        out.extend(f.path for f in (self.front, self.best_point) if f is not None)
        return out
