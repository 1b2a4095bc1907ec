"""One motion (a Solution's Motion) as recording items: signals, robot, scene."""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from legcore.recording.helpers import (
    _as_float,
    _cumtrapz,
    _fill_nan_rows,
    _z_to,
    entity_part,
    link_radius,
    unique_parts,
)
from legcore.recording.model import (
    C_BASELINE,
    C_BODY,
    C_GROUND,
    C_OBSTACLE,
    C_PATH,
    C_SUPPORT,
    C_TARGET,
    C_TOOL,
    DEFAULT_MAX_SAMPLES,
    SIGNALS,
    BoxSet,
    FloatArray,
    IntArray,
    MeshRoots,
    MotionRecording,
    PointSet,
    PointTrack,
    Polyline,
    PolylineTrack,
    PoseTrack,
    Series,
)
from legcore.recording.sampling import minmax_columns, shared_minmax_indices, stride_indices
from legcore.recording.urdf_visuals import _urdf_visuals

if TYPE_CHECKING:
    from legcore.robots.legged import LeggedRobot
    from legcore.robots.model import Robot
    from legcore.studies.study import Motion

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


def _scene_items(
    motion: Motion, idx: IntArray, world: str, radius: float, rec: MotionRecording
) -> None:
    """Scene entries → items. ``obstacles`` (Box list) → boxes; ``support_polygon`` (P,3) or
    (K,P,3) (NaN rows = unused vertices) → closed strip, static or over time; ``ground_z`` →
    a thin ground slab under everything drawn; ``MOVING_POINT_KEYS`` (K,3) and any (K,P,3)
    array → points over time; keys with "path" → a static strip; other (M,3)/(3,) arrays and
    ``feet``/``targets`` dicts of 3-vectors → static points. Body-pose keys, metadata and
    direction-like keys are not drawn."""
    from legcore.studies.study import Box

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
