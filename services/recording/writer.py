"""Rerun recordings of jobs: write a job's ``.rrd`` file. With ``motion_log`` (a motion's
items), ``layout`` (which items share an entity), ``blueprint`` (the views), ``merge`` and
``replay``, the only modules importing rerun.

    write_recording(result, path, recording_id=job_id)   # one job  -> path (.rrd)
    merge.merge_recordings([a, b], out, names=["a", "b"])   # a sweep -> out, /jobs/<name>/
    replay.open_viewer(path)                        # native viewer, or the web viewer
    replay.serve_web(path, port)                    # web viewer on 127.0.0.1:port

What is logged where is decided by the pure :mod:`legcore.recording` (``docs/recording.md``);
this module and ``motion_log`` (series, poses, skeleton, paths) turn its items into archetypes:

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
    RunRecording,
    record_run,
)
from services.recording.blueprint import blueprint_for
from services.recording.front_display import FrontDisplay, front_display
from services.recording.layout import baseline_signals, series_groups
from services.recording.motion_log import _log_motion, _log_series_group, _time_column

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
