"""Which entities a recording gets where items share one: the baselines' signals (one entity
per signal when they share their samples) and the robot's skeleton entity."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from legcore.recording import (
    PoseTrack,
    RunRecording,
    Series,
)

if TYPE_CHECKING:
    pass

def series_groups(series: Sequence[Series]) -> list[list[Series]]:
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

__all__ = [
    "baseline_signals",
    "series_groups",
    "robot_skeleton",
]


def baseline_signals(rec: RunRecording) -> list[tuple[str, list[tuple[str, list[Series]]]]]:
    """The baselines' signals by entity: ``(entity, [(baseline name, its series), ...])``. A
    signal every baseline has on the same samples is one entity for all of them,
    ``baselines/signals/<kind>`` (one line per baseline and joint, named ``<baseline>: ...``):
    a chunk is ~1.5 kB of schema whatever it holds. Otherwise each baseline keeps its own,
    ``baselines/<name>/signals/<kind>``."""
    by_kind: dict[str, list[tuple[str, list[Series]]]] = {}
    for m in rec.baselines.values():
        for g in series_groups(m.series):
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


def robot_skeleton(
    poses: Sequence[PoseTrack],
) -> tuple[str, list[PoseTrack], list[PoseTrack]] | None:
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
