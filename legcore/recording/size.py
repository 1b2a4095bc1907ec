"""The size estimate of a recording and its budget constants (rerun-sdk 0.41 files)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from legcore.recording.model import FrontTrack, MotionRecording, PoseTrack, RunRecording, Series

if TYPE_CHECKING:
    pass

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
