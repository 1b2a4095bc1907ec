"""Rerun recordings of jobs: write a job's ``.rrd`` file. With ``layout`` (which items
share an entity), ``blueprint`` (the views), ``merge`` and ``replay``, the
only modules importing rerun.

    write_recording(result, path, recording_id=job_id)   # one job  -> path (.rrd)
    merge.merge_recordings([a, b], out, names=["a", "b"])   # a sweep -> out, /jobs/<name>/
    replay.open_viewer(path)                        # native viewer, or the web viewer
    replay.serve_web(path, port)                    # web viewer on 127.0.0.1:port

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
  on the ``time`` timeline too (:mod:`services.recording.front_display`); a merged recording
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
import os
import uuid
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
import rerun_bindings

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
from services.recording.blueprint import blueprint_for
from services.recording.front_display import FrontDisplay, front_display
from services.recording.layout import baseline_signals, robot_skeleton, series_groups

if TYPE_CHECKING:
    from legcore.robots.legged import LeggedRobot
    from legcore.robots.model import Robot
    from legcore.runner import RunResult

__all__ = [
    "APP_ID",
    "log_run",
    "release_streams",
    "write_recording",
]

#: Rerun application id of every LegOpt recording (blueprints are matched to it).
APP_ID = "legopt"



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
    for entity, groups in baseline_signals(rec):
        _log_series_group(stream, [s for _, g in groups for s in g], "", entity, groups)
    for group in series_groups(rec.optimization):  # the objectives of best / ideal / nadir
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
    ``signals`` its series are left to the caller (:func:`baseline_signals`)."""
    for group in series_groups(m.series) if signals else []:
        _log_series_group(stream, group, tag)
    skeleton = robot_skeleton(m.poses)
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
