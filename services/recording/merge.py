"""Merged recordings of a sweep: every job's ``.rrd`` under ``jobs/<name>/``, each job in its
own colour and name, one box for all fronts."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import rerun as rr
from rerun.chunk import RrdReader

from legcore import recording as lrec
from services.recording.blueprint import blueprint_for, read_entities
from services.recording.front_display import FrontDisplay, front_display
from services.recording.writer import _box_transform, _log_axes, _write_atomic

if TYPE_CHECKING:
    pass

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


def job_color(i: int) -> tuple[tuple[int, int, int], str]:
    """The colour (RGB 0-255) and its name of the ``i``-th job of a merged recording: the 12
    named colours, then hues spread by the golden angle (a merge holds up to 32 jobs; no two
    share a colour)."""
    if i < len(JOB_COLORS):
        return JOB_COLORS[i], _COLOR_NAMES[i]
    import colorsys

    hue = (i * 0.6180339887) % 1.0
    r, g, b = colorsys.hsv_to_rgb(hue, 0.55 + 0.3 * (i % 2), 0.75)
    rgb = (round(r * 255), round(g * 255), round(b * 255))
    return rgb, f"#{rgb[0]:02x}{rgb[1]:02x}{rgb[2]:02x}"

__all__ = [
    "merge_recordings",
]


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
    rows = [f"| {job_color(i)[1]} | `{p}` |" for i, p in enumerate(parts)]
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
            _colour_job(stream, ents, part, job_color(i)[0], best_names)
            if common is not None and f"jobs/{part}/optimization/front" in ents:
                root = f"jobs/{part}/optimization"
                for e in ("front", "best_point", "final_front"):
                    stream.log(f"{root}/{e}", _box_transform(common), static=True)
                _log_axes(stream, f"{root}/axes", common)
        stream.log("jobs/legend", rr.TextDocument(_legend(parts), media_type="text/markdown"),
                   static=True)  # fmt: skip

    _write_atomic(Path(out), recording_id, log, blueprint_for(ents, jobs=parts))
