"""How a motion's items are logged to a Rerun stream (for :mod:`services.recording.writer`):
scalar series (one entity and one ``send_columns`` call per signal's joints), poses and what
they draw, the robot's skeleton (links and frame axes as two entities), points, paths, point
sets and boxes. The Pareto front's items are the writer's own.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import rerun as rr

from legcore import recording as lrec
from legcore.recording import MotionRecording, PoseTrack, Series
from services.recording.layout import robot_skeleton, series_groups


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
