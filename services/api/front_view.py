"""The final front of a job as the dashboard and ``legopt results`` read it (``GET
/jobs/{id}/front``): labelled objectives and variables, the points with their metrics, the
reported optimum's place, the baselines, the paper's numbers. Pure: the route reads the
records and hands them in."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from services.api.dashboard_schemas import (
    BaselineMark,
    FrontOut,
    FrontPointOut,
    PaperMark,
    PaperOut,
    PaperValue,
    Quantity,
    finite_or_none,
    quantities,
)
from services.api.schemas import objective_names
from services.store.records import (
    BaselineRecord,
    JobRecord,
    ParetoPointRecord,
    ResultRecord,
)

#: Per point index its metrics (or None), the state of the point metrics and a note.
PointMetrics = tuple[dict[int, Any], Any, str | None]


def front_out(
    job: JobRecord,
    spec: Any,
    points: Sequence[ParetoPointRecord],
    result: ResultRecord | None,
    baselines: Sequence[BaselineRecord],
    ref: Any,
    point_metrics_state: PointMetrics,
) -> FrontOut:
    """The front response of ``job`` from its stored records."""
    problem = spec.get("problem") if isinstance(spec, dict) else None
    kind = problem.get("kind") if isinstance(problem, dict) else None
    objectives = result.objectives if result is not None else None
    names = objective_names(objectives)
    if not names and points:
        names = [f"f{i + 1}" for i in range(len(points[0].objectives or []))]
    n_var = max((len(p.x or []) for p in points), default=0)
    best_index = reported_optimum_index(result, points, names)
    marks = [BaselineMark.from_record(b, names) for b in baselines]
    objective_quantities = quantities(names, kind)
    per_point, state, note = point_metrics_state
    # the result's order (as the job's metric table), then any only the points have
    keys = dict.fromkeys(result.metrics or {}) if result is not None else {}
    keys.update(dict.fromkeys(k for v in per_point.values() if v for k in v))
    metrics = list(keys)
    return FrontOut(
        job_id=job.id,
        status=job.status,
        objectives=objective_quantities,
        variables=[
            Quantity(name=f"x{i + 1}", label=f"x{i + 1}", unit="", axis=f"x{i + 1}")
            for i in range(n_var)
        ],
        metrics=quantities(metrics, kind),
        points=[
            FrontPointOut(
                index=p.index,
                objectives=[finite_or_none(v) for v in p.objectives or []],
                x=[finite_or_none(v) for v in p.x or []],
                metrics=per_point.get(p.index),
            )
            for p in points
        ],
        point_metrics=state,
        point_metrics_note=note,
        best_index=best_index,
        baselines=marks,
        hypervolume_ref=ref,
        paper=paper_numbers(spec, objective_quantities, kind, _task(result)),
    )


def _task(result: Any) -> Any:
    """The task a job ran (stored in its result's summary), or None."""
    summary = getattr(result, "summary", None)
    return summary.get("task") if isinstance(summary, dict) else None


def paper_numbers(
    spec: Any, objectives: list[Quantity], kind: str | None, task: Any = None
) -> PaperOut | None:
    """The paper's numbers for the job's case — only on the paper's robot with the paper's
    settings (``task``: the task the job ran, when known): per metric its start and optimum,
    and on the front its start / optimum where it printed every objective (none when an
    objective is maximised: the front holds what the optimiser minimises)."""
    from services.paper_numbers import paper_entry

    entry = paper_entry(spec if isinstance(spec, dict) else None, task)
    if entry is None:
        return None
    rows = {r.metric: r for r in entry.rows}
    metrics = {
        r.metric: PaperValue(
            symbol=r.symbol(kind),
            start=r.start,
            optimum=r.optimum,
            note=" ".join(r.note.split()),
        )
        for r in entry.rows
        if r.start is not None or r.optimum is not None
    }
    names = [q.name for q in objectives]
    senses = [q.sense for q in objectives]
    marks = []
    for label, pick in (("paper's start", "start"), ("paper's optimum", "optimum")):
        values = [getattr(rows[n], pick) if n in rows else None for n in names]
        numbers = [float(v) for v in values if v is not None]
        if names and "max" not in senses and len(numbers) == len(names):
            marks.append(PaperMark(label=label, objectives=numbers))
    return PaperOut(source=entry.source, marks=marks, metrics=metrics)


def reported_optimum_index(
    result: ResultRecord | None, points: Sequence[ParetoPointRecord], names: Sequence[str]
) -> int | None:
    """The front index of the reported optimum: as the worker stored it (``best_index`` of the
    result summary; None there: the optimum is not on the front, e.g. refined), else — for a
    result stored before the worker kept it — the point nearest the optimum's objectives."""
    if result is None or not points:
        return None
    summary = result.summary if isinstance(result.summary, dict) else {}
    if "best_index" in summary:
        stored = summary["best_index"]
        known = {p.index for p in points}
        return stored if isinstance(stored, int) and stored in known else None
    objectives = result.objectives
    if not isinstance(objectives, dict):
        return None
    target = [finite_or_none((objectives.get("values") or {}).get(n)) for n in names]
    if not target or any(v is None for v in target):
        return None
    dist = [
        sum(
            (float(a or 0) - float(b or 0)) ** 2
            for a, b in zip(p.objectives, target, strict=False)
        )
        for p in points
    ]
    return points[dist.index(min(dist))].index
