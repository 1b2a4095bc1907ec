"""A run → the plain time series its Rerun recording shows (pure: numpy only, no Rerun here).

:func:`record_run` turns a :class:`~legcore.runner.RunResult` (and :func:`record_motion` a single
:class:`~legcore.problems.study.Motion`) into a :class:`RunRecording`: a flat list of items, each
with its entity path, its timeline and its numbers. ``services.worker.rerun_writer`` — the only
module that imports Rerun — logs them one archetype per item; nothing here knows about Rerun.

Entity paths (``docs/recording.md`` has the full table). Items are named per joint, frame and
link here; ``services.worker.rerun_writer`` logs several of them as one entity:

- ``signals/<q|qd|qdd|jerk|tau|power>/<joint>`` — one scalar series per joint on the ``time``
  timeline (s); ``signals/energy/<joint>`` the cumulative ``∫|P_i| dt`` of that joint (J) and
  ``signals/energy/total`` the motion's own cumulative energy (``Motion.energy``). The joints
  of one signal share their samples and are logged as one entity, ``signals/<kind>``
  (``Series.group``).
- ``world/robot[/<leg>]/frames/<k>`` — link frame ``k`` (0 = base) in the world over time
  (``legcore.kinematics.frames``, one batched call for all displayed samples);
  ``.../frames/<k>/link`` — the link drawn as a capsule from frame origin ``k-1`` to frame
  origin ``k``, posed relative to frame ``k`` (static there for DH chains), and
  ``.../frames/<n>/tool_link`` from the last frame's origin to the tool point when they differ;
  ``world/robot/body`` the body box of a legged robot. A robot drawn without meshes is logged
  as **one entity** ``world/robot/links``: per sample 3 arrows (x / y / z) per drawn frame —
  every frame of a serial robot, a legged robot's joint frames between each leg's base and
  foot frame —, the capsules and the body box posed in the world. A URDF robot with meshes
  keeps one entity per frame and link.
- ``world/robot/tool`` the moving tool point (serial robots); ``world/path`` the motion's
  tool/foot path (``Motion.tool``); ``world/robot/<leg>/foot_path`` each leg's foot path
  (legged), logged in the ``world/path`` entity (labelled ``path``, ``L1``, …). A pose that
  does not change over the motion is logged once, static.
- ``world/scene/<targets|obstacles|support_polygon|...>`` from ``Motion.scene``.
- ``baselines/<name>/signals/...`` the signals of each baseline — by default only ``q`` and
  ``energy/total`` (:data:`BASELINE_SIGNALS`; ``record_run(baseline_signals=None)`` keeps all)
  —, logged as one entity per signal for all baselines, ``baselines/signals/<kind>``, when they
  share their samples; ``world/baselines/<name>/path`` each baseline's path, logged together
  as ``world/baselines/paths``.
- ``optimization/best/<objective>`` (best objective per generation), ``optimization/front_size``,
  ``optimization/ideal|nadir/<objective>``, ``optimization/constraint_violation`` on the
  ``generation`` timeline (the objectives of best / ideal / nadir: one entity each,
  ``optimization/best`` …, when there are several); ``optimization/front`` the Pareto front
  (points in objective space) per generation and ``optimization/best_point`` the history's best
  (knee) point.

Downsampling (display only; the stored result keeps every sample). A motion of ``K`` samples is
shown with at most ``max_samples`` (default 2000) of them:

- scalar signals use **min/max decimation**: the interior samples are cut into
  ``(max_samples - 2) // 2`` equal buckets and each bucket keeps the samples of its minimum and
  maximum, plus the first and last sample — so peaks (τ_max, jerk spikes) survive; every kept
  value is an original sample at its original time; the joints of one signal keep the union
  of their samples (:func:`shared_minmax_indices`, still at most ``max_samples``);
- poses, the moving tool point, the path and time-varying scene items use a **uniform stride**:
  ``round(linspace(0, K-1, max_samples))``, endpoints included.

Every series records ``source_samples`` (``K``) and ``n_samples`` (what is logged), so the
counts are exact and known. The Pareto front per generation is capped the same way (points
sorted by the first objective, uniform stride) at ``max_front_points``. Size budget: a run's
estimated file size (:func:`estimate_bytes`, constants measured on rerun-sdk 0.41 files) is
kept under ``max_bytes`` (16 MB by default) by lowering the caps in proportion to the excess —
baselines first, then the best motion (never below ``MIN_SAMPLES``), then the front — and
``RunRecording.properties`` records the caps used.

Fronts per generation: a :class:`~legcore.runner.RunResult` carries only the final front
(``pareto``) and a per-generation summary (``history``: best, ideal, nadir, front size). Pass
``fronts={generation: F (k, m)}`` (e.g. collected from each ``Progress.front_F`` in the run's
callback) to log the front of every generation; without it the final front is logged once, at
the last generation, and ``FrontTrack.source`` says ``"final_only"``.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from legcore.resource_paths import ResourceRefused, read_resource

if TYPE_CHECKING:
    from legcore.problems.study import Motion, Solution
    from legcore.robots.legged import LeggedRobot
    from legcore.robots.model import Robot
    from legcore.runner import RunResult

__all__ = [
    "BASELINE_SIGNALS",
    "DEFAULT_MAX_BYTES",
    "DEFAULT_MAX_SAMPLES",
    "MAX_MESH_BYTES",
    "MESH_SUFFIXES",
    "MIN_SAMPLES",
    "SIGNALS",
    "BoxSet",
    "FrontTrack",
    "MotionRecording",
    "PointSet",
    "PointTrack",
    "Polyline",
    "PolylineTrack",
    "PoseTrack",
    "RunRecording",
    "Series",
    "entity_part",
    "estimate_bytes",
    "link_radius",
    "minmax_columns",
    "minmax_indices",
    "quaternion_xyzw",
    "record_motion",
    "record_run",
    "shared_minmax_indices",
    "stride_indices",
    "unique_parts",
]

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


# ---------------------------------------------------------------------------------------------
# downsampling
# ---------------------------------------------------------------------------------------------


def stride_indices(K: int, max_samples: int = DEFAULT_MAX_SAMPLES) -> IntArray:
    """Indices of a uniform-stride subsample of ``K`` samples: all of them when
    ``K <= max_samples``, else ``round(linspace(0, K-1, max_samples))`` (exactly
    ``max_samples`` distinct indices, first and last included)."""
    if max_samples < 2:
        raise ValueError(f"max_samples: must be >= 2, got {max_samples}")
    if K <= max_samples:
        return np.arange(K, dtype=np.int64)
    return np.unique(np.round(np.linspace(0, K - 1, max_samples)).astype(np.int64))


def minmax_indices(y: FloatArray, max_samples: int = DEFAULT_MAX_SAMPLES) -> IntArray:
    """Indices of a min/max decimation of the signal ``y`` (K,): all of them when
    ``K <= max_samples``; else the first and last sample plus, in each of
    ``(max_samples - 2) // 2`` equal buckets of the interior, the samples of the bucket's
    minimum and maximum (NaN ignored). At most ``max_samples`` sorted distinct indices."""
    y = np.asarray(y, dtype=float)
    return minmax_columns(y[:, None], max_samples)[0]


def shared_minmax_indices(Y: FloatArray, max_samples: int = DEFAULT_MAX_SAMPLES) -> IntArray:
    """One set of indices for all columns of ``Y`` (K, n) (the joints of one signal, logged as
    one entity): all of them when ``K <= max_samples``; else the union over columns of each
    column's :func:`minmax_columns` at the largest per-column cap (at least 4) whose union has
    at most ``max_samples`` sorted distinct indices — every column keeps its bucket minima and
    maxima, every kept value is an original sample."""
    Y = np.asarray(Y, dtype=float)
    K, n = Y.shape
    if K <= max_samples:
        return np.arange(K, dtype=np.int64)
    per = max_samples
    while True:  # joints often peak together: shrink the per-joint cap only as far as needed
        idx = np.unique(np.concatenate(minmax_columns(Y, per)))
        if idx.size <= max_samples or per <= 4:
            return idx
        per = max(4, min(per - 2, int(per * max_samples / idx.size)))


def minmax_columns(Y: FloatArray, max_samples: int = DEFAULT_MAX_SAMPLES) -> list[IntArray]:
    """:func:`minmax_indices` of every column of ``Y`` (K, n) in one vectorised pass."""
    Y = np.asarray(Y, dtype=float)
    K, n = Y.shape
    if max_samples < 4:
        return [stride_indices(K, max(2, max_samples))] * n
    if K <= max_samples:
        return [np.arange(K, dtype=np.int64)] * n
    n_buckets = (max_samples - 2) // 2
    edges = np.linspace(1, K - 1, n_buckets + 1).astype(np.int64)  # interior 1 .. K-2
    starts, stops = edges[:-1], edges[1:]
    width = int(np.max(stops - starts))
    # gather each bucket into a (n_buckets, width) window, padding with the bucket's first sample
    idx = starts[:, None] + np.arange(width)[None, :]
    idx = np.where(idx < stops[:, None], idx, starts[:, None])
    win = Y[idx]  # (n_buckets, width, n)
    finite = np.isfinite(win)
    rows = np.arange(n_buckets)[:, None]
    imin = idx[rows, np.argmin(np.where(finite, win, np.inf), axis=1)]  # (n_buckets, n)
    imax = idx[rows, np.argmax(np.where(finite, win, -np.inf), axis=1)]
    ends = np.array([0, K - 1], dtype=np.int64)
    return [np.unique(np.concatenate((ends, imin[:, j], imax[:, j]))) for j in range(n)]


# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------

_PART_RE = re.compile(r"[^A-Za-z0-9_\-]+")


def entity_part(name: str) -> str:
    """``name`` as one entity-path part: runs of characters other than letters, digits, ``_``
    and ``-`` become ``_`` (``"L1.θ2"`` → ``"L1_2"``); empty → ``"_"``."""
    s = _PART_RE.sub("_", str(name)).strip("_")
    return s or "_"


def unique_parts(names: Iterable[str]) -> list[str]:
    """:func:`entity_part` of each name, duplicates suffixed ``_2``, ``_3``, ..."""
    out: list[str] = []
    seen: set[str] = set()
    for n in names:
        p = entity_part(n)
        base, k = p, 2
        while p in seen:
            p = f"{base}_{k}"
            k += 1
        seen.add(p)
        out.append(p)
    return out


def _cumtrapz(y: FloatArray, t: FloatArray) -> FloatArray:
    """Cumulative trapezoid integral of ``y`` (K, ...) over ``t`` (K,), starting at 0."""
    out = np.zeros_like(y, dtype=float)
    if y.shape[0] > 1:
        dt = np.diff(t).reshape((-1,) + (1,) * (y.ndim - 1))
        out[1:] = np.cumsum(0.5 * (y[1:] + y[:-1]) * dt, axis=0)
    return out


def _z_to(d: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Rotations (N, 3, 3) taking +z onto the directions ``d`` (N, 3), and the lengths |d| (N,).

    Zero-length directions give the identity."""
    L = np.linalg.norm(d, axis=-1)
    safe = L > 1e-12
    u = np.where(safe[:, None], d / np.where(safe, L, 1.0)[:, None], np.array([0.0, 0.0, 1.0]))
    c = u[:, 2]
    v = np.stack([-u[:, 1], u[:, 0], np.zeros_like(c)], axis=-1)  # z × u
    Vx = np.zeros((u.shape[0], 3, 3))
    Vx[:, 0, 1], Vx[:, 0, 2] = -v[:, 2], v[:, 1]
    Vx[:, 1, 0], Vx[:, 1, 2] = v[:, 2], -v[:, 0]
    Vx[:, 2, 0], Vx[:, 2, 1] = -v[:, 1], v[:, 0]
    opposite = c < -1.0 + 1e-9
    k = np.where(opposite, 0.0, 1.0 / np.where(opposite, 1.0, 1.0 + c))
    R = np.eye(3)[None] + Vx + (Vx @ Vx) * k[:, None, None]
    R[opposite] = np.diag([1.0, -1.0, -1.0])
    return R, L


def quaternion_xyzw(R: FloatArray) -> FloatArray:
    """Unit quaternions (..., 4) as (x, y, z, w), w >= 0, of rotation matrices ``R`` (..., 3, 3)
    (Shepperd's method: the largest of the four squared components is taken as the pivot)."""
    R = np.asarray(R, dtype=float)
    m00, m11, m22 = R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]
    tr = m00 + m11 + m22
    cand = np.stack([tr, m00, m11, m22], axis=-1)
    k = np.argmax(cand, axis=-1)
    q = np.empty(R.shape[:-2] + (4,))
    # case w largest
    s = np.sqrt(np.maximum(1.0 + cand[..., 0], 1e-300)) * 2.0
    qw = np.stack(
        [
            (R[..., 2, 1] - R[..., 1, 2]) / s,
            (R[..., 0, 2] - R[..., 2, 0]) / s,
            (R[..., 1, 0] - R[..., 0, 1]) / s,
            0.25 * s,
        ],
        axis=-1,
    )
    s = np.sqrt(np.maximum(1.0 + m00 - m11 - m22, 1e-300)) * 2.0
    qx = np.stack(
        [
            0.25 * s,
            (R[..., 0, 1] + R[..., 1, 0]) / s,
            (R[..., 0, 2] + R[..., 2, 0]) / s,
            (R[..., 2, 1] - R[..., 1, 2]) / s,
        ],
        axis=-1,
    )
    s = np.sqrt(np.maximum(1.0 - m00 + m11 - m22, 1e-300)) * 2.0
    qy = np.stack(
        [
            (R[..., 0, 1] + R[..., 1, 0]) / s,
            0.25 * s,
            (R[..., 1, 2] + R[..., 2, 1]) / s,
            (R[..., 0, 2] - R[..., 2, 0]) / s,
        ],
        axis=-1,
    )
    s = np.sqrt(np.maximum(1.0 - m00 - m11 + m22, 1e-300)) * 2.0
    qz = np.stack(
        [
            (R[..., 0, 2] + R[..., 2, 0]) / s,
            (R[..., 1, 2] + R[..., 2, 1]) / s,
            0.25 * s,
            (R[..., 1, 0] - R[..., 0, 1]) / s,
        ],
        axis=-1,
    )
    q = np.where(
        (k == 0)[..., None],
        qw,
        np.where((k == 1)[..., None], qx, np.where((k == 2)[..., None], qy, qz)),
    )
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., 3:4] < 0, -q, q)


def _fill_nan_rows(a: FloatArray) -> tuple[FloatArray, int]:
    """Forward- (then backward-) fill rows of ``a`` (N, ...) that contain NaN; count of them."""
    flat = a.reshape(a.shape[0], -1)
    bad = ~np.all(np.isfinite(flat), axis=1)
    n_bad = int(bad.sum())
    if n_bad == 0 or n_bad == a.shape[0]:
        return a, n_bad
    good = np.flatnonzero(~bad)
    pos = np.arange(a.shape[0])
    src = good[np.clip(np.searchsorted(good, pos, side="right") - 1, 0, None)]
    src = np.where(pos < good[0], good[0], src)
    return a[src], n_bad


def _chain_scale(robot: Robot) -> float:
    """Sum of the distances between consecutive frame origins (and the tool) at ``home`` (m)."""
    from legcore.kinematics import fk, frames

    F = frames(robot, robot.home)
    p = np.concatenate([F[:, :3, 3], fk(robot, robot.home)[None, :3, 3]])
    return float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=-1)))


def link_radius(robot: Robot | LeggedRobot) -> float:
    """Drawing radius of the links (m): 3.5 % of the longest chain's length at home
    (PUMA 560 ≈ 6 cm, the CITEDI hexapod's legs ≈ 4 mm), at least 1 mm."""
    chains = [leg.robot for leg in robot.legs] if hasattr(robot, "legs") else [robot]
    scale = max(_chain_scale(c) for c in chains)
    return max(0.035 * scale, 1e-3)


def _as_float(a: Any) -> FloatArray | None:
    try:
        out = np.asarray(a, dtype=float)
    except (TypeError, ValueError):
        return None
    return out


# ---------------------------------------------------------------------------------------------
# one motion
# ---------------------------------------------------------------------------------------------


def _signal_series(motion: Motion, prefix: str, max_samples: int, parts: list[str]) -> list[Series]:
    t = np.asarray(motion.t, dtype=float)
    K = t.shape[0]
    out: list[Series] = []

    def add(paths: list[str], Y: FloatArray, labels: list[str], unit: str) -> None:
        if len(paths) == 1:  # the total energy: an entity of its own
            idx = minmax_columns(Y, max_samples)[0]
            out.append(Series(paths[0], "time", t[idx], Y[idx, 0], labels[0], unit, K))
            return
        idx = shared_minmax_indices(Y, max_samples)
        group = paths[0].rsplit("/", 1)[0]
        for path, label, j in zip(paths, labels, range(Y.shape[1]), strict=True):
            out.append(Series(path, "time", t[idx], Y[idx, j], label, unit, K, group))

    names = motion.joint_names
    for attr, unit, label in SIGNALS:
        a = getattr(motion, attr)
        if a is None:
            continue
        if attr == "power" and motion.power_kind != "mechanical":
            label = f"joint power ({motion.power_kind})"
        add(
            [f"{prefix}/{attr}/{p}" for p in parts],
            np.asarray(a, dtype=float),
            [f"{label} {n}" for n in names],
            unit,
        )
    e_joint = None
    if motion.power is not None:
        e_joint = _cumtrapz(np.abs(np.asarray(motion.power, dtype=float)), t)
        add(
            [f"{prefix}/energy/{p}" for p in parts],
            e_joint,
            [f"cumulative ∫|P| dt {n}" for n in names],
            "J",
        )
    if motion.energy is not None:
        total = np.asarray(motion.energy, dtype=float)[:, None]
        add([f"{prefix}/energy/total"], total, ["energy (total)"], "J")
    elif e_joint is not None:
        add([f"{prefix}/energy/total"], e_joint.sum(axis=1)[:, None], ["energy (Σ ∫|P_i| dt)"], "J")
    return out


def _chains(
    robot: Robot | LeggedRobot, motion: Motion
) -> tuple[list[tuple[str, Robot, FloatArray, slice]], list[str]]:
    """(sub-path, chain, hip pose (4,4) in the body, columns of q) per drawn chain, and notes."""
    from legcore.robots.legged import LeggedRobot

    n = motion.q.shape[1]
    if not isinstance(robot, LeggedRobot):
        serial = robot
        if serial.nq != n:
            return [], [f"robot {serial.name!r} has nq = {serial.nq} but the motion has {n} joints"]
        return [("", serial, np.eye(4), slice(0, n))], []
    legged = robot
    names = list(motion.legs) if motion.legs else [leg.name for leg in legged.legs]
    out: list[tuple[str, Robot, FloatArray, slice]] = []
    col = 0
    for name in names:
        try:
            leg = legged.leg(name)
        except KeyError as exc:
            return [], [str(exc.args[0])]
        out.append(
            (
                f"/{entity_part(name)}",
                leg.robot,
                np.asarray(leg.hip, dtype=float),
                slice(col, col + leg.robot.nq),
            )
        )
        col += leg.robot.nq
    if col != n:
        return [], [f"the legs {names} have {col} joints in all but the motion has {n}"]
    return out, []


#: scene keys that give the body pose: (4,4) or (K,4,4) transforms, or (K,3) / (3,) positions.
BODY_POSE_KEYS = ("body_pose", "body_T", "body_position")
#: scene keys of (K, 3) arrays that are ONE point moving over time (not a set of points).
MOVING_POINT_KEYS = frozenset({"com", "com_ground", "zmp", "cop", "cog"})
#: scene keys never drawn (metadata, body-frame data, directions).
_SKIP_KEYS = frozenset(
    {"frame", "tool", "hips", "body_size", "obstacle_margin", "support_polygon_n"}
)
_DIRECTION_WORDS = ("approach", "direction", "normal", "axis", "velocity", "force", "load")


def _body_poses(motion: Motion, idx: IntArray) -> FloatArray:
    """Body poses (N, 4, 4) at the displayed samples from the first of ``BODY_POSE_KEYS`` in
    the scene ((4,4) or (K,4,4) transforms; (3,) or (K,3) positions); identity otherwise."""
    N, K = idx.shape[0], motion.n_samples
    out = np.broadcast_to(np.eye(4), (N, 4, 4)).copy()
    for key in BODY_POSE_KEYS:
        value = (motion.scene or {}).get(key)
        a = _as_float(value) if value is not None else None
        if a is None:
            continue
        if a.shape == (4, 4):
            return np.broadcast_to(a, (N, 4, 4)).copy()
        if a.shape == (K, 4, 4):
            return a[idx].copy()
        if a.shape == (3,):
            out[:, :3, 3] = a
            return out
        if a.shape == (K, 3):
            out[:, :3, 3] = a[idx]
            return out
    return out


def _pose_track(
    path: str, t: FloatArray, translation: FloatArray, rotation: FloatArray, scale: float, **kw: Any
) -> PoseTrack:
    """A pose track, static (``t`` None, one sample) when the pose does not change over time
    (translation within 1e-9·scale, rotation within 1e-9)."""
    const = bool(
        np.all(np.ptp(translation, axis=0) <= 1e-9 * scale)
        and np.all(np.ptp(rotation, axis=0) <= 1e-9)
    )
    if const:
        return PoseTrack(path, None, translation[:1], rotation[:1], **kw)
    return PoseTrack(path, t, translation, rotation, **kw)


def _robot_items(
    robot: Robot | LeggedRobot,
    motion: Motion,
    idx: IntArray,
    world: str,
    rec: MotionRecording,
    mesh_roots: MeshRoots = (),
) -> None:
    from legcore.kinematics import fk, frames

    chains, notes = _chains(robot, motion)
    rec.notes.extend(notes)
    if not chains:
        return
    radius = link_radius(robot)
    axis_len = 4.0 * radius
    K = motion.n_samples
    t = np.asarray(motion.t, dtype=float)[idx]
    q = np.asarray(motion.q, dtype=float)[idx]
    body = _body_poses(motion, idx)
    if hasattr(robot, "legs"):
        half = tuple(0.5 * float(s) for s in robot.body_size)  # type: ignore[union-attr]
        rec.poses.append(
            _pose_track(
                f"{world}/robot/body",
                t,
                body[:, :3, 3],
                body[:, :3, :3],
                max(1.0, float(np.max(np.abs(body[:, :3, 3])))),
                geometry="box",
                half_size=half,
                color=C_BODY,
                source_samples=K,
            )
        )
    for sub, chain, hip, cols in chains:
        qc, n_bad = _fill_nan_rows(q[:, cols])
        if n_bad == qc.shape[0]:
            rec.notes.append(f"chain {sub or chain.name!r}: no finite configuration to draw")
            continue
        if n_bad:
            rec.notes.append(
                f"chain {sub or chain.name!r}: {n_bad} displayed samples had NaN joints (held)"
            )
        F = frames(chain, qc)  # (N, n+1, 4, 4), one batched call
        T_tool = fk(chain, qc)  # (N, 4, 4)
        base = body @ hip  # (N, 4, 4)
        W = base[:, None] @ F
        p_tool = (base @ T_tool)[:, :3, 3]
        base_path = f"{world}/robot{sub}"
        scale = max(1.0, float(np.max(np.abs(W[:, :, :3, 3]))))
        for k in range(W.shape[1]):
            rec.poses.append(
                _pose_track(
                    f"{base_path}/frames/{k}",
                    t,
                    W[:, k, :3, 3],
                    W[:, k, :3, :3],
                    scale,
                    geometry="axes",
                    axis_length=axis_len,
                    source_samples=K,
                )
            )
        # link k: a capsule from frame origin k-1 to frame origin k, drawn as a child of frame k
        # (static there for DH chains); "tool": from the last frame's origin to the tool point.
        R_all, p_all = W[:, :, :3, :3], W[:, :, :3, 3]
        segments = [(p_all[:, k - 1], k) for k in range(1, W.shape[1])]
        n_last = W.shape[1] - 1
        tool_local = np.einsum("nji,nj->ni", R_all[:, n_last], p_tool - p_all[:, n_last])
        for a_world, frame in segments:
            a_loc = np.einsum("nji,nj->ni", R_all[:, frame], a_world - p_all[:, frame])
            R, L = _z_to(-a_loc)
            rec.poses.append(
                _pose_track(
                    f"{base_path}/frames/{frame}/link",
                    t,
                    a_loc,
                    R,
                    scale,
                    geometry="capsule",
                    length=float(np.median(L)),
                    radius=radius,
                    source_samples=K,
                )
            )
        if float(np.max(np.linalg.norm(tool_local, axis=-1))) > 1e-9:
            R, L = _z_to(tool_local)
            rec.poses.append(
                _pose_track(
                    f"{base_path}/frames/{n_last}/tool_link",
                    t,
                    np.zeros_like(tool_local),
                    R,
                    scale,
                    geometry="capsule",
                    length=float(np.median(L)),
                    radius=radius,
                    source_samples=K,
                )
            )
        if chain.meta.get("urdf"):
            rec.poses.extend(_urdf_visuals(chain, f"{base_path}/frames", rec.notes, mesh_roots))
        if sub:  # each leg's foot path
            rec.polylines.append(
                Polyline(f"{base_path}/foot_path", p_tool, 0.25 * radius, C_PATH, K)
            )
        else:
            rec.points.append(
                PointTrack(f"{world}/robot/tool", t, p_tool[:, None], 1.5 * radius, C_TOOL, K)
            )


def _rpy_matrix(r: float, p: float, y: float) -> FloatArray:
    """URDF ``rpy``: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def _floats(text: str | None, n: int, default: float = 0.0) -> list[float]:
    vals = [float(v) for v in (text or "").split()]
    return vals + [default] * (n - len(vals)) if len(vals) < n else vals[:n]


def _urdf_mesh(
    shape: Any, link: str, k_link: int, mesh_roots: MeshRoots, notes: list[str]
) -> dict[str, Any] | None:
    """The PoseTrack fields of a ``<mesh>`` visual, its file read only inside ``mesh_roots``
    (none: no file access, DESIGN §5); a mesh not read is noted and left to the link capsule."""
    name = shape.get("filename", "")
    drawn = "the link is drawn as a capsule" if k_link > 0 else "it is not drawn"
    try:
        if mesh_roots and os.path.splitext(name)[1].lower() not in MESH_SUFFIXES:
            raise ResourceRefused(
                name, f"only {', '.join(sorted(MESH_SUFFIXES))} meshes can be recorded"
            )
        path, data = read_resource(name, mesh_roots, max_bytes=MAX_MESH_BYTES)
    except ResourceRefused as exc:
        notes.append(f"URDF mesh {name!r} of link {link!r} not read: {exc.reason}; {drawn}")
        return None
    scale = _floats(shape.get("scale"), 3, 1.0)
    return {"geometry": "mesh", "mesh": str(path), "mesh_data": data, "half_size": tuple(scale)}


def _urdf_visuals(
    robot: Robot, frames_path: str, notes: list[str], mesh_roots: MeshRoots = ()
) -> list[PoseTrack]:
    """The ``<visual>`` geometry of a URDF robot, each a static child of its link's frame entity:
    boxes, cylinders (as capsules) and spheres drawn as given; a mesh is drawn only when its name
    resolves to a file inside one of ``mesh_roots`` (:mod:`legcore.resource_paths`; default none:
    no file is ever opened), else noted (``notes``) and left to the link capsule."""
    import xml.etree.ElementTree as ET

    from legcore.robots.build import reject_declarations

    spec = robot.spec
    text = getattr(spec, "urdf", None)
    if not text:
        return []
    try:
        reject_declarations(text)
    except ValueError as exc:
        notes.append(f"URDF visuals not drawn: {exc}")
        return []
    model = robot.model
    index: dict[str, int] = {}
    for f in model.frames:  # the base link: a body frame on the universe joint
        if f.parentJoint == 0 and str(f.type).endswith("BODY"):
            index.setdefault(f.name, 0)
    for k, fid in enumerate(robot.link_frames, start=1):
        index[model.frames[fid].name] = k
    out: list[PoseTrack] = []
    for link in ET.fromstring(text).iter("link"):
        k_link = index.get(link.get("name", ""))
        if k_link is None:
            continue
        for j, visual in enumerate(link.findall("visual")):
            origin = visual.find("origin")
            xyz = np.array(_floats(origin.get("xyz") if origin is not None else None, 3))
            R = _rpy_matrix(*_floats(origin.get("rpy") if origin is not None else None, 3))
            geom = visual.find("geometry")
            shape = geom[0] if geom is not None and len(geom) else None
            if shape is None:
                continue
            path = f"{frames_path}/{k_link}/visual_{j}"
            kw: dict[str, Any] = {}
            p = xyz
            if shape.tag == "box":
                size = _floats(shape.get("size"), 3)
                kw = {"geometry": "box", "half_size": tuple(0.5 * v for v in size)}
            elif shape.tag == "cylinder":
                length, r = float(shape.get("length", "0")), float(shape.get("radius", "0"))
                p = xyz - R @ np.array([0.0, 0.0, 0.5 * length])
                kw = {"geometry": "capsule", "length": length, "radius": r}
            elif shape.tag == "sphere":
                r = float(shape.get("radius", "0"))
                kw = {"geometry": "capsule", "length": 0.0, "radius": r}
            elif shape.tag == "mesh":
                mesh = _urdf_mesh(shape, link.get("name", "?"), k_link, mesh_roots, notes)
                if mesh is None:
                    continue
                kw = mesh
            else:
                continue
            out.append(PoseTrack(path, None, p[None], R[None], color=C_LINK, **kw))
    return out


def _scene_items(
    motion: Motion, idx: IntArray, world: str, radius: float, rec: MotionRecording
) -> None:
    """Scene entries → items. ``obstacles`` (Box list) → boxes; ``support_polygon`` (P,3) or
    (K,P,3) (NaN rows = unused vertices) → closed strip, static or over time; ``ground_z`` →
    a thin ground slab under everything drawn; ``MOVING_POINT_KEYS`` (K,3) and any (K,P,3)
    array → points over time; keys with "path" → a static strip; other (M,3)/(3,) arrays and
    ``feet``/``targets`` dicts of 3-vectors → static points. Body-pose keys, metadata and
    direction-like keys are not drawn."""
    from legcore.problems.study import Box

    K = motion.n_samples
    t = np.asarray(motion.t, dtype=float)[idx]
    ground_z: float | None = None
    for key, value in (motion.scene or {}).items():
        path = f"{world}/scene/{entity_part(key)}"
        if key in _SKIP_KEYS or key in BODY_POSE_KEYS or isinstance(value, str) or value is None:
            continue
        if key == "obstacles" or isinstance(value, Box):
            boxes = [value] if isinstance(value, Box) else list(value or [])
            boxes = [b for b in boxes if isinstance(b, Box)]
            if boxes:
                rec.boxes.append(
                    BoxSet(
                        path,
                        np.array([b.center for b in boxes], dtype=float),
                        np.array([b.half_size for b in boxes], dtype=float),
                        C_OBSTACLE,
                    )
                )
            continue
        if key == "ground_z":
            with_value = _as_float(value)
            if with_value is not None and with_value.ndim == 0 and np.isfinite(with_value):
                ground_z = float(with_value)
            continue
        if isinstance(value, Mapping):
            if key in ("feet", "targets"):
                vals = [_as_float(v) for v in value.values()]
                good = [v for v in vals if v is not None and v.shape == (3,)]
                if good and len(good) == len(vals):
                    rec.point_sets.append(PointSet(path, np.stack(good), 0.8 * radius, C_TARGET))
            continue
        a = _as_float(value)
        if a is None or a.ndim == 0 or a.shape[-1] != 3:
            continue
        if key == "support_polygon":
            if a.ndim == 2:
                v = a[np.all(np.isfinite(a), axis=1)]
                if v.shape[0]:
                    rec.polylines.append(
                        Polyline(
                            path, np.concatenate([v, v[:1]]), 0.3 * radius, C_SUPPORT, v.shape[0]
                        )
                    )
            elif a.ndim == 3 and a.shape[0] == K:
                strips = []
                for poly in a[idx]:
                    v = poly[np.all(np.isfinite(poly), axis=1)]
                    strips.append(np.concatenate([v, v[:1]]) if v.shape[0] else v)
                rec.polyline_tracks.append(
                    PolylineTrack(path, t, strips, 0.3 * radius, C_SUPPORT, K)
                )
            else:
                rec.notes.append(f"scene['support_polygon'] of shape {a.shape} not drawn")
            continue
        if any(w in key.lower() for w in _DIRECTION_WORDS):
            continue
        if a.ndim == 2 and a.shape[0] == K and key in MOVING_POINT_KEYS:
            pts, _ = _fill_nan_rows(a[idx])
            rec.points.append(PointTrack(path, t, pts[:, None], 1.2 * radius, C_SUPPORT, K))
        elif a.ndim == 3 and a.shape[0] == K:
            pts, _ = _fill_nan_rows(a[idx])
            rec.points.append(PointTrack(path, t, pts, 1.0 * radius, C_TARGET, K))
        elif a.ndim <= 2 and "path" in key.lower():
            pts = a.reshape(-1, 3)
            pts = pts[np.all(np.isfinite(pts), axis=1)]
            sel = stride_indices(pts.shape[0], rec.max_samples)
            rec.polylines.append(Polyline(path, pts[sel], 0.2 * radius, C_BASELINE, pts.shape[0]))
        elif a.ndim <= 2:
            pts = a.reshape(-1, 3)
            pts = pts[np.all(np.isfinite(pts), axis=1)]
            sel = stride_indices(pts.shape[0], rec.max_samples)
            color = C_TARGET if "target" in key.lower() else C_SUPPORT
            rec.point_sets.append(PointSet(path, pts[sel], 0.6 * radius, color))
        else:
            rec.notes.append(f"scene[{key!r}] of shape {a.shape} not drawn")
    if ground_z is not None:
        rec.boxes.append(_ground(rec, ground_z, radius, f"{world}/scene/ground"))


def _ground(rec: MotionRecording, z: float, radius: float, path: str) -> BoxSet:
    """A thin slab at height ``z`` under the xy extent of everything drawn so far (+20 %)."""
    pts: list[FloatArray] = [p.points for p in rec.polylines if p.points.size]
    pts += [p.points for p in rec.point_sets if p.points.size]
    pts += [p.positions.reshape(-1, 3) for p in rec.points]
    pts += [p.translation for p in rec.poses if re.search(r"/frames/\d+$", p.path)]
    xy = np.concatenate([p[:, :2] for p in pts]) if pts else np.zeros((1, 2))
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    lo, hi = (xy.min(axis=0), xy.max(axis=0)) if xy.size else (np.zeros(2), np.zeros(2))
    half = np.maximum(0.6 * (hi - lo), 10 * radius)
    c = 0.5 * (lo + hi)
    th = 0.25 * radius
    return BoxSet(
        path, np.array([[c[0], c[1], z - th]]), np.array([[half[0], half[1], th]]), C_GROUND
    )


def record_motion(
    motion: Motion,
    robot: Robot | LeggedRobot | None = None,
    *,
    name: str = "best",
    signals_prefix: str = "signals",
    world_prefix: str = "world",
    max_samples: int = DEFAULT_MAX_SAMPLES,
    animate: bool = True,
    scene: bool = True,
    path_color: tuple[int, int, int] = C_PATH,
    mesh_roots: MeshRoots = (),
) -> MotionRecording:
    """The items of one motion: joint signals under ``signals_prefix``, and under
    ``world_prefix`` the path, plus (``animate``) the robot's frames and links over time and
    (``scene``) the scene items. ``robot`` None: the catalog robot ``motion.robot`` if there is
    one, else no robot is drawn (a note says why). ``mesh_roots``: the only directories URDF
    mesh files are read from (default none: no file access; see :func:`record_run`)."""
    K = motion.n_samples
    rec = MotionRecording(name=name, n_source=K, max_samples=max_samples)
    parts = unique_parts(motion.joint_names)
    rec.series.extend(_signal_series(motion, signals_prefix, max_samples, parts))
    idx = stride_indices(K, max_samples)
    if robot is None and (animate or scene) and motion.robot:
        from legcore.robots import catalog

        try:
            robot = catalog.get(motion.robot)
        except KeyError:
            rec.notes.append(f"robot {motion.robot!r} is not in the catalog: not drawn")
    radius = link_radius(robot) if robot is not None else 0.01
    if motion.tool is not None:
        tool, _ = _fill_nan_rows(np.asarray(motion.tool, dtype=float))
        rec.polylines.append(
            Polyline(f"{world_prefix}/path", tool[idx], 0.3 * radius, path_color, K)
        )
    if animate and robot is not None:
        _robot_items(robot, motion, idx, world_prefix, rec, mesh_roots)
    if scene:
        _scene_items(motion, idx, world_prefix, radius, rec)
    return rec


# ---------------------------------------------------------------------------------------------
# one run
# ---------------------------------------------------------------------------------------------


def _objective_names(result: RunResult, m: int) -> tuple[str, ...]:
    names = tuple(getattr(result, "objective_names", ()) or ())
    if len(names) != m:
        names = tuple(f"f{i + 1}" for i in range(m))
    return names


def _history_arrays(history: Sequence[Mapping[str, Any]], key: str, m: int) -> FloatArray:
    rows = []
    for h in history:
        v = h.get(key)
        if v is None:
            rows.append([math.nan] * m)
        elif isinstance(v, list | tuple | np.ndarray):
            rows.append(
                [math.nan if x is None else float(x) for x in v][:m] + [math.nan] * (m - len(v))
            )
        else:
            rows.append([float(v)] + [math.nan] * (m - 1))
    return np.asarray(rows, dtype=float).reshape(len(history), m)


def _optimization_series(result: RunResult, max_samples: int) -> tuple[list[Series], int]:
    history = list(getattr(result, "history", []) or [])
    if not history:
        return [], 0
    first = history[0].get("best_f")
    m = len(first) if isinstance(first, list | tuple) else 1
    names = _objective_names(result, m)
    parts = unique_parts(names)
    gen = np.array([float(h.get("generation", i + 1)) for i, h in enumerate(history)])
    G = gen.shape[0]
    out: list[Series] = []

    def add(path: str, y: FloatArray, label: str) -> None:
        idx = minmax_indices(y, max_samples)
        out.append(Series(path, "generation", gen[idx], y[idx], label, "", G))

    def add_objectives(kind: str, Y: FloatArray) -> None:
        """One series per objective; several share their samples and one entity (``group``
        ``optimization/<kind>``, like the joints of a signal)."""
        if m == 1:
            add(f"optimization/{kind}/{parts[0]}", Y[:, 0], f"{kind} {names[0]}")
            return
        idx = shared_minmax_indices(Y, max_samples)
        for j, part in enumerate(parts):
            path, label = f"optimization/{kind}/{part}", f"{kind} {names[j]}"
            group = f"optimization/{kind}"
            out.append(Series(path, "generation", gen[idx], Y[idx, j], label, "", G, group))

    add_objectives("best", _history_arrays(history, "best_f", m))
    if m > 1:
        add_objectives("ideal", _history_arrays(history, "ideal", m))
        add_objectives("nadir", _history_arrays(history, "nadir", m))
    add(
        "optimization/front_size",
        np.array([float(h.get("front_size", 0) or 0) for h in history]),
        "front size",
    )
    cv = np.array([float(h.get("best_cv") or 0.0) for h in history])
    if np.any(cv != 0):
        add("optimization/constraint_violation", cv, "constraint violation of the best")
    return out, m


def _cap_front(F: FloatArray, cap: int) -> FloatArray:
    if F.shape[0] <= cap:
        return F
    order = np.lexsort(F.T[::-1])
    return F[order[stride_indices(F.shape[0], cap)]]


def _front_track(
    path: str,
    fronts: Sequence[tuple[int, FloatArray]],
    names: tuple[str, ...],
    source: str,
    cap: int,
    radius: float,
    color: tuple[int, int, int],
) -> FrontTrack | None:
    gens, pts, sizes = [], [], []
    for g, F in fronts:
        F = np.asarray(F, dtype=float)
        if F.ndim != 2 or F.shape[1] < 2:
            return None
        F = F[np.all(np.isfinite(F[:, :3]), axis=1), :3]
        gens.append(int(g))
        sizes.append(int(F.shape[0]))
        pts.append(_cap_front(F, cap))
    if not gens:
        return None
    return FrontTrack(
        path, np.asarray(gens, dtype=np.int64), pts, names[:3], source, sizes, radius, color
    )


def _front_scale(fronts: Sequence[tuple[int, FloatArray]]) -> float:
    allF = [np.asarray(F, dtype=float)[:, :3] for _, F in fronts if np.asarray(F).size]
    if not allF:
        return 1.0
    A = np.concatenate(allF)
    A = A[np.all(np.isfinite(A), axis=1)]
    if A.size == 0:
        return 1.0
    span = float(np.max(np.ptp(A, axis=0)))
    return span if span > 0 else max(1.0, float(np.max(np.abs(A))))


#: Estimated bytes of a ``.rrd`` file (:func:`estimate_bytes`), measured on rerun-sdk 0.41 files
#: (LZ4-compressed Arrow chunks) of the seed studies and the recording tests' robots:
#: an entity's chunks (~2.4 kB of schema and header for its temporal chunk, ~1.8 kB for its
#: static one); per time row its row id and index; per scalar value (float64); per 3-D point
#: (float32); per sample of a drawn link frame's 3 arrows (vectors, the repeated origin mostly
#: compressed away) and of a capsule / box posed in the world (translation + quaternion); a
#: ``Transform3D`` row of its own entity (a URDF robot with meshes).
_B_ENTITY, _B_ROW, _B_VALUE, _B_POINT = 4200, 14, 8, 12
_B_AXES, _B_POSE, _B_POSE_ROW = 44, 26, 42
#: The file's fixed part: the default blueprint (53–73 kB for the seed studies: ~2.7 kB per
#: chunk, 19–27 chunks), the file header and the recording's properties.
_B_FIXED = 66_000
#: Default size budget of a recording (estimated), under the issue's 20 MB.
DEFAULT_MAX_BYTES = 16_000_000
#: Display caps are never lowered below this many samples by the size budget.
MIN_SAMPLES = 200


def _series_bytes(series: Sequence[Series]) -> tuple[int, int]:
    """(entities, per-sample bytes) of scalar series: a group is one entity whose rows share
    their row id and index."""
    groups: dict[str, tuple[int, int]] = {}
    entities = var = 0
    for s in series:
        if s.group is None:
            entities += 1
            var += (_B_ROW + _B_VALUE) * s.n_samples
        else:
            rows, n = groups.get(s.group, (s.n_samples, 0))
            groups[s.group] = (rows, n + 1)
    entities += len(groups)
    var += sum(rows * (_B_ROW + _B_VALUE * n) for rows, n in groups.values())
    return entities, var


def _robot_bytes(poses: Sequence[PoseTrack]) -> tuple[int, int]:
    """(entities, per-sample bytes) of a robot's poses as the writer logs them: without meshes
    one entity ``world/robot/links`` (per sample 3 arrows per drawn moving frame — a legged
    robot's legs without their base and foot frames —, a world pose per moving link capsule and
    body box); with meshes one entity per pose."""
    moving = [p for p in poses if p.t is not None]
    if not moving:
        return len(poses), 0
    if any(p.geometry == "mesh" for p in poses) or not any(p.geometry == "axes" for p in poses):
        return len(poses), sum(_B_POSE_ROW * p.n_samples for p in moving)
    ks: dict[str, list[int]] = {}
    for p in poses:
        chain, _, k = p.path.rpartition("/frames/")
        if p.geometry == "axes" and k.isdigit() and not chain.endswith("/robot"):
            ks.setdefault(chain, []).append(int(k))
    n = max(p.n_samples for p in moving)
    fixed_frames = {p.path for p in poses if p.geometry == "axes" and p.t is None}
    per = _B_ROW
    for p in poses:
        chain, _, k = p.path.rpartition("/frames/")
        if p.geometry == "axes" and p.t is not None:  # a fixed frame's arrows compress away
            legged = chain in ks
            per += 0 if legged and int(k) in (min(ks[chain]), max(ks[chain])) else _B_AXES
        elif p.geometry in ("capsule", "box") and (
            p.t is not None or p.path.rsplit("/", 1)[0] not in fixed_frames
        ):  # posed in the world: moves with its frame
            per += _B_POSE
    others = [p for p in poses if p.geometry not in ("axes", "capsule", "box")]
    return 1 + len(others), n * per + sum(
        _B_POSE_ROW * p.n_samples for p in others if p.t is not None
    )


def _motion_bytes(m: MotionRecording) -> tuple[int, int]:
    """(fixed, per-sample) estimated bytes of one motion's items, as the writer logs them (a
    legged robot's foot paths share the motion's path entity)."""
    n_series, var = _series_bytes(m.series)
    n_robot, robot_var = _robot_bytes(m.poses)
    feet = [p for p in m.polylines if p.path.endswith("/foot_path")]
    merged = len(feet) if feet and len(m.polylines) > len(feet) else 0
    others = len(m.points) + len(m.polylines) - merged + len(m.polyline_tracks)
    fixed = _B_ENTITY * (n_series + n_robot + others + len(m.point_sets) + len(m.boxes))
    var += robot_var
    var += sum(_B_ROW * p.t.shape[0] + _B_POINT * p.positions[..., 0].size for p in m.points)
    fixed += sum(_B_POINT * p.points.shape[0] for p in m.polylines)
    var += sum(
        _B_ROW * len(p.strips) + _B_POINT * sum(len(s) for s in p.strips) for p in m.polyline_tracks
    )
    fixed += sum(_B_POINT * p.points.shape[0] for p in m.point_sets)
    fixed += sum(2 * _B_POINT * p.centers.shape[0] for p in m.boxes)
    fixed += sum(len(p.mesh_data) for p in m.poses)
    return fixed, var


def _baselines_bytes(baselines: Sequence[MotionRecording]) -> tuple[int, int]:
    """(fixed, per-sample) estimated bytes of the baselines as the writer logs them: a signal
    every baseline has on the same samples is one entity for all of them (one row id and
    index per sample), their paths one entity ``world/baselines/paths``."""
    parts = [_motion_bytes(m) for m in baselines]
    fixed, var = sum(f for f, _ in parts), sum(v for _, v in parts)
    if len(baselines) < 2:
        return fixed, var
    kinds: dict[str, list[Series]] = {}
    for m in baselines:
        firsts: dict[str, Series] = {}
        for s in m.series:
            firsts.setdefault(s.group or s.path, s)
        for entity, s in firsts.items():
            kinds.setdefault(entity.split("/", 2)[-1], []).append(s)
    for firsts_of_kind in kinds.values():
        first = firsts_of_kind[0]
        if len(firsts_of_kind) > 1 and all(
            s.timeline == first.timeline and np.array_equal(s.index, first.index)
            for s in firsts_of_kind
        ):
            fixed -= _B_ENTITY * (len(firsts_of_kind) - 1)
            var -= _B_ROW * first.n_samples * (len(firsts_of_kind) - 1)
    paths = sum(len(m.polylines) for m in baselines)
    fixed -= _B_ENTITY * max(0, paths - 1)
    return fixed, var


def _front_bytes(f: FrontTrack | None) -> tuple[int, int]:
    """(fixed, per-sample) of a front track (``dims`` float32 per point)."""
    if f is None:
        return 0, 0
    return _B_ENTITY + _B_ROW * len(f.points), _B_POINT // 3 * f.dims * sum(
        p.shape[0] for p in f.points
    )


def estimate_bytes(rec: RunRecording) -> int:
    """Estimated size (bytes) of the ``.rrd`` file of ``rec`` (within ~25 % for rerun 0.41 on
    the seed studies; less when the data compress well, e.g. identical baselines)."""
    n_opt, b = _series_bytes(rec.optimization)
    b += _B_FIXED + _B_ENTITY * n_opt
    if rec.best is not None:
        b += sum(_motion_bytes(rec.best))
    b += sum(_baselines_bytes(list(rec.baselines.values())))
    for f in (rec.front, rec.best_point):
        b += sum(_front_bytes(f))
    if rec.front is not None and rec.front.points and 2 <= rec.front.dims <= 3:
        # the final front, the axes and their labels: three static entities
        b += 3 * _B_ENTITY + _B_POINT // 3 * rec.front.dims * rec.front.points[-1].shape[0]
    return int(b)


def record_run(
    result: RunResult,
    *,
    robot: Robot | LeggedRobot | None = None,
    fronts: Mapping[int, Any] | Sequence[tuple[int, Any]] | None = None,
    max_samples: int = DEFAULT_MAX_SAMPLES,
    max_front_points: int | None = None,
    max_bytes: int | None = DEFAULT_MAX_BYTES,
    mesh_roots: MeshRoots = (),
    baseline_signals: Sequence[str] | None = BASELINE_SIGNALS,
) -> RunRecording:
    """Everything to log for a finished job.

    ``robot``: the robot to draw (default: the job's robot, resolved from ``result.spec`` as
    the runner does, or the catalog robot named by the motion). ``fronts``: optional Pareto
    front per generation ``{generation: F (k, m)}`` (see the module docstring); default the
    final ``result.pareto`` at the last generation. ``max_samples`` caps every displayed signal
    and pose track, ``max_front_points`` (default ``max_samples``) each generation's front.

    Size budget: when the :func:`estimate_bytes` of the result exceeds ``max_bytes`` (None: no
    budget), the caps are lowered in proportion to the excess — the baselines' first, then the
    best motion's (never below ``MIN_SAMPLES``), then the front's (never below
    ``MIN_SAMPLES // 4`` points) — until it fits; ``properties`` and ``notes`` say so.

    ``mesh_roots``: the only directories a URDF ``<mesh filename=…>`` may be read from
    (``package://<pkg>/<rel>`` or a relative name, confined by :mod:`legcore.resource_paths`).
    The default, none, opens no file at all — what every robot submitted over the API gets
    (DESIGN §5); a mesh not read becomes a note and its link is drawn as a capsule.

    ``baseline_signals``: the signals kept for each baseline (``"q"``, ``"energy/total"``, any
    kind of :data:`SIGNALS`, ``"energy"``); default :data:`BASELINE_SIGNALS`, what the
    blueprint shows; None: all of them, like the best motion.
    """
    notes: list[str] = []
    if robot is None:
        robot = _resolve_robot(result, notes)
    optimization, m = _optimization_series(result, max_samples)
    initial = {
        "best": max_samples,
        "baselines": max_samples,
        "front": max_front_points or max_samples,
    }
    caps = dict(initial)
    best = _record_best(result, robot, caps["best"], mesh_roots)
    baselines = _record_baselines(result, robot, caps["baselines"], baseline_signals)
    front, best_point = _record_fronts(result, fronts, m, caps["front"], max_samples, notes)

    def assemble() -> RunRecording:
        return _assemble(
            result, robot, best, baselines, optimization, front, best_point, notes, max_samples
        )

    rec = assemble()
    floors = {"best": MIN_SAMPLES, "baselines": MIN_SAMPLES, "front": MIN_SAMPLES // 4}
    for key in ("baselines", "best", "front"):
        est = estimate_bytes(rec)
        if max_bytes is None or est <= max_bytes:
            break
        if key == "baselines":
            var = _baselines_bytes(list(baselines.values()))[1]
            used = max((s.n_samples for b in baselines.values() for s in b.series), default=0)
        elif key == "best":
            var = _motion_bytes(best)[1] if best is not None else 0
            used = max((s.n_samples for s in best.series), default=0) if best is not None else 0
        else:
            var = _front_bytes(front)[1]
            used = max((p.shape[0] for p in front.points), default=0) if front is not None else 0
        if var <= 0 or used <= floors[key]:
            continue
        ratio = max(0.0, (var - (est - max_bytes)) / var)
        new_cap = max(floors[key], int(used * ratio * 0.95))
        if new_cap >= used:
            continue
        caps[key] = new_cap
        if key == "baselines":
            baselines = _record_baselines(result, robot, new_cap, baseline_signals)
        elif key == "best":
            best = _record_best(result, robot, new_cap, mesh_roots)
        else:
            front, best_point = _record_fronts(result, fronts, m, new_cap, max_samples, [])
        rec = assemble()
    est = estimate_bytes(rec)
    if caps != initial:
        rec.notes.append(
            f"display caps lowered to {caps} samples to keep the recording under "
            f"{(max_bytes or 0) / 1e6:.0f} MB (estimated {est / 1e6:.1f} MB)"
        )
    if max_bytes is not None and est > max_bytes:
        rec.notes.append(
            f"estimated size {est / 1e6:.1f} MB is over the {max_bytes / 1e6:.0f} MB budget"
        )
    rec.properties.update(
        {
            "max_samples_best": caps["best"],
            "max_samples_baselines": caps["baselines"],
            "max_front_points": caps["front"],
            "estimated_bytes": est,
        }
    )
    return rec


def _record_best(
    result: RunResult, robot: Robot | LeggedRobot | None, cap: int, mesh_roots: MeshRoots = ()
) -> MotionRecording | None:
    best_sol: Solution | None = getattr(result, "best", None)
    if best_sol is None or best_sol.motion is None:
        return None
    return record_motion(best_sol.motion, robot, max_samples=cap, mesh_roots=mesh_roots)


def _record_baselines(
    result: RunResult,
    robot: Robot | LeggedRobot | None,
    cap: int,
    signals: Sequence[str] | None = BASELINE_SIGNALS,
) -> dict[str, MotionRecording]:
    out: dict[str, MotionRecording] = {}
    names = list((getattr(result, "baselines", None) or {}).keys())
    for name, part in zip(names, unique_parts(names), strict=True):
        sol = result.baselines[name]
        if sol is None or sol.motion is None:
            continue
        out[name] = record_motion(
            sol.motion,
            robot,
            name=name,
            signals_prefix=f"baselines/{part}/signals",
            world_prefix=f"world/baselines/{part}",
            max_samples=cap,
            animate=False,
            scene=False,
            path_color=C_BASELINE,
        )
        if signals is not None:
            prefix = f"baselines/{part}/signals/"
            out[name].series[:] = [
                s
                for s in out[name].series
                if any(
                    (rel := s.path[len(prefix) :]) == k or rel.startswith(k + "/") for k in signals
                )
            ]
    return out


def _record_fronts(
    result: RunResult,
    fronts: Mapping[int, Any] | Sequence[tuple[int, Any]] | None,
    m: int,
    cap: int,
    max_samples: int,
    notes: list[str],
) -> tuple[FrontTrack | None, FrontTrack | None]:
    pareto = list(getattr(result, "pareto", []) or [])
    if m == 0 and pareto:
        m = len(pareto[0].get("objectives", []))
    if m < 2:
        return None, None
    obj_names = _objective_names(result, m)
    history = list(getattr(result, "history", []) or [])
    last_gen = int(history[-1].get("generation", len(history))) if history else 0
    if fronts is not None:
        pairs = fronts.items() if isinstance(fronts, Mapping) else fronts
        items = sorted((int(g), np.asarray(F, dtype=float)) for g, F in pairs)
        source = "per_generation"
    else:
        F_final = np.array([p["objectives"] for p in pareto], dtype=float).reshape(-1, m)
        items = [(last_gen, F_final)] if F_final.size else []
        source = "final_only"
        notes.append(
            "per-generation fronts were not given: the final front is logged at the last generation"
        )
    scale = _front_scale(items)
    front = _front_track(
        "optimization/front", items, obj_names, source, cap, 0.006 * scale, C_FRONT
    )
    best_point = None
    if history:
        bf = _history_arrays(history, "best_f", m)
        gens = [int(h.get("generation", i + 1)) for i, h in enumerate(history)]
        sel = stride_indices(len(gens), max_samples)
        best_point = _front_track(
            "optimization/best_point",
            [(gens[i], bf[i : i + 1]) for i in sel],
            obj_names,
            "history",
            1,
            0.012 * scale,
            C_BEST,
        )
    return front, best_point


def _assemble(
    result: RunResult,
    robot: Robot | LeggedRobot | None,
    best: MotionRecording | None,
    baselines: dict[str, MotionRecording],
    optimization: list[Series],
    front: FrontTrack | None,
    best_point: FrontTrack | None,
    run_notes: list[str],
    max_samples: int,
) -> RunRecording:
    notes = list(run_notes)
    spec = getattr(result, "spec", None)
    kind = getattr(getattr(spec, "problem", None), "kind", "") if spec is not None else ""
    title = (
        (getattr(spec, "name", None) or kind or "legopt run") if spec is not None else "legopt run"
    )
    motion = getattr(getattr(result, "best", None), "motion", None)
    props: dict[str, Any] = {
        "study": kind,
        "robot": getattr(robot, "name", "")
        if robot is not None
        else (motion.robot if motion else ""),
        "seed": int(getattr(spec, "seed", 0) or 0) if spec is not None else 0,
        "optimizer": str((getattr(result, "optimizer", None) or {}).get("kind", "")),
        "objectives": ", ".join(getattr(result, "objective_names", ()) or ()),
        "status": str(getattr(result, "status", "")),
        "front_source": front.source if front is not None else "none",
        "max_samples": int(max_samples),
    }
    for mrec in ([best] if best else []) + list(baselines.values()):
        notes.extend(f"{mrec.name}: {n}" for n in mrec.notes)
    return RunRecording(title, best, dict(baselines), optimization, front, best_point, props, notes)


def _resolve_robot(result: RunResult, notes: list[str]) -> Robot | LeggedRobot | None:
    spec = getattr(result, "spec", None)
    if spec is not None:
        try:
            from legcore.problems.registry import get_study
            from legcore.runner import resolve_robot

            return resolve_robot(spec, get_study(spec.problem.kind))
        except Exception as exc:  # noqa: BLE001 - drawing falls back to the motion's robot name
            notes.append(f"robot of the spec not resolved ({type(exc).__name__}: {exc})")
    motion = getattr(getattr(result, "best", None), "motion", None)
    if motion is not None and motion.robot:
        from legcore.robots import catalog

        try:
            return catalog.get(motion.robot)
        except KeyError:
            notes.append(f"robot {motion.robot!r} is not in the catalog: not drawn")
    return None
