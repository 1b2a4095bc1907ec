"""The verdict and the task in the CLI's result blocks (:mod:`services.cli.display`): the
``INFEASIBLE: …`` line, the rules that derived the task from the robot, why a change in % is
withheld, a solution's feasibility as a table cell."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rich.text import Text

from legcore.studies.metric_names import baseline_name, metric_name
from services.verdict import Verdict, violations_text

__all__ = ["change_withheld", "gap_line", "task_line", "task_lines", "verdict_cell",
           "verdict_line"]


def verdict_line(verdict: Verdict) -> Text | None:
    """``INFEASIBLE: <each violation with its amount and unit>`` (bold red) when the optimum
    violates a constraint, ``feasible: …`` (green) when it was checked and meets them all,
    None when it was not checked (a result stored before the service checked)."""
    if verdict.feasible is None:
        return None
    if verdict.feasible:
        return Text("  feasible: the optimum meets every constraint", style="green")
    what = violations_text(verdict.violations) or "the optimum violates a constraint"
    return Text(f"  INFEASIBLE: {what}", style="bold red")


def gap_line(gap: Mapping[str, Any] | None) -> Text | None:
    """``gap to the physical minimum (TOPP-RA …): +0.93 % (3.391 s vs 3.360 s)`` for a
    single-objective optimum with a reference, ``no optimality gap: <why>`` (dim) without one,
    None for a result stored without it or a multi-objective one."""
    if not gap:
        return None
    ref, pct = gap.get("reference"), gap.get("pct")
    if ref is None:
        if gap.get("objective") is None:  # several objectives: the front speaks for itself
            return None
        return Text(f"  no optimality gap: {gap.get('reason') or 'no reference'}", style="dim")
    m = metric_name(str(gap.get("objective")), None)
    unit = f" {m.unit}" if m.unit else ""
    how = f"{gap.get('kind') or 'reference'}"
    words = f"{pct:+.3g} %" if isinstance(pct, int | float) else "—"
    value = gap.get("value")
    shown = (f" ({float(value):.6g}{unit} vs {float(ref):.6g}{unit}"
             f"{', ' + str(gap['method']) if gap.get('method') else ''})"
             if isinstance(value, int | float) else "")
    return Text(f"  gap to the {how}: {words}{shown}", style="magenta")


def _rules(task: Mapping[str, Any] | None) -> dict[str, str]:
    rules = (task or {}).get("rules")
    return {str(k): str(r) for k, r in rules.items()} if isinstance(rules, dict) else {}


def task_line(task: Mapping[str, Any] | None) -> Text | None:
    """One line on the task a job ran (``{params, rules, preset}``): the rule that derived
    each robot-relative value (``task derived from the robot: depth: 0.6 × leg length …;
    step_length: …``; on the paper's robot, what its preset leaves to the robot), cut at the
    console's width (:func:`task_lines` has them whole); None when nothing was derived (every
    value given, or a result stored without its task)."""
    rules = _rules(task)
    if not rules:
        return None
    head = ("  task: the paper's settings; the rest derived from the robot: "
            if (task or {}).get("preset") else "  task derived from the robot: ")
    text = head + "; ".join(f"{k}: {r}" for k, r in rules.items())
    return Text(text, style="cyan", no_wrap=True, overflow="ellipsis")


def task_lines(task: Mapping[str, Any] | None) -> list[Text]:
    """The task in full: the paper whose settings it used, then one line per derived value."""
    out = []
    preset = (task or {}).get("preset")
    if preset:
        words = f"  task: what the spec leaves out is the paper's — {preset}"
        out.append(Text(words, style="cyan"))
    rules = _rules(task)
    if rules:
        out.append(Text("  task derived from the robot:", style="cyan"))
        out.extend(Text(f"    {k}: {r}", style="cyan") for k, r in rules.items())
    return out


def change_withheld(
    optimum: Verdict, start: str | None, baselines: Mapping[str, Verdict]
) -> str | None:
    """Why no change in % is shown between the ``start`` baseline and the optimum (None: it
    is): only two solutions that both meet every constraint are compared."""
    if optimum.feasible is False:
        return "the optimum is infeasible"
    ref = baselines.get(start) if start is not None else None
    if ref is None or ref.feasible is not False:
        return None
    why = violations_text(ref.violations)
    return f"the start ({baseline_name(start or '')}) is infeasible" + (f": {why}" if why else "")


def verdict_cell(verdict: Verdict) -> Text:
    """yes (green) / NO (red) / — (not checked) for a solution's feasibility."""
    if verdict.feasible is None:
        return Text("—")
    return Text("yes", style="green") if verdict.feasible else Text("NO", style="bold red")
