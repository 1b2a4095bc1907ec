"""Rerun recordings of jobs: write, merge, replay ``.rrd`` files (the only module importing rerun).

    write_recording(result, path, recording_id=job_id)   # one job  -> path (.rrd)
    merge_recordings([a, b], out, names=["a", "b"])       # a sweep  -> out, under /jobs/<name>/
    open_viewer(path)                                     # native viewer, or the web viewer
    serve_web(path, port)                                 # web viewer on 127.0.0.1:port

What is logged where is decided by the pure :mod:`legcore.recording` (``docs/recording.md``);
this module turns its items into archetypes:

- scalar series → ``Scalars`` sent column-wise with ``send_columns`` (on the ``time`` timeline
  in s or the ``generation`` sequence timeline), named by a static ``SeriesLines``; the joints
  of one signal (``Series.group``, e.g. ``signals/q``) are one entity and one call — a batch of
  one value per joint at each sample, one named line per joint — so they share their row ids
  and time stamps (a tiny recording is 2–2.5× smaller than with one entity per joint);
- poses → ``Transform3D`` columns (translation + unit quaternion xyzw, one ``send_columns``
  call per frame) with static ``TransformAxes3D`` (link frames), ``Capsules3D`` (links) or
  ``Boxes3D`` (the body of a legged robot) in the entity's own frame;
- the tool/foot point → ``Points3D`` columns; the path, support polygon → ``LineStrips3D``;
  targets → ``Points3D``; obstacles → ``Boxes3D``;
- the Pareto front per generation → ``Points3D`` (``Points2D`` for two objectives) columns
  partitioned by generation, drawn in the front's own box (a static ``Transform3D`` maps its
  span to the unit square; values stay true) with named, ticked axes (``optimization/axes``)
  and the final front also static (``optimization/final_front``), so the Pareto view shows it
  on the ``time`` timeline too (:mod:`services.worker.front_display`); a merged recording
  gives each job its colour and name, one box for all fronts and a legend (``jobs/legend``).

Each job gets its own ``RecordingStream`` (never the global one: several jobs may run in one
process) saving to a temporary file next to ``path``; the file is moved into place with
``os.replace`` only after the stream is flushed and closed, so ``path`` is either absent or a
complete recording. The stream and its blueprint stream are then freed for good
(:func:`release_streams`): rerun-sdk would otherwise keep their threads and buffers for the life
of the process (4 threads, 2-3 MB per recording in a worker or in the API's sweep merges).
A blueprint (3D view of robot, path and scene; time-series tabs for q, qd,
qdd, jerk, τ, power, energy, the best objective per generation; the front) is saved with it.

Replay: a stored ``.rrd`` opens in the native viewer (``rerun FILE``) or, where there is no
display, in the web viewer: the bundled ``rerun --serve-web`` runs in a child process bound to
``127.0.0.1`` and this process pushes the file (with its blueprint) to it.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
import uuid
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any
from urllib.parse import quote

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
import rerun_bindings
from rerun.chunk import RrdReader

from legcore import recording as lrec
from legcore.recording import (
    DEFAULT_MAX_SAMPLES,
    FrontTrack,
    MotionRecording,
    PoseTrack,
    RunRecording,
    Series,
    record_run,
)
from services.worker.front_display import FrontDisplay, front_display

if TYPE_CHECKING:
    from legcore.robots.legged import LeggedRobot
    from legcore.robots.model import Robot
    from legcore.runner import RunResult

__all__ = [
    "APP_ID",
    "ViewerHandle",
    "blueprint_for",
    "has_display",
    "log_run",
    "merge_recordings",
    "open_viewer",
    "read_entities",
    "rerun_binary",
    "serve_web",
    "viewer_url",
    "write_recording",
]

#: Rerun application id of every LegOpt recording (blueprints are matched to it).
APP_ID = "legopt"

_SIGNAL_VIEWS = (
    ("q", "q (rad)"),
    ("qd", "qd (rad/s)"),
    ("qdd", "qdd (rad/s²)"),
    ("jerk", "jerk (rad/s³)"),
    ("tau", "τ (N·m)"),
    ("power", "power (W)"),
)


# ---------------------------------------------------------------------------------------------
# writing
# ---------------------------------------------------------------------------------------------


def write_recording(
    result: RunResult,
    path: Path,
    *,
    recording_id: str | None = None,
    max_samples: int = DEFAULT_MAX_SAMPLES,
    fronts: Mapping[int, Any] | Sequence[tuple[int, Any]] | None = None,
    robot: Robot | LeggedRobot | None = None,
    mesh_roots: lrec.MeshRoots = (),
) -> list[str]:
    """Write the Rerun recording of a finished job to ``path`` (``.rrd``); return its notes
    (what it could not show as asked, e.g. a URDF mesh not read) for the job's warnings.

    ``recording_id``: the recording's id (the job id; a fresh UUID by default).
    ``max_samples``: display cap per signal / pose track (see :mod:`legcore.recording`).
    ``fronts``: optional Pareto front per generation ``{generation: F (k, m)}``; without it the
    final front is logged at the last generation. ``robot``: override the robot drawn.
    ``mesh_roots``: the only directories URDF mesh files may be read from (see
    :func:`legcore.recording.record_run`); the default, none, opens no file — what the worker
    passes for every job, so an uploaded robot's mesh names are never opened.

    Written to a temporary file next to ``path`` and moved into place only once the stream is
    closed; on any error the temporary file is removed and ``path`` is left untouched.
    """
    rec = record_run(
        result, robot=robot, fronts=fronts, max_samples=max_samples, mesh_roots=mesh_roots
    )
    _write_atomic(Path(path), recording_id, lambda stream: log_run(stream, rec), blueprint_for(rec))
    return list(rec.notes)


def _write_atomic(
    path: Path,
    recording_id: str | None,
    log: Any,
    blueprint: rrb.Blueprint | None,
) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:12]}.tmp")
    try:
        _save_stream(tmp, recording_id or str(uuid.uuid4()), log, blueprint)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    finally:
        release_streams()


def _save_stream(tmp: Path, recording_id: str, log: Any, blueprint: rrb.Blueprint | None) -> None:
    """Log into a new stream saving to ``tmp``; the file is complete when this returns. The
    stream is referenced only by this frame, so it is dropped on return (see
    :func:`release_streams`)."""
    stream = rr.RecordingStream(APP_ID, recording_id=recording_id)
    try:
        _with_default_blueprint(
            blueprint,
            lambda bp: rerun_bindings.save(str(tmp), bp, stream.to_native(), write_footer=True),
        )  # = stream.save(tmp, default_blueprint=blueprint), without its leak
        log(stream)
        stream.flush()
        stream.disconnect()  # closes the file sink: the file is complete only now
    except BaseException:
        with contextlib.suppress(Exception):
            stream.disconnect()
        raise


def _with_default_blueprint(blueprint: rrb.Blueprint | None, attach: Callable[[Any], None]) -> None:
    """Call ``attach(storage)``, ``storage`` being ``blueprint`` in the in-memory form rerun's
    sinks take as their default blueprint (None without one), then free the blueprint's stream.

    This is what ``RecordingStream.save`` / ``connect_grpc`` do through rerun's
    ``create_in_memory_blueprint``, plus the ``disconnect`` they omit: that blueprint stream's
    memory sink holds the storage, which holds the stream (a reference cycle on the Rust side),
    so rerun's orphan sweep never frees it: 2 threads and the blueprint leaked per call.
    """
    if blueprint is None:
        attach(None)
        return
    bp = rr.RecordingStream._from_native(
        rerun_bindings.new_blueprint(
            application_id=APP_ID, make_default=False, make_thread_default=False
        )
    )
    try:
        bp.set_log_time_enabled(False)  # a blueprint needs no wall clock (~0.3 kB a chunk)
        bp.set_time("blueprint", sequence=0)
        blueprint.to_blueprint()._log_to_stream(bp)
        attach(bp.memory_recording().storage)
    finally:
        bp.disconnect()  # swaps the memory sink for a buffer: breaks the cycle


def release_streams() -> None:
    """Free the native side (batcher and sink threads, buffers) of every ``RecordingStream``
    of this process that Python no longer references.

    rerun-sdk (0.41) keeps every stream created from Python in a native registry; dropping the
    Python object only disconnects it (``RecordingStream.__del__``): its batcher thread, its
    stream thread and its buffers live on until ``flush_and_cleanup_orphaned_recordings``
    (rerun issue #2116; only ``rr.init`` calls it). With the blueprint streams (see
    :func:`_with_default_blueprint`) that was 4 threads and 2-3 MB per recording. Streams still
    in use (by another thread) are flushed and kept; a stream kept alive by an exception's
    traceback goes at the next call. Side effect: clears the global data recording, which
    LegOpt never sets. Thread-safe (rerun locks its registry).
    """
    rerun_bindings.flush_and_cleanup_orphaned_recordings()


def log_run(stream: rr.RecordingStream, rec: RunRecording) -> None:
    """Log every item of ``rec`` to ``stream`` (column-wise where the data varies)."""
    stream.send_recording_name(rec.title)
    stream.send_property(
        "legopt",
        rr.AnyValues(
            **{k: v for k, v in rec.properties.items() if isinstance(v, str | int | float)}  # type: ignore[arg-type]
        ),
    )
    if rec.best is not None:
        _log_motion(stream, rec.best)
    for m in rec.baselines.values():
        _log_motion(stream, m, m.name, signals=False, polylines=False)
    paths = [(m.name, pl) for m in rec.baselines.values() for pl in m.polylines]
    if paths:  # every baseline's path in one entity, labelled with its name
        stream.log(
            "world/baselines/paths",
            rr.LineStrips3D(
                [np.asarray(pl.points, dtype=np.float32) for _, pl in paths],
                radii=[pl.radius for _, pl in paths],
                colors=[pl.color for _, pl in paths],
                labels=[name for name, _ in paths],
            ),
            static=True,
        )
    for entity, groups in _baseline_signals(rec):
        _log_series_group(stream, [s for _, g in groups for s in g], "", entity, groups)
    for group in _series_groups(rec.optimization):  # the objectives of best / ideal / nadir
        _log_series_group(stream, group)
    display = _display_of(rec)
    for f, ui_radius in ((rec.front, FRONT_UI_RADIUS), (rec.best_point, BEST_UI_RADIUS)):
        if f is not None:
            _log_front(stream, f, display, ui_radius)
    if rec.front is not None and rec.front.points and display is not None:
        _log_front_frame(stream, rec.front, display)


def _time_column(timeline: str, index: np.ndarray) -> rr.TimeColumn:
    if timeline == "generation":
        return rr.TimeColumn("generation", sequence=np.asarray(index, dtype=np.int64))
    return rr.TimeColumn(timeline, duration=np.asarray(index, dtype=np.float64))


def _series_name(s: Series, tag: str = "") -> str:
    """The line's name: ``label (unit)``, prefixed ``<tag>: `` (a baseline's name)."""
    name = f"{s.label} ({s.unit})" if s.unit else s.label
    return f"{tag}: {name}" if tag else name


def _log_series(stream: rr.RecordingStream, s: Series, tag: str = "") -> None:
    stream.send_columns(
        s.path,
        indexes=[_time_column(s.timeline, s.index)],
        columns=rr.Scalars.columns(scalars=np.asarray(s.values, dtype=np.float64)),
    )
    name = _series_name(s, tag)
    if name.replace(" ", "_") != s.path.rsplit("/", 1)[-1]:  # else the viewer's own name
        stream.log(s.path, rr.SeriesLines(names=name), static=True)


def _pose_geometry(p: PoseTrack, n: int) -> list[Any]:
    """The columns (``n`` rows, the same value in each) of what a pose draws in its own frame:
    sent with its transforms, one chunk per entity instead of a temporal and a static one (each
    chunk costs ~1.5 kB of schema in a file; the repeated values a few bytes a row)."""
    if p.geometry == "axes":
        return list(rr.TransformAxes3D.columns(axis_length=np.full(n, p.axis_length, np.float32)))
    if p.geometry == "capsule":
        return list(
            rr.Capsules3D.columns(
                lengths=np.full(n, p.length, np.float32),
                radii=np.full(n, p.radius, np.float32),
                colors=np.tile(np.asarray(p.color, np.uint8), (n, 1)),
            )
        )
    if p.geometry == "box":
        return list(
            rr.Boxes3D.columns(
                half_sizes=np.tile(np.asarray(p.half_size, np.float32), (n, 1)),
                colors=np.tile(np.asarray((*p.color, 200), np.uint8), (n, 1)),
                fill_mode=["solid"] * n,
            )
        )
    return []


def _log_pose(stream: rr.RecordingStream, p: PoseTrack) -> None:
    """A pose and what it draws: one chunk (static, or temporal with the geometry repeated)."""
    quat = lrec.quaternion_xyzw(p.rotation).astype(np.float32)  # vectorised; mat3x3 is not
    n = 1 if p.t is None else int(np.asarray(p.t).shape[0])
    columns = [
        *rr.Transform3D.columns(
            translation=np.asarray(p.translation[:n], dtype=np.float32), quaternion=quat[:n]
        ),
        *_pose_geometry(p, n),
    ]
    if p.t is None:  # a static chunk: one row
        stream.send_columns(p.path, indexes=[], columns=columns)
    else:
        stream.send_columns(p.path, indexes=[_time_column("time", p.t)], columns=columns)
    if p.geometry == "mesh" and p.mesh_data:  # a URDF mesh, scaled in a child entity
        # the bytes read inside the mesh roots (legcore.resource_paths); never a path opened here
        stream.log(f"{p.path}/mesh", rr.Transform3D(scale=p.half_size), static=True)
        media = rr.components.MediaType.guess_from_path(p.mesh)
        asset = rr.Asset3D(contents=p.mesh_data, media_type=media)
        stream.log(f"{p.path}/mesh", asset, static=True)


def _series_groups(series: Sequence[Series]) -> list[list[Series]]:
    """Consecutive series of one ``group`` sharing their index (the joints of one signal), and
    every other series alone."""
    out: list[list[Series]] = []
    for s in series:
        last = out[-1][0] if out else None
        if (
            last is not None
            and s.group is not None
            and s.group == last.group
            and s.timeline == last.timeline
            and np.array_equal(s.index, last.index)
        ):
            out[-1].append(s)
        else:
            out.append([s])
    return out


def _baseline_signals(rec: RunRecording) -> list[tuple[str, list[tuple[str, list[Series]]]]]:
    """The baselines' signals by entity: ``(entity, [(baseline name, its series), ...])``. A
    signal every baseline has on the same samples is one entity for all of them,
    ``baselines/signals/<kind>`` (one line per baseline and joint, named ``<baseline>: ...``):
    a chunk is ~1.5 kB of schema whatever it holds. Otherwise each baseline keeps its own,
    ``baselines/<name>/signals/<kind>``."""
    by_kind: dict[str, list[tuple[str, list[Series]]]] = {}
    for m in rec.baselines.values():
        for g in _series_groups(m.series):
            entity = g[0].group or g[0].path  # baselines/<part>/signals/...
            by_kind.setdefault(entity.split("/", 2)[-1], []).append((m.name, g))
    out: list[tuple[str, list[tuple[str, list[Series]]]]] = []
    for kind, groups in by_kind.items():
        first = groups[0][1][0]
        if len(groups) > 1 and all(
            g[0].timeline == first.timeline and np.array_equal(g[0].index, first.index)
            for _, g in groups
        ):
            out.append((f"baselines/{kind}", groups))
        else:
            out.extend((g[0].group or g[0].path, [(name, g)]) for name, g in groups)
    return out


def _log_series_group(
    stream: rr.RecordingStream,
    group: Sequence[Series],
    tag: str = "",
    entity: str | None = None,
    tagged: Sequence[tuple[str, Sequence[Series]]] = (),
) -> None:
    """The joints of one signal as one entity (``Series.group``, or ``entity``): a ``Scalars``
    batch of one value per joint at each sample, and one named line per joint (``<tag>: ``
    first; ``tagged``: (tag, series) pairs naming the lines of several motions)."""
    first = group[0]
    entity = entity or first.group
    if (len(group) == 1 and not tagged) or entity is None:
        for s in group:
            _log_series(stream, s, tag)
        return
    values = np.stack([np.asarray(s.values, dtype=np.float64) for s in group], axis=1)
    n_rows, n = values.shape
    stream.send_columns(
        entity,
        indexes=[_time_column(first.timeline, first.index)],
        columns=rr.Scalars.columns(scalars=values.ravel()).partition([n] * n_rows),
    )
    pairs = [(t, s) for t, g in tagged for s in g] if tagged else [(tag, s) for s in group]
    names = [_series_name(s, t) for t, s in pairs]
    stream.log(entity, rr.SeriesLines(names=names), static=True)


def _log_motion(
    stream: rr.RecordingStream,
    m: MotionRecording,
    tag: str = "",
    *,
    signals: bool = True,
    polylines: bool = True,
) -> None:
    """One motion's items; ``tag`` (a baseline's name) prefixes its series' names; without
    ``signals`` its series are left to the caller (:func:`_baseline_signals`)."""
    for group in _series_groups(m.series) if signals else []:
        _log_series_group(stream, group, tag)
    skeleton = _skeleton(m.poses)
    if skeleton is not None:
        _log_skeleton(stream, *skeleton)
    drawn = set() if skeleton is None else {p.path for p in (*skeleton[1], *skeleton[2])}
    for p in m.poses:
        if p.path not in drawn:
            _log_pose(stream, p)
    for pt in m.points:
        N, P = pt.positions.shape[:2]
        stream.send_columns(
            pt.path,
            indexes=[_time_column("time", pt.t)],
            columns=rr.Points3D.columns(
                positions=np.asarray(pt.positions, dtype=np.float32).reshape(-1, 3)
            ).partition([P] * N),
        )
        stream.log(
            pt.path, rr.Points3D.from_fields(radii=[pt.radius], colors=[pt.color]), static=True
        )
    feet = [pl for pl in m.polylines if pl.path.endswith("/foot_path")]
    path = next((pl for pl in m.polylines if pl.path.endswith("path") and pl not in feet), None)
    strips: list[Any] = []
    if polylines and feet and path is not None:  # the motion's path and its feet's: one entity
        strips = [path, *feet]
        stream.log(
            path.path,
            rr.LineStrips3D(
                [np.asarray(pl.points, dtype=np.float32) for pl in strips],
                radii=[pl.radius for pl in strips],
                colors=[pl.color for pl in strips],
                labels=["path", *(pl.path.split("/")[-2] for pl in feet)],
            ),
            static=True,
        )
    else:
        strips = []
    for pl in m.polylines if polylines else []:
        if any(pl is x for x in strips):
            continue
        stream.log(
            pl.path, rr.LineStrips3D([pl.points], radii=[pl.radius], colors=[pl.color]), static=True
        )
    for tr in m.polyline_tracks:
        N = len(tr.strips)
        stream.send_columns(
            tr.path,
            indexes=[_time_column("time", tr.t)],
            columns=rr.LineStrips3D.columns(
                strips=[np.asarray(s, dtype=np.float32) for s in tr.strips]
            ).partition([1] * N),
        )
        stream.log(
            tr.path, rr.LineStrips3D.from_fields(radii=[tr.radius], colors=[tr.color]), static=True
        )
    for ps in m.point_sets:
        stream.log(
            ps.path, rr.Points3D(ps.points, radii=[ps.radius], colors=[ps.color]), static=True
        )
    for b in m.boxes:
        stream.log(
            b.path,
            rr.Boxes3D(
                centers=b.centers,
                half_sizes=b.half_sizes,
                colors=[(*b.color, 110)],
                fill_mode="solid",
            ),
            static=True,
        )


def _skeleton(poses: Sequence[PoseTrack]) -> tuple[str, list[PoseTrack], list[PoseTrack]] | None:
    """(``<world>/robot/links``, link frames, links) of a robot drawn without meshes, to be
    logged as that one entity (None: a URDF robot with meshes, which hang under its frame
    entities, or poses on different samples). One entity instead of one per frame and per
    link: each entity costs a file ~1.5 kB per chunk, 40–60 % of a small recording for a
    hexapod's 26."""
    frames = [p for p in poses if p.geometry == "axes"]
    if not frames or any(p.geometry == "mesh" for p in poses):
        return None
    root = frames[0].path.split("/robot")[0]
    body = f"{root}/robot/body"
    links = [p for p in poses if p.geometry == "capsule" or p.path == body]
    times = [p.t for p in (*frames, *links) if p.t is not None]
    if any(not np.array_equal(t, times[0]) for t in times[1:]):
        return None
    return f"{root}/robot/links", frames, links


def _axes_frames(frames: Sequence[PoseTrack]) -> list[PoseTrack]:
    """The frames whose axes are drawn: every frame of a serial robot (base and tool frame
    too); of a legged robot's legs (``.../robot/<leg>/frames/<k>``) the joint frames between
    the base frame (fixed to the body, whose box shows its orientation) and the foot frame (the
    foot is a point): half a hexapod leg's arrows, ~17 kB of a tiny recording."""
    chains: dict[str, list[int]] = {}
    for f in frames:
        chain, _, k = f.path.rpartition("/frames/")
        chains.setdefault(chain, []).append(int(k) if k.isdigit() else -1)

    def drawn(f: PoseTrack) -> bool:
        chain, _, k = f.path.rpartition("/frames/")
        if chain.endswith("/robot") or not k.isdigit():  # a serial robot
            return True
        return min(chains[chain]) < int(k) < max(chains[chain])

    return [f for f in frames if drawn(f)] or list(frames)


def _world_poses(p: PoseTrack, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(R (n, 3, 3), t (n, 3)) of a pose, a static one repeated."""
    R = np.broadcast_to(np.asarray(p.rotation, dtype=float), (n, 3, 3))
    t = np.broadcast_to(np.asarray(p.translation, dtype=float), (n, 3))
    return R, t


def _send(
    stream: rr.RecordingStream, entity: str, t: np.ndarray | None, columns: list[Any]
) -> None:
    """One chunk: temporal on ``time`` at ``t``, or static (one row) when ``t`` is None."""
    indexes = [] if t is None else [_time_column("time", t)]
    stream.send_columns(entity, indexes=indexes, columns=columns)


def _log_skeleton(
    stream: rr.RecordingStream, entity: str, frames: list[PoseTrack], links: list[PoseTrack]
) -> None:
    """A robot over time as two entities, each one temporal chunk (a batch per sample) and one
    static chunk (sizes, colours):

    - ``<robot>/links``: ``Capsules3D``, link k from frame origin k−1 to k, posed in the world;
    - ``<robot>/axes``: ``Arrows3D``, the x / y / z axes (red / green / blue, ``axis_length``)
      of every link frame from its origin — frame ``i`` is arrows ``3i … 3i+2``, in the order
      of the frames (``world/robot[/<leg>]/frames/<k>``); their meeting points are the joints.
    """
    t = next((p.t for p in (*frames, *links) if p.t is not None), None)
    n = 1 if t is None else int(np.asarray(t).shape[0])
    axes = _axes_frames(frames)
    R = np.stack([_world_poses(f, n)[0] for f in axes], axis=1)  # (n, F, 3, 3)
    origins = np.stack([_world_poses(f, n)[1] for f in axes], axis=1)  # (n, F, 3)
    lengths = np.array([f.axis_length for f in axes])
    vectors = np.swapaxes(R, 2, 3) * lengths[None, :, None, None]  # [..., i, :]: axis i
    F = len(axes)
    columns: list[Any] = [
        *rr.Arrows3D.columns(
            vectors=vectors.reshape(-1, 3).astype(np.float32),
            origins=np.repeat(origins, 3, axis=1).reshape(-1, 3).astype(np.float32),
        ).partition([3 * F] * n)
    ]
    static: list[Any] = [
        rr.Arrows3D.from_fields(colors=np.tile(np.asarray(C_XYZ, np.uint8), (F, 1)))
    ]
    boxes = [p for p in links if p.geometry == "box"]  # a legged robot's body
    links = [p for p in links if p.geometry == "capsule"]
    if boxes:
        Rb = [_world_poses(b, n) for b in boxes]
        columns += rr.Boxes3D.columns(
            centers=np.stack([tb for _, tb in Rb], axis=1).reshape(-1, 3).astype(np.float32),
            quaternions=np.stack([lrec.quaternion_xyzw(R) for R, _ in Rb], axis=1)
            .reshape(-1, 4)
            .astype(np.float32),
        ).partition([len(boxes)] * n)
        static.append(
            rr.Boxes3D.from_fields(
                half_sizes=[b.half_size for b in boxes],
                colors=[(*b.color, 200) for b in boxes],
                fill_mode="solid",
            )
        )
    if links:
        by_path = {f.path: f for f in frames}
        cap_t, cap_q = [], []
        for link in links:
            Rf, tf = _world_poses(by_path[link.path.rsplit("/", 1)[0]], n)
            Rl, tl = _world_poses(link, n)
            cap_t.append(tf + np.einsum("nij,nj->ni", Rf, tl))
            cap_q.append(lrec.quaternion_xyzw(Rf @ Rl))
        columns += rr.Capsules3D.columns(
            translations=np.stack(cap_t, axis=1).reshape(-1, 3).astype(np.float32),
            quaternions=np.stack(cap_q, axis=1).reshape(-1, 4).astype(np.float32),
        ).partition([len(links)] * n)
        static.append(
            rr.Capsules3D.from_fields(
                lengths=[p.length for p in links],
                radii=[p.radius for p in links],
                colors=[p.color for p in links],
            )
        )
    _send(stream, entity, t, columns)
    stream.log(entity, *static, static=True)


#: Colours of a frame's x, y and z axes (the arrows keep rerun's default radius: one column
#: less, ~0.8 kB).
C_XYZ = ((230, 40, 40), (40, 170, 40), (40, 90, 230))

#: Point radii of the fronts in UI points (negative radii: screen-space, whatever the scale).
FRONT_UI_RADIUS, BEST_UI_RADIUS, FINAL_UI_RADIUS, AXIS_UI_RADIUS = -2.5, -5.0, -3.5, -0.6
C_AXES = (140, 140, 140)
C_FINAL = (170, 200, 235)


def _display_of(rec: RunRecording) -> FrontDisplay | None:
    """The axes box and names of the recording's front (None without a 2-3 objective front)."""
    if rec.front is None:
        return None
    pts = list(rec.front.points) + (list(rec.best_point.points) if rec.best_point else [])
    return front_display(pts, rec.front.objective_names, str(rec.properties.get("study") or ""))


def _box_transform(display: FrontDisplay) -> rr.Transform3D:
    """Draws the display's box as the unit square (cube); the data keep their true values."""
    t, s = display.transform()
    return rr.Transform3D(translation=t.tolist(), scale=s.tolist())


def _log_front_frame(stream: rr.RecordingStream, f: FrontTrack, display: FrontDisplay) -> None:
    """The final front as static points (shown on every timeline, also ``time``, on which the
    recording opens) and the named, ticked axes, both in the front's box."""
    arche: Any = rr.Points3D if f.dims == 3 else rr.Points2D
    final = np.asarray(f.points[-1], dtype=np.float32)[:, : f.dims]
    path = "optimization/final_front"
    points = arche(final, radii=[FINAL_UI_RADIUS], colors=[C_FINAL])
    stream.log(path, points, _box_transform(display), static=True)  # one chunk
    _log_axes(stream, "optimization/axes", display)


def _log_axes(stream: rr.RecordingStream, path: str, display: FrontDisplay) -> None:
    """Axes of a front's box at ``path`` (lines, with the box's transform and the axis names
    as ``legopt_axis_names`` for a merge to read back) and ``path/labels`` (names, ticks)."""
    lines, marks = display.axes()
    strips: Any = rr.LineStrips3D if display.dims == 3 else rr.LineStrips2D
    stream.log(  # one chunk: the lines, the box and the names
        path,
        strips([a.astype(np.float32) for a in lines], colors=[C_AXES], radii=[AXIS_UI_RADIUS]),
        _box_transform(display),
        rr.AnyValues(legopt_axis_names=list(display.labels)),
        static=True,
    )
    stream.log(
        f"{path}/labels",
        strips(
            [m.points.astype(np.float32) for m in marks],
            labels=[m.label for m in marks],
            colors=[C_AXES],
            radii=[AXIS_UI_RADIUS],
        ),
        static=True,
    )


def _log_front(
    stream: rr.RecordingStream,
    f: FrontTrack,
    display: FrontDisplay | None = None,
    ui_radius: float | None = None,
) -> None:
    lengths = [int(p.shape[0]) for p in f.points]
    pts = (
        np.concatenate(f.points).astype(np.float32)
        if f.points
        else np.zeros((0, f.dims), np.float32)
    )
    arche: Any = rr.Points3D if f.dims == 3 else rr.Points2D
    stream.send_columns(
        f.path,
        indexes=[_time_column("generation", f.generations)],
        columns=arche.columns(positions=pts[:, : f.dims]).partition(lengths),
    )
    radius = f.radius if display is None or ui_radius is None else ui_radius
    box = [] if display is None else [_box_transform(display)]
    stream.log(f.path, arche.from_fields(radii=[radius], colors=[f.color]), *box, static=True)


# ---------------------------------------------------------------------------------------------
# blueprint
# ---------------------------------------------------------------------------------------------


def read_entities(path: Path) -> dict[str, set[str]]:
    """Entity paths of a ``.rrd`` file's recording (no leading ``/``) → archetype names logged
    there (e.g. ``{"signals/q/q1": {"rerun.archetypes.Scalars", ...}}``)."""
    out: dict[str, set[str]] = {}
    for chunk in RrdReader(path).stream():
        ep = chunk.entity_path.lstrip("/")
        if ep.startswith("__"):
            continue
        names = out.setdefault(ep, set())
        for f in chunk.to_record_batch().schema:
            a = (f.metadata or {}).get(b"rerun:archetype")
            if a:
                names.add(a.decode())
    return out


def _entities_of(rec: RunRecording) -> dict[str, set[str]]:
    """The entities :func:`log_run` writes for ``rec`` (what :func:`read_entities` reads back;
    archetypes only for the fronts)."""
    baseline_series = {s.path for m in rec.baselines.values() for s in m.series}
    out: dict[str, set[str]] = {p: set() for p in rec.entity_paths() if p not in baseline_series}
    out.update((entity, set()) for entity, _ in _baseline_signals(rec))
    for s in rec.optimization:  # the objectives of best / ideal / nadir: one entity each
        if s.group is not None:
            out.pop(s.path, None)
            out[s.group] = set()
    if rec.best is not None:
        skeleton = _skeleton(rec.best.poses)
        if skeleton is not None:  # the robot: one entity
            for p in (*skeleton[1], *skeleton[2]):
                out.pop(p.path, None)
            out[skeleton[0]] = set()
        feet = [pl.path for pl in rec.best.polylines if pl.path.endswith("/foot_path")]
        if any(pl.path == "world/path" for pl in rec.best.polylines):
            for foot in feet:  # drawn with the motion's path
                out.pop(foot, None)
    for m in rec.baselines.values():
        for pl in m.polylines:
            out.pop(pl.path, None)
            out["world/baselines/paths"] = set()
    for f in (rec.front, rec.best_point):
        if f is not None:
            out[f.path] = {
                "rerun.archetypes.Points3D" if f.dims == 3 else "rerun.archetypes.Points2D"
            }
    return out


def _job_views(
    ents: Mapping[str, set[str]], root: str, name: str | None
) -> tuple[list[Any], list[Any]]:
    """(spatial views, time-series views) for one job's entities under ``root`` ('' or
    'jobs/<name>/')."""

    def has(prefix: str) -> bool:
        p = root + prefix
        return any(e == p or e.startswith(p + "/") for e in ents)

    tag = f"{name}: " if name else ""
    spatial: list[Any] = []
    series: list[Any] = []
    if has("world"):
        spatial.append(rrb.Spatial3DView(origin=root + "world", name=f"{tag}robot, path and scene"))
    front = ents.get(root + "optimization/front")
    if front is not None:
        contents = [
            f"+ /{root}optimization/{e}" for e in ("front", "best_point", "final_front", "axes/**")
        ]
        if any("Points2D" in a for a in front):
            spatial.append(
                rrb.Spatial2DView(
                    origin=root + "optimization", contents=contents, name=f"{tag}Pareto front"
                )
            )
        else:
            spatial.append(
                rrb.Spatial3DView(
                    origin=root + "optimization", contents=contents, name=f"{tag}Pareto front"
                )
            )
    for kind, title in _SIGNAL_VIEWS:
        if has(f"signals/{kind}"):
            series.append(rrb.TimeSeriesView(origin=f"{root}signals/{kind}", name=f"{tag}{title}"))
    if has("signals/energy"):
        extra = sorted(
            f"+ /{e}"
            for e in ents
            if e.startswith(root + "baselines/") and e.endswith("/signals/energy/total")
        )
        series.append(
            rrb.TimeSeriesView(
                origin=f"{root}signals/energy",
                contents=[f"+ /{root}signals/energy/**", *extra],
                name=f"{tag}energy (J), best vs baselines" if extra else f"{tag}energy (J)",
            )
        )
    if has("optimization/best"):
        series.append(
            rrb.TimeSeriesView(
                origin=f"{root}optimization/best", name=f"{tag}best objective / generation"
            )
        )
    baseline_q = sorted(
        {
            f"+ /{e.split('/signals/q')[0]}/signals/q/**"
            for e in ents
            if e.startswith(root + "baselines/") and (e + "/").count("/signals/q/")
        }
    )
    if baseline_q:  # one view for every baseline (its series are named "<baseline>: ...")
        series.append(
            rrb.TimeSeriesView(
                origin=f"{root}baselines", contents=baseline_q, name=f"{tag}baselines: q (rad)"
            )
        )
    return spatial, series


def blueprint_for(
    content: RunRecording | Mapping[str, set[str]], *, jobs: Sequence[str] = ()
) -> rrb.Blueprint:
    """The default layout: spatial views (robot/path/scene, Pareto front) on the left, tabs of
    time-series views (q, qd, qdd, jerk, τ, power, energy, best objective, baselines) on the
    right. ``content``: a :class:`RunRecording` or an entity map (:func:`read_entities`).
    ``jobs``: for a merged recording, the job names under ``/jobs/<name>/`` (one set of views
    per job, plus overlays of every job's front, energy and best objective)."""
    ents = _entities_of(content) if isinstance(content, RunRecording) else dict(content)
    spatial: list[Any] = []
    series: list[Any] = []
    if jobs:
        with_front = [j for j in jobs if f"jobs/{j}/optimization/front" in ents]
        fronts = [
            f"+ /jobs/{j}/optimization/{e}" for j in with_front for e in ("front", "final_front")
        ] + [f"+ /jobs/{j}/optimization/axes/**" for j in with_front[:1]]
        if len(with_front) > 1:
            two_d = any(
                "Points2D" in a
                for j in jobs
                for a in ents.get(f"jobs/{j}/optimization/front", set())
            )
            view = rrb.Spatial2DView if two_d else rrb.Spatial3DView
            spatial.append(view(origin="jobs", contents=fronts, name="Pareto fronts, all jobs"))
        energy = [
            f"+ /jobs/{j}/signals/energy/total"
            for j in jobs
            if f"jobs/{j}/signals/energy/total" in ents
        ]
        if energy:
            series.append(
                rrb.TimeSeriesView(origin="jobs", contents=energy, name="energy (J), all jobs")
            )
        best = [
            f"+ /jobs/{j}/optimization/best/**"
            for j in jobs
            if any((e + "/").startswith(f"jobs/{j}/optimization/best/") for e in ents)
        ]
        if best:
            series.append(
                rrb.TimeSeriesView(origin="jobs", contents=best, name="best objective, all jobs")
            )
        spatial.append(rrb.TextDocumentView(origin="jobs/legend", name="jobs and colours"))
        per_job: list[Any] = []
        for j in jobs:  # one tab per job, not one tiny view per job stacked
            sp, se = _job_views(ents, f"jobs/{j}/", j)
            if sp or se:
                per_job.append(rrb.Tabs(*sp, *se, name=j))
        if per_job:
            series.append(rrb.Tabs(*per_job, name="each job"))
    else:
        spatial, series = _job_views(ents, "", None)
    parts: list[Any] = []
    if spatial:
        parts.append(rrb.Vertical(*spatial) if len(spatial) > 1 else spatial[0])
    if series:
        parts.append(rrb.Tabs(*series))
    if not parts:
        return rrb.Blueprint(auto_layout=True, auto_views=True)
    root: Any = rrb.Horizontal(*parts, column_shares=[3, 2]) if len(parts) == 2 else parts[0]
    has_time = any(e.startswith("signals/") or "/signals/" in e for e in ents)
    return rrb.Blueprint(
        root,
        rrb.TimePanel(timeline="time" if has_time else "generation"),
        collapse_panels=False,
    )


# ---------------------------------------------------------------------------------------------
# merging
# ---------------------------------------------------------------------------------------------

#: One colour per job of a merged recording (Tableau 10 and 2 more), RGB 0-255.
JOB_COLORS: tuple[tuple[int, int, int], ...] = (
    (31, 119, 180), (214, 39, 40), (44, 160, 44), (255, 127, 14), (148, 103, 189),
    (140, 86, 75), (227, 119, 194), (23, 190, 207), (188, 189, 34), (127, 127, 127),
    (0, 0, 128), (128, 0, 0),
)  # fmt: skip
_COLOR_NAMES = ("blue", "red", "green", "orange", "purple", "brown", "pink", "cyan", "olive",
                "grey", "navy", "maroon")  # fmt: skip


def _series_names_of(path: Path, entity: str) -> list[str]:
    """The line names (static ``SeriesLines:names``) of ``entity`` in the recording ``path``."""
    names: list[str] = []
    for chunk in RrdReader(path).stream():
        if chunk.entity_path.lstrip("/") != entity:
            continue
        batch = chunk.to_record_batch()
        if "SeriesLines:names" in batch.schema.names:
            rows = [r for r in batch.column("SeriesLines:names").to_pylist() if r]
            names = [str(n) for n in rows[-1]] if rows else names
    return names


def _colour_job(
    stream: rr.RecordingStream,
    ents: Mapping[str, set[str]],
    part: str,
    color: tuple[int, ...],
    best_names: Sequence[str] = (),
) -> None:
    """Give job ``part`` of a merged recording its own colour and name on the overlaid items
    (front points, energy and best-objective series): static values logged after the job's
    own, so they replace them. ``best_names``: the job's names of its objectives' lines in the
    grouped ``optimization/best`` entity (one line per objective), prefixed here ``<part>: ``."""
    root = f"jobs/{part}/"
    for e, archetypes in ents.items():
        if not e.startswith(root):
            continue
        rel = e[len(root) :]
        if rel in ("optimization/front", "optimization/final_front"):
            arche: Any = rr.Points3D if any("Points3D" in a for a in archetypes) else rr.Points2D
            stream.log(e, arche.from_fields(colors=[color]), static=True)
        elif rel == "signals/energy/total":
            stream.log(e, rr.SeriesLines(colors=[color], names=[f"{part}: energy"]), static=True)
        elif rel == "optimization/best":  # the objectives in one entity: one line each
            names = [f"{part}: {n}" for n in best_names] or [f"{part}: best"]
            stream.log(e, rr.SeriesLines(colors=[color] * len(names), names=names), static=True)
        elif rel.startswith("optimization/best/"):
            name = f"{part}: best {rel.rsplit('/', 1)[-1]}"
            stream.log(e, rr.SeriesLines(colors=[color], names=[name]), static=True)


def _front_frame_of(path: Path) -> tuple[np.ndarray | None, list[str]]:
    """The final front (k, d) and the axis names a recording's writer stored, if any."""
    points: np.ndarray | None = None
    names: list[str] = []
    for chunk in RrdReader(path).stream():
        if chunk.entity_path not in ("/optimization/final_front", "/optimization/axes"):
            continue
        batch = chunk.to_record_batch()
        for col in batch.schema.names:
            if col.endswith(":positions") and chunk.entity_path.endswith("final_front"):
                rows = [r for r in batch.column(col).to_pylist() if r]
                if rows:
                    points = np.asarray(rows[-1], dtype=float)
            elif col.endswith("legopt_axis_names"):
                rows = [r for r in batch.column(col).to_pylist() if r]
                names = [str(n) for n in rows[-1]] if rows else names
    return points, names


def _common_display(paths: Sequence[Path]) -> FrontDisplay | None:
    """One box for the fronts of every recording (so an overlay compares like with like)."""
    frames = [_front_frame_of(p) for p in paths]
    fronts = [F for F, _ in frames if F is not None and F.ndim == 2 and F.size]
    if not fronts or len({F.shape[1] for F in fronts}) != 1:
        return None
    labels = next((n for _, n in frames if n), [])
    return front_display(fronts, [], labels=labels)


def _legend(parts: Sequence[str]) -> str:
    """Markdown naming each job's colour."""
    rows = [f"| {_COLOR_NAMES[i % len(_COLOR_NAMES)]} | `{p}` |" for i, p in enumerate(parts)]
    return "\n".join(["| colour | job |", "|---|---|", *rows])


def merge_recordings(
    paths: Sequence[Path],
    out: Path,
    names: Sequence[str],
    *,
    recording_id: str | None = None,
) -> None:
    """Merge several jobs' recordings into one ``out`` for side-by-side replay: every entity of
    ``paths[i]`` moves under ``/jobs/<names[i]>/`` (names made entity-path safe), timelines are
    kept (all jobs' ``time`` and ``generation`` axes overlap), and a blueprint with one set of
    views per job plus overlays of the fronts, energies and best objectives is saved with it.
    Atomic like :func:`write_recording`."""
    paths = [Path(p) for p in paths]
    if len(paths) != len(names):
        raise ValueError(
            f"names: expected {len(paths)} names (one per recording), got {len(names)}"
        )
    if not paths:
        raise ValueError("paths: no recordings to merge")
    parts = lrec.unique_parts(names)
    for p in paths:
        if not p.is_file():
            raise FileNotFoundError(f"recording not found: {p}")
    ents: dict[str, set[str]] = {}
    for p, part in zip(paths, parts, strict=True):
        for e, a in read_entities(p).items():
            ents[f"jobs/{part}/{e}"] = a

    common = _common_display(paths)

    def log(stream: rr.RecordingStream) -> None:
        stream.send_recording_name(f"{len(paths)} jobs: {', '.join(parts)}")
        for i, (p, part) in enumerate(zip(paths, parts, strict=True)):
            stream.send_chunks(
                c.with_entity_path(f"/jobs/{part}{c.entity_path}")
                for c in RrdReader(p).stream()
                if not c.entity_path.startswith("/__")
            )
            best_names = _series_names_of(p, "optimization/best")
            _colour_job(stream, ents, part, JOB_COLORS[i % len(JOB_COLORS)], best_names)
            if common is not None and f"jobs/{part}/optimization/front" in ents:
                root = f"jobs/{part}/optimization"
                for e in ("front", "best_point", "final_front"):
                    stream.log(f"{root}/{e}", _box_transform(common), static=True)
                _log_axes(stream, f"{root}/axes", common)
        stream.log("jobs/legend", rr.TextDocument(_legend(parts), media_type="text/markdown"),
                   static=True)  # fmt: skip

    _write_atomic(Path(out), recording_id, log, blueprint_for(ents, jobs=parts))


# ---------------------------------------------------------------------------------------------
# replay
# ---------------------------------------------------------------------------------------------


def has_display() -> bool:
    """True where a native viewer window can open (macOS/Windows, or DISPLAY/WAYLAND_DISPLAY)."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def rerun_binary() -> str:
    """Path of the Rerun viewer/CLI executable bundled with rerun-sdk (``RERUN_CLI_PATH``
    overrides). The ``rerun`` console script is a Python wrapper whose child would outlive a
    terminated wrapper, so the binary is run directly."""
    env = os.environ.get("RERUN_CLI_PATH")
    if env:
        return env
    spec = importlib.util.find_spec("rerun_cli")
    if spec is not None and spec.origin:
        exe = Path(spec.origin).parent / ("rerun.exe" if sys.platform == "win32" else "rerun")
        if exe.exists():
            return str(exe)
    found = shutil.which("rerun")
    if found:
        return found
    raise FileNotFoundError("the rerun viewer binary was not found (is rerun-sdk installed?)")


def viewer_url(web_port: int, grpc_url: str, host: str = "127.0.0.1") -> str:
    """The web viewer page that connects to ``grpc_url``."""
    return f"http://{host}:{web_port}/?url={quote(grpc_url, safe='')}"


@dataclass
class ViewerHandle:
    """A viewer running in a child process: ``url`` is the web viewer page (None for the
    native viewer). ``wait()`` blocks until it exits, ``stop()`` ends it; usable in ``with``."""

    process: subprocess.Popen[bytes]
    url: str | None
    log: IO[bytes] | None = None

    def wait(self, timeout: float | None = None) -> int:
        return self.process.wait(timeout)

    def stop(self, timeout: float = 5.0) -> None:
        """Terminate the viewer process (SIGTERM, then SIGKILL after ``timeout`` s)."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout)
        if self.log is not None:
            self.log.close()

    def __enter__(self) -> ViewerHandle:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def _free_port(host: str = "127.0.0.1") -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])


def _push(path: Path, grpc_url: str) -> None:
    """Send the recording ``path`` (with its blueprint, rebuilt from its entities) to the gRPC
    server at ``grpc_url``; the server keeps it for viewers that connect later."""
    reader = RrdReader(path)
    stores = reader.recordings()
    rid = stores[0].recording_id if stores else str(uuid.uuid4())
    ents = read_entities(path)
    jobs = sorted({e.split("/")[1] for e in ents if e.startswith("jobs/") and e.count("/") >= 2})
    try:
        _push_stream(reader, rid, grpc_url, blueprint_for(ents, jobs=jobs))
    finally:
        release_streams()


def _push_stream(reader: RrdReader, rid: str, grpc_url: str, blueprint: rrb.Blueprint) -> None:
    stream = rr.RecordingStream(APP_ID, recording_id=rid)  # dropped when this returns
    try:
        _with_default_blueprint(
            blueprint, lambda bp: rerun_bindings.connect_grpc(grpc_url, bp, stream.to_native())
        )
        stream.send_chunks(c for c in reader.stream() if not c.entity_path.startswith("/__"))
        stream.flush()
    finally:
        stream.disconnect()


def serve_web(
    path: Path,
    port: int | None = 9090,
    *,
    grpc_port: int | None = None,
    bind: str = "127.0.0.1",
    timeout: float = 30.0,
) -> ViewerHandle:
    """Serve the recording ``path`` in the Rerun web viewer on ``http://<bind>:<port>/``.

    Starts the bundled ``rerun --serve-web`` (web viewer over HTTP + a gRPC proxy on
    ``grpc_port``; both bound to ``bind``, free ports when None) in a child process, waits until
    the page answers HTTP 200, then sends the file's data and blueprint to the proxy, which
    keeps them for every browser that connects. Returns the handle (``handle.url`` is the page
    to open; ``handle.stop()`` or a ``with`` block ends the server).

    (The file is pushed from here instead of passed to ``rerun --serve-web FILE`` because that
    file loader keeps a core busy for as long as it serves.)
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"recording not found: {path}")
    port = port or _free_port(bind)
    grpc_port = grpc_port or _free_port(bind)
    cmd = [
        rerun_binary(),
        "--serve-web",
        "--bind",
        bind,
        "--web-viewer-port",
        str(port),
        "--port",
        str(grpc_port),
    ]
    log = tempfile.TemporaryFile()  # not a pipe: a long session must never block on its log
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT)
    host = "127.0.0.1" if bind in ("0.0.0.0", "::") else bind  # noqa: S104
    grpc_url = f"rerun+http://{host}:{grpc_port}/proxy"
    handle = ViewerHandle(proc, viewer_url(port, grpc_url, host), log)
    try:
        _wait_http(f"http://{host}:{port}/", proc, timeout, log)
        _push(path, grpc_url)
    except BaseException:
        handle.stop()
        raise
    return handle


def _wait_http(url: str, proc: subprocess.Popen[bytes], timeout: float, log: IO[bytes]) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            log.seek(0)
            err = log.read().decode(errors="replace")
            raise RuntimeError(
                f"rerun web viewer exited ({proc.returncode}): {err.strip()[-2000:]}"
            )
        try:
            with urllib.request.urlopen(url, timeout=1.0) as r:
                if r.status == 200:
                    return
        except (urllib.error.URLError, OSError):
            pass
        time.sleep(0.1)
    raise TimeoutError(f"rerun web viewer did not answer at {url} within {timeout} s")


def open_viewer(path: Path, *, web: bool | None = None, port: int = 9090) -> ViewerHandle:
    """Open the recording ``path``: the native Rerun viewer (``rerun FILE``) where there is a
    display, else (or with ``web=True``) the web viewer served on ``127.0.0.1:port`` from a
    child process. Returns the handle: ``handle.url`` is the page to open (web), ``wait()``
    blocks until the viewer exits, ``stop()`` ends it."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"recording not found: {path}")
    if web is None:
        web = not has_display()
    if web:
        return serve_web(path, port)
    proc = subprocess.Popen([rerun_binary(), str(path)])
    return ViewerHandle(proc, None)
