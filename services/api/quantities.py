"""Readable names and SI units of the objectives, metrics and decision variables the studies
report, for the dashboard's axes and tables: an adapter over
:mod:`legcore.studies.metric_names` (the one table of display names, shared with the CLI)."""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["describe", "describe_all"]


def describe(name: str, kind: str | None = None) -> dict[str, str]:
    """``{"name", "label", "unit", "axis", "sense"}`` of a result key of the study ``kind``:
    ``axis`` is the label with its unit in brackets, as the plots show it; ``sense`` is
    "min"/"max" when smaller/larger is better, else ""."""
    from legcore.studies.metric_names import metric_name

    m = metric_name(str(name), kind)
    axis = f"{m.label} [{m.unit}]" if m.unit else m.label
    return {"name": name, "label": m.label, "unit": m.unit, "axis": axis, "sense": m.sense}


def describe_all(names: Sequence[str], kind: str | None = None) -> list[dict[str, str]]:
    """:func:`describe` of each name, in order."""
    return [describe(n, kind) for n in names]
