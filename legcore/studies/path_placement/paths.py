"""Cartesian tool paths for the ``path_placement`` study (seed 001): built-in paths and CSV input.

A :class:`ToolPath` is a list of K tool poses ``T`` (K, 4, 4) (world frame, m) with time stamps
``t`` (K,) s. The tool frame is the welding gun's: its z axis is the approach direction of the
torch. Orientation of a torch is free about its own axis, so the built-in paths fix the tool x
axis as the projection of the world x axis on the plane normal to z (no spin about the torch:
the wrist does not have to wind a full turn per circle).

Built-in paths standing in for seed 001's two paths (whose point files are not published).
Each is sampled at a uniform time step over the paper's duration of its original path; every
segment runs from rest to rest with a trapezoidal speed profile (ramps of 20 % of the segment's
time), so that corners do not ask for infinite accelerations.

- ``pan`` — "Robotworks" (PanCirc.SRC/.DAT of RobotWorks, 225 points): a closed circular seam
  of radius 0.08 m (the inside bottom edge of a round pan), 225 points over the full circle
  (last = first), torch 10° from the vertical leaning out into the corner. Duration
  1.01205355 s (paper, Table 2): cruise ≈ 0.62 m/s.
- ``jar`` — "Tarro Inclinado" (413 points from 3D edges of a tilted jar modelled in Inventor):
  a jar of radius 0.06 m and height 0.15 m whose axis leans 30° (towards +y); the path welds the
  bottom circle (160 points, closed), climbs the side seam (93 points) and welds the top rim
  (160 points, closed), the torch pointing down the jar axis and leaning out by 10°. Duration
  1.66888271 s (paper, Table 3).

Both are written at their "as drawn" location, the ORIGINAL placement of the study: the pan's
centre at :data:`PAN_CENTER` and the jar's base centre at :data:`JAR_CENTER` in the robot base
frame — close to the robot with the arm folded (low manipulability), like the paper's
originals (see docs/studies.md (seed 001)).

CSV text (:func:`parse_path_csv`): one point per row, comma separated (``#`` comments and blank
lines ignored), SI units. Columns, optionally named by a header row:

- ``x, y, z, roll, pitch, yaw`` (m, rad; ``R = Rz(yaw) Ry(pitch) Rx(roll)``, the fixed-axis
  X-Y-Z convention, = KUKA's A, B, C = yaw, pitch, roll), or
- ``x, y, z, r11, r12, r13, r21, r22, r23, r31, r32, r33`` (the rotation matrix, row-major),
- each optionally preceded by a time column ``t`` (s, strictly increasing). Without ``t`` the
  points are spread uniformly over the ``duration`` given in the study parameters.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.trajectories.profiles import TrapezoidalProfile

__all__ = [
    "BUILTIN_PATHS",
    "MAX_CSV_CHARS",
    "MAX_POINTS",
    "ToolPath",
    "builtin_path",
    "jar_path",
    "oriented",
    "pan_path",
    "parse_path_csv",
    "rpy_to_matrix",
]

FloatArray = NDArray[np.float64]

#: Largest number of path points accepted (K), and of CSV characters.
MAX_POINTS = 5000
MAX_CSV_CHARS = 1_000_000

#: Paper's durations of the original paths (Tables 2 and 3), s.
PAN_DURATION = 1.01205355
JAR_DURATION = 1.66888271

#: "As drawn" (original) locations of the built-in paths in the robot base frame, m.
PAN_CENTER = (0.25, 0.0, 0.80)
JAR_CENTER = (0.0, -0.38, 0.75)

_RPY_COLS = ("x", "y", "z", "roll", "pitch", "yaw")
_ROT_COLS = ("x", "y", "z", "r11", "r12", "r13", "r21", "r22", "r23", "r31", "r32", "r33")


@dataclass(frozen=True, eq=False)
class ToolPath:
    """K tool poses ``T`` (K, 4, 4) (world, m) at times ``t`` (K,) s, with a name."""

    name: str
    T: FloatArray
    t: FloatArray
    description: str = ""

    def __post_init__(self) -> None:
        K = self.T.shape[0]
        if self.T.shape != (K, 4, 4) or K < 2:
            raise ValueError(f"path: expected poses (K >= 2, 4, 4), got {self.T.shape}")
        if self.t.shape != (K,):
            raise ValueError(f"path: expected times ({K},), got {self.t.shape}")
        if np.any(np.diff(self.t) <= 0.0):
            raise ValueError("path: times must be strictly increasing")

    @property
    def n_points(self) -> int:
        return int(self.T.shape[0])

    @property
    def p(self) -> FloatArray:
        """Tool positions (K, 3), m."""
        return self.T[:, :3, 3]

    @property
    def duration(self) -> float:
        """t_K − t_1, s."""
        return float(self.t[-1] - self.t[0])

    @property
    def length(self) -> float:
        """Length of the polyline through the points, m."""
        return float(np.sum(np.linalg.norm(np.diff(self.p, axis=0), axis=1)))


def rpy_to_matrix(roll: ArrayLike, pitch: ArrayLike, yaw: ArrayLike) -> FloatArray:
    """``R = Rz(yaw) Ry(pitch) Rx(roll)`` (…, 3, 3) from angles (…) in rad."""
    r, p, y = (np.asarray(a, dtype=float) for a in (roll, pitch, yaw))
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    R = np.empty(np.broadcast(r, p, y).shape + (3, 3))
    R[..., 0, 0] = cy * cp
    R[..., 0, 1] = cy * sp * sr - sy * cr
    R[..., 0, 2] = cy * sp * cr + sy * sr
    R[..., 1, 0] = sy * cp
    R[..., 1, 1] = sy * sp * sr + cy * cr
    R[..., 1, 2] = sy * sp * cr - cy * sr
    R[..., 2, 0] = -sp
    R[..., 2, 1] = cp * sr
    R[..., 2, 2] = cp * cr
    return R


def _frames_from_approach(z: FloatArray, ref: FloatArray | None = None) -> FloatArray:
    """Rotations (K, 3, 3) with z axis ``z`` (K, 3) and x axis the projection of ``ref``."""
    z = z / np.linalg.norm(z, axis=-1, keepdims=True)
    e = np.array([1.0, 0.0, 0.0]) if ref is None else np.asarray(ref, dtype=float)
    x = e - np.sum(z * e, axis=-1, keepdims=True) * z
    x /= np.linalg.norm(x, axis=-1, keepdims=True)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=-1)


def _poses(p: FloatArray, R: FloatArray) -> FloatArray:
    T = np.zeros((p.shape[0], 4, 4))
    T[:, :3, :3] = R
    T[:, :3, 3] = p
    T[:, 3, 3] = 1.0
    return T


def _segment_time_law(n_intervals: Sequence[int], duration: float, ramp: float) -> tuple[
    FloatArray, FloatArray, NDArray[np.int64]
]:
    """Uniform time grid over consecutive segments, each run rest-to-rest with a trapezoidal
    velocity profile (ramps of ``ramp`` × its duration at both ends).

    Segment j spans ``n_intervals[j]`` intervals of the grid (its duration is proportional).
    Returns ``t`` (K,), the normalised path parameter ``s`` (K,) within the segment of each
    point, and the segment index ``seg`` (K,) (a corner point belongs to the segment it ends).
    """
    n = np.asarray(n_intervals, dtype=np.int64)
    K = int(n.sum()) + 1
    t = np.linspace(0.0, duration, K)
    dt = duration / (K - 1)
    s = np.empty(K)
    seg = np.empty(K, dtype=np.int64)
    s[0], seg[0] = 0.0, 0
    start = 0
    for j, nj in enumerate(n):  # a handful of segments
        Tj = nj * dt
        prof = TrapezoidalProfile(Tj, ramp * Tj, ramp * Tj)
        idx = np.arange(start + 1, start + nj + 1)
        s[idx] = prof.s((idx - start) * dt)
        seg[idx] = j
        start += nj
    return t, np.clip(s, 0.0, 1.0), seg


def pan_path(
    center: tuple[float, float, float] = PAN_CENTER,
    radius: float = 0.08,
    work_angle: float = math.radians(10.0),
    n_points: int = 225,
    duration: float = PAN_DURATION,
    ramp: float = 0.2,
) -> ToolPath:
    """Seed 001's "Robotworks" stand-in: a closed circular seam, torch leaning out (see module).

    ``center`` (m) is the circle's centre; the first point is at angle 0 (+x side of the
    circle); the path runs counter-clockwise seen from above, from rest to rest (trapezoidal
    speed, ramps of ``ramp`` × ``duration``). ``work_angle`` (rad) is the tilt of the torch from
    the vertical, towards the outside of the circle.
    """
    t, s, _ = _segment_time_law([n_points - 1], duration, ramp)
    ang = 2.0 * math.pi * s
    u = np.stack([np.cos(ang), np.sin(ang), np.zeros_like(ang)], axis=-1)  # radial out
    p = np.asarray(center, dtype=float) + radius * u
    z = math.cos(work_angle) * np.array([0.0, 0.0, -1.0]) + math.sin(work_angle) * u
    desc = (f"circular seam r = {radius} m, {n_points} points, torch "
            f"{math.degrees(work_angle):.0f}° from vertical, {duration:.6g} s")
    return ToolPath("pan", _poses(p, _frames_from_approach(z)), t, desc)


def jar_path(
    base_center: tuple[float, float, float] = JAR_CENTER,
    radius: float = 0.06,
    height: float = 0.15,
    tilt: float = math.radians(30.0),
    work_angle: float = math.radians(10.0),
    n_circle: int = 160,
    n_side: int = 93,
    duration: float = JAR_DURATION,
    ramp: float = 0.2,
) -> ToolPath:
    """Seed 001's "Tarro Inclinado" stand-in: bottom circle, side seam, top rim of a tilted jar.

    The jar axis ``a`` is the vertical turned by ``tilt`` (rad) about the world x axis (it leans
    towards +y). Bottom circle (``n_circle`` points, closed) around ``base_center`` (m), then
    ``n_side`` points up the side line at the circle's start angle (corners excluded), then the
    top rim (``n_circle`` points, closed): 413 points by default. Each of the three segments is
    run from rest to rest (trapezoidal speed, ramps of ``ramp`` × its duration); the segment
    durations are proportional to their numbers of intervals. The torch points down the jar
    axis, leaning out by ``work_angle`` (rad) (away from the axis).
    """
    a = np.array([0.0, math.sin(tilt), math.cos(tilt)])
    e1 = np.array([1.0, 0.0, 0.0])
    e2 = np.cross(a, e1)
    t, s, seg = _segment_time_law([n_circle - 1, n_side + 1, n_circle - 1], duration, ramp)
    ang = np.where(seg == 1, 0.0, 2.0 * math.pi * s)
    u = np.cos(ang)[:, None] * e1 + np.sin(ang)[:, None] * e2  # radial out, (K, 3)
    c0 = np.asarray(base_center, dtype=float)
    lift = np.where(seg == 0, 0.0, np.where(seg == 1, s, 1.0)) * height
    p = c0 + radius * u + lift[:, None] * a
    z = -math.cos(work_angle) * a + math.sin(work_angle) * u
    K = p.shape[0]
    desc = (f"tilted jar r = {radius} m, h = {height} m, axis {math.degrees(tilt):.0f}° off "
            f"vertical; bottom circle {n_circle} + side {n_side} + rim {n_circle} = {K} points, "
            f"{duration:.6g} s")
    return ToolPath("jar", _poses(p, _frames_from_approach(z)), t, desc)


BUILTIN_PATHS = ("pan", "jar")


def builtin_path(name: str, duration: float | None = None, scale: float = 1.0) -> ToolPath:
    """The built-in path ``name`` (``"pan"`` or ``"jar"``) at its paper duration or ``duration``
    (s), its size ``scale`` × the paper's (about its centre as drawn; the orientations and the
    time stamps unchanged). ``scale`` 1 and no ``duration``: exactly the paper's path."""
    if name == "pan":
        if scale == 1.0:
            return pan_path() if duration is None else pan_path(duration=duration)
        return pan_path(radius=0.08 * scale, duration=PAN_DURATION if duration is None
                        else duration)
    if name == "jar":
        if scale == 1.0:
            return jar_path() if duration is None else jar_path(duration=duration)
        return jar_path(radius=0.06 * scale, height=0.15 * scale,
                        duration=JAR_DURATION if duration is None else duration)
    raise ValueError(f"path: unknown built-in path {name!r}; expected one of {BUILTIN_PATHS}")


def _rotation_onto(a: FloatArray, b: FloatArray) -> FloatArray:
    """The smallest rotation (3, 3) taking unit vector ``a`` onto unit vector ``b`` (a half
    turn about a horizontal axis ⊥ ``a`` when they are opposite)."""
    v = np.cross(a, b)
    c = float(a @ b)
    if np.linalg.norm(v) < 1e-12:
        if c > 0.0:
            return np.eye(3)
        e = np.eye(3)[int(np.argmin(np.abs(a)))]
        u = np.cross(a, e)
        u /= np.linalg.norm(u)
        return 2.0 * np.outer(u, u) - np.eye(3)
    K = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + K + K @ K / (1.0 + c)


def oriented(path: ToolPath, axis: ArrayLike | None = None, spin: float = 0.0) -> ToolPath:
    """``path`` with every tool pose turned by ``spin`` (rad) about its own z axis (the torch
    spins freely about its axis: the same weld) and then, with ``axis`` (3,), the whole path
    turned rigidly about its centroid by the smallest rotation that takes its mean tool axis
    onto ``axis`` (e.g. a seam on a table turned onto a wall). No change: the path itself."""
    if axis is None and spin == 0.0:
        return path
    T = path.T.copy()
    if spin != 0.0:
        c, s = math.cos(spin), math.sin(spin)
        T[:, :3, :3] = T[:, :3, :3] @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    desc = path.description
    if axis is not None:
        a = np.asarray(axis, dtype=float)
        a = a / np.linalg.norm(a)
        m = T[:, :3, 2].mean(axis=0)
        m /= np.linalg.norm(m)
        R = _rotation_onto(m, a)
        centroid = T[:, :3, 3].mean(axis=0)
        T[:, :3, 3] = centroid + (T[:, :3, 3] - centroid) @ R.T
        T[:, :3, :3] = R @ T[:, :3, :3]
        desc += f"; turned so that its mean tool axis is {np.round(a, 4).tolist()}"
    if spin != 0.0:
        desc += f"; tool spun {spin:.4g} rad about its axis"
    return ToolPath(path.name, T, path.t.copy(), desc)


def _orthonormalize(R: FloatArray, tol: float = 1e-4) -> FloatArray:
    """Nearest rotations (K, 3, 3) of matrices that are rotations to ``tol``; ValueError else."""
    err = np.abs(R @ np.swapaxes(R, -1, -2) - np.eye(3)).max(axis=(-2, -1))
    det = np.linalg.det(R)
    bad = np.flatnonzero((err > tol) | (det <= 0.0))
    if bad.size:
        raise ValueError(f"csv: row {int(bad[0]) + 1} is not a rotation matrix "
                         f"(|R Rᵀ − I| = {err[bad[0]]:.3g}, det = {det[bad[0]]:.3g})")
    U, _, Vt = np.linalg.svd(R)
    return U @ Vt


def parse_path_csv(text: str, duration: float | None = None, name: str = "csv") -> ToolPath:
    """A :class:`ToolPath` from CSV text (see the module docstring for the columns).

    Raises ValueError (starting with ``csv:`` or ``duration:``) for malformed text, non-finite
    values, fewer than 2 or more than :data:`MAX_POINTS` points, non-rotations, non-increasing
    times, or a missing ``duration`` when the text has no time column.
    """
    if not isinstance(text, str):
        raise ValueError("csv: expected text")
    if len(text) > MAX_CSV_CHARS:
        raise ValueError(f"csv: text longer than {MAX_CSV_CHARS} characters")
    rows: list[list[str]] = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            rows.append([c.strip() for c in line.split(",")])
    if not rows:
        raise ValueError("csv: no data rows")
    def numeric(c: str) -> bool:
        try:
            float(c)
        except ValueError:
            return False
        return True

    header: list[str] | None = None
    if not any(numeric(c) for c in rows[0]):  # a header row names every column
        header = [c.lower() for c in rows[0]]
        rows = rows[1:]
    n_cols = len(header) if header is not None else len(rows[0]) if rows else 0
    if len(rows) < 2:
        raise ValueError(f"csv: need at least 2 points, got {len(rows)}")
    if len(rows) > MAX_POINTS:
        raise ValueError(f"csv: at most {MAX_POINTS} points, got {len(rows)}")
    for i, r in enumerate(rows):
        if len(r) != n_cols:
            raise ValueError(f"csv: row {i + 1} has {len(r)} columns, expected {n_cols}")
    try:
        data = np.array([[float(c) for c in r] for r in rows], dtype=float)
    except ValueError as exc:
        raise ValueError(f"csv: non-numeric value ({exc})") from None
    if not np.all(np.isfinite(data)):
        row = int(np.flatnonzero(~np.all(np.isfinite(data), axis=1))[0])
        raise ValueError(f"csv: row {row + 1} has a non-finite value")
    if header is None:
        layouts = {6: _RPY_COLS, 7: ("t", *_RPY_COLS), 12: _ROT_COLS, 13: ("t", *_ROT_COLS)}
        if n_cols not in layouts:
            raise ValueError(f"csv: expected 6, 7, 12 or 13 columns, got {n_cols}")
        header = list(layouts[n_cols])
    if len(set(header)) != len(header):
        raise ValueError(f"csv: repeated column names in header {header}")
    col = {c: data[:, header.index(c)] for c in header}
    names = set(header) - {"t"}
    if names == set(_RPY_COLS):
        R = rpy_to_matrix(col["roll"], col["pitch"], col["yaw"])
    elif names == set(_ROT_COLS):
        R = _orthonormalize(np.stack([col[c] for c in _ROT_COLS[3:]], axis=-1).reshape(-1, 3, 3))
    else:
        raise ValueError(f"csv: header {header} must name x, y, z and roll, pitch, yaw "
                         f"or r11..r33 (optionally t)")
    p = np.stack([col["x"], col["y"], col["z"]], axis=-1)
    if np.max(np.abs(p)) > 100.0:
        raise ValueError("csv: coordinates beyond 100 m; positions must be in metres")
    K = p.shape[0]
    if "t" in col:
        t = col["t"] - col["t"][0]
        if np.any(np.diff(t) <= 0.0):
            row = int(np.flatnonzero(np.diff(t) <= 0.0)[0]) + 2
            raise ValueError(f"csv: times must be strictly increasing (row {row})")
    else:
        if duration is None:
            raise ValueError("duration: required (s) when the CSV path has no t column")
        t = np.linspace(0.0, float(duration), K)
    return ToolPath(name, _poses(p, R), t, f"user path, {K} points, {t[-1]:.6g} s")
