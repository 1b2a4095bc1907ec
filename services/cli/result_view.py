"""A finished job as the CLI reads it (:class:`ResultView`) and how it writes one value
(:func:`fmt`: 4 significant digits, yes/no for flags, "—" for a missing value) and one name
(:func:`label`: ``name (unit)``)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

from legcore.studies.metric_names import MetricName, display_objective, metric_name
from services.verdict import Verdict

__all__ = ["ResultView", "fmt", "label"]


def fmt(v: Any, m: MetricName | None = None) -> str:
    """4 significant digits; yes/no for flags; "—" for missing or non-finite values."""
    if v is None or isinstance(v, str):
        return "—" if v is None else v
    if isinstance(v, bool):
        return "yes" if v else "no"
    if m is not None and m.kind == "flag":
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    v = float(v)
    if not math.isfinite(v):
        return "—"
    if v == 0:
        return "0"
    return f"{v:.4g}"


def label(m: MetricName) -> str:
    """``name (unit)``."""
    return f"{m.label} ({m.unit})" if m.unit else m.label


def _dict_or_none(v: Any) -> dict[str, Any] | None:
    return v if isinstance(v, dict) else None


@dataclass
class ResultView:
    """A finished job as the CLI shows it (all values in the studies' units): the optimum's
    objectives and metrics, its verdict (``verdict``), the task it ran (``task``: parameters,
    the rules that derived them from the robot, the paper's preset), every baseline's metrics
    and verdict."""

    kind: str
    objective_names: list[str]
    objectives: dict[str, float | None]
    metrics: dict[str, Any]
    baselines: dict[str, dict[str, Any]]
    table: list[dict[str, Any]] = field(default_factory=list)
    optimizer: dict[str, Any] = field(default_factory=dict)
    front_size: int | None = None
    start: dict[str, Any] | None = None
    verdict: Verdict = field(default_factory=Verdict)
    baseline_verdicts: dict[str, Verdict] = field(default_factory=dict)
    task: dict[str, Any] | None = None
    gap: dict[str, Any] | None = None

    @classmethod
    def from_api(cls, kind: str, res: dict[str, Any], front_size: int | None = None) -> ResultView:
        """From ``GET /jobs/{id}/result`` (and the total of ``/pareto``)."""
        obj = res.get("objectives") or {}
        names = list(res.get("objective_names") or obj.get("names") or [])
        values = obj.get("values", {}) if isinstance(obj, dict) else {}
        if isinstance(values, list):
            values = dict(zip((display_objective(n, None)[0] for n in names), values,
                              strict=False))  # fmt: skip
        summary = res.get("summary") or {}
        baselines = res.get("baselines") or []
        verdicts: dict[str, Verdict] = {}
        if isinstance(baselines, list):
            verdicts = {b["name"]: Verdict.of(b.get("metrics"), b.get("feasible"),
                                              b.get("violations")) for b in baselines}  # fmt: skip
            baselines = {b["name"]: b.get("metrics") or {} for b in baselines}
        else:
            verdicts = {k: Verdict.of(v) for k, v in baselines.items()}
        # a stored baseline is the decoded solution: {x, objectives, metrics, table, extra}
        baselines = {
            k: v["metrics"] if isinstance(v.get("metrics"), dict) else v
            for k, v in baselines.items()
        }
        task = res.get("task") or summary.get("task")
        return cls(kind, names, dict(values), dict(res.get("metrics") or {}), dict(baselines),
                   list(summary.get("table") or []), dict(summary.get("optimizer") or {}),
                   front_size, summary.get("start"),
                   Verdict.of(None, res.get("feasible"), res.get("violations")), verdicts,
                   task if isinstance(task, dict) else None,
                   _dict_or_none(res.get("gap") or summary.get("gap")))  # fmt: skip

    @classmethod
    def from_run(cls, doc: dict[str, Any]) -> ResultView:
        """From ``RunResult.to_dict()`` (``legopt run``)."""
        best = doc["best"]
        baselines = doc.get("baselines", {})
        task = doc.get("task")
        return cls(
            doc["spec"]["problem"]["kind"],
            list(doc["objective_names"]),
            dict(best["objectives"]),
            dict(best["metrics"]),
            {k: v["metrics"] for k, v in baselines.items()},
            list(best.get("table") or []),
            dict(doc.get("optimizer") or {}),
            len(doc.get("pareto") or []),
            doc.get("start"),
            Verdict.of(None, doc.get("feasible"), doc.get("violations")),
            {k: Verdict.of(v) for k, v in baselines.items()},
            task if isinstance(task, dict) else None,
            _dict_or_none(doc.get("gap")),
        )

    # -------------------------------------------------------------- rows
    def shown_objectives(self) -> list[tuple[str, MetricName, float | None]]:
        """``(key, name, value)`` per objective, maximised ones positive, with their sense."""
        out = []
        for n in self.objective_names:
            key, _ = display_objective(n, None)
            m = metric_name(key, self.kind)
            m = dataclasses.replace(m, sense="max" if n != key else "min", same_as=None)
            value = self.objectives.get(key, self.objectives.get(n))
            out.append((key, m, value))
        return out

    def shown_metrics(self) -> list[tuple[str, MetricName]]:
        """Metric keys of the best and the baselines, without the objectives and repeats."""
        skip = {k for k, _, _ in self.shown_objectives()}
        keys: list[str] = []
        for source in (self.metrics, *self.baselines.values()):
            keys.extend(k for k in source if k not in keys)
        out = []
        for k in keys:
            m = metric_name(k, self.kind)
            if k in skip or m.same_as is not None:
                continue
            out.append((k, m))
        return out

    def value(self, key: str, baseline: str | None = None) -> Any:
        """The best's (or a baseline's) value of ``key``: a metric, an objective, or the
        metric that repeats that objective under another key."""
        source = self.metrics if baseline is None else self.baselines.get(baseline, {})
        if key in source:
            return source[key]
        if baseline is None and key in self.objectives:
            return self.objectives[key]
        for k, v in source.items():
            if metric_name(k, self.kind).same_as == key:
                return v
        return None

    @property
    def multi_objective(self) -> bool:
        return len(self.objective_names) > 1
