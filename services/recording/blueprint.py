"""The default Rerun blueprint of a recording (views and tabs), and what a .rrd file holds."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import rerun.blueprint as rrb
from rerun.chunk import RrdReader

from legcore.recording import (
    RunRecording,
)
from services.recording.layout import baseline_signals, robot_skeleton

if TYPE_CHECKING:
    pass

# ---------------------------------------------------------------------------------------------
# blueprint
# ---------------------------------------------------------------------------------------------

__all__ = [
    "blueprint_for",
    "read_entities",
]


_SIGNAL_VIEWS = (
    ("q", "q (rad)"),
    ("qd", "qd (rad/s)"),
    ("qdd", "qdd (rad/s²)"),
    ("jerk", "jerk (rad/s³)"),
    ("tau", "τ (N·m)"),
    ("power", "power (W)"),
)

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
    out.update((entity, set()) for entity, _ in baseline_signals(rec))
    for s in rec.optimization:  # the objectives of best / ideal / nadir: one entity each
        if s.group is not None:
            out.pop(s.path, None)
            out[s.group] = set()
    if rec.best is not None:
        skeleton = robot_skeleton(rec.best.poses)
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
