"""What the CLI prints about a result: one compact block per study, or the full tables.

Both views read a :class:`ResultView` — a finished job's objectives, metrics, baselines and
per-joint table, from the API's result document (:meth:`ResultView.from_api`) or from an
in-process ``RunResult.to_dict()`` (:meth:`ResultView.from_run`). Names and units come from
`legcore.studies.metric_names`; the papers' own numbers from
``examples/papers/paper_numbers.yaml``.

Conventions: numbers have 4 significant digits; a quantity the user maximises is shown
positive (``neg_score`` → ``score``); a metric that repeats another (``same_as``) is not shown.

Feasibility is part of the answer: an optimum that violates a constraint is announced as
``INFEASIBLE: <each violation, its amount and unit>`` before any number; a change in % is
computed only between feasible solutions (a start or optimum that violates a constraint gets
"—" and the reason); the paper's numbers appear only for the paper's robot and settings
(``services.paper_numbers``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from rich import box
from rich.console import Group, RenderableType
from rich.table import Table
from rich.text import Text

from legcore.studies.metric_names import (
    STUDY_DISPLAY,
    MetricName,
    baseline_name,
    display_objective,
    joint_row_name,
    metric_name,
)
from services.cli.display_verdict import (
    change_withheld,
    gap_line,
    task_line,
    task_lines,
    verdict_cell,
    verdict_line,
)
from services.cli.result_view import ResultView, fmt, label
from services.paper_numbers import paper_entry
from services.verdict import Verdict

__all__ = ["full_tables", "joint_table", "summary_block"]


# ------------------------------------------------------------------ the compact block
def _change(start: Any, end: Any, m: MetricName | None = None) -> str:
    """Relative change in % (empty for flags, missing values or a zero start)."""
    if m is not None and (m.kind == "flag" or m.unit == "%"):
        return ""
    if not isinstance(start, int | float) or not isinstance(end, int | float):
        return ""
    if start == 0 or not math.isfinite(start) or not math.isfinite(end):
        return ""
    return f"{100.0 * (end - start) / abs(start):+.3g} %"


def _pair(a: Any, b: Any, m: MetricName, single: bool = False) -> str:
    """``a → b``, or ``b`` alone when ``single``."""
    return fmt(b, m) if single else f"{fmt(a, m)} → {fmt(b, m)}"


def summary_block(
    view: ResultView, *, title: str, spec: dict[str, Any] | None = None
) -> RenderableType:
    """One study in a few lines: the verdict (``INFEASIBLE: …`` first when the optimum
    violates a constraint), the task's derived values, what was optimised, start → optimum of
    the objectives and headline metrics with the change in % (only between feasible
    solutions, else "—" and the reason), ours beside the paper's numbers (its symbol in
    parentheses; only on the paper's robot and settings)."""
    study = STUDY_DISPLAY.get(view.kind)
    paper = paper_entry(spec, view.task)
    start = (paper.start if paper and paper.start else None) or (study.start if study else None)
    if start not in view.baselines:
        start = None
    lines: list[RenderableType] = [Text.from_markup(title)]
    for extra_line in (verdict_line(view.verdict), gap_line(view.gap), task_line(view.task)):
        if extra_line is not None:
            lines.append(extra_line)
    no_change = change_withheld(view.verdict, start, view.baseline_verdicts)
    what = study.task if study else "the decision variables"
    head = f"  optimised: {what}"
    if start:
        head += f"; start = {baseline_name(start)}"
    if view.multi_objective:
        size = "?" if view.front_size is None else str(view.front_size)
        head += f"; Pareto front of {size} points, optimum = its knee point"
    lines.append(Text(head))
    prows = {r.metric: r for r in paper.rows} if paper else {}
    notes: list[str] = []
    rows: list[tuple[str, MetricName, Any]] = list(view.shown_objectives())
    shown = {k for k, _, _ in rows}
    extra = [k for k in (study.headline if study else ()) if k not in shown]
    extra += [k for k in prows if k not in shown and k not in extra]
    for k in extra:
        v = view.value(k)
        if v is not None:
            rows.append((k, metric_name(k, view.kind), v))
    cells: list[tuple[str, str, str, str]] = []
    for i, (key, m, v) in enumerate(rows):
        name = label(m)
        if i < len(view.objective_names):
            name += " — maximised" if m.sense == "max" else " — minimised"
        pr = prows.get(key)
        symbol = pr.symbol(view.kind) if pr else m.paper
        if symbol:
            name += f" (paper: {symbol})"
        at_opt = bool(pr and pr.at_optimum)
        s = None if at_opt or not start else view.value(key, start)
        ours = _pair(s, v, m, single=at_opt or not start)
        paper_txt = ""
        if pr is not None:
            paper_txt = (
                "not printed" if pr.start is None and pr.optimum is None
                else _pair(pr.start, pr.optimum, m, single=at_opt)
            )  # fmt: skip
            if pr.note:
                notes.append(f"{m.label}: {pr.note}")
            change = _change(pr.start, pr.optimum, m)
            if change:  # one word: kept on one line where the column wraps
                paper_txt += "  (" + change.replace(" ", "") + ")"
        if m.note:
            notes.append(f"{m.label}: {m.note}")
        change = _change(s, v, m)
        if no_change and change:
            change = "—"
        cells.append(("  " + name, ours, change, paper_txt))
    lines.append(_summary_table(cells, start is not None, paper.source if paper else None))
    if no_change:
        lines.append(Text(f"  change: — because {no_change}", style="yellow"))
    earned = earned_line(view)
    if earned:
        lines.append(Text(earned))
    if paper and paper.note:
        notes.insert(0, paper.note)
    lines.extend(Text(f"  note — {n}", style="dim") for n in notes)
    return Group(*lines)


def _summary_table(
    cells: Sequence[tuple[str, str, str, str]], has_start: bool, source: str | None
) -> Table:
    """The summary's rows: quantity, ours (start → optimum), change, the paper's numbers. Our
    numbers and the change are never cut: on a narrow terminal the quantity's name and the
    paper's column wrap instead (80 columns keep every number)."""
    t = Table(box=box.SIMPLE_HEAD, show_edge=False, pad_edge=False, padding=(0, 1))
    ours_head = "start → optimum" if has_start else "optimum"
    t.add_column("  quantity", overflow="fold", ratio=3)
    t.add_column(ours_head, justify="right", no_wrap=True,
                 min_width=max([len(ours_head), *(len(c[1]) for c in cells)]))  # fmt: skip
    t.add_column("change", justify="right", no_wrap=True,
                 min_width=max([len("change"), *(len(c[2]) for c in cells)]))  # fmt: skip
    t.add_column(f"paper ({source})" if source else "paper", overflow="fold", ratio=2)
    for row in cells:
        t.add_row(*row)
    return t


def earned_line(view: ResultView) -> str:
    """What the optimiser earned (single objective): its initial population's best → the
    optimum, and the solution the encoding gives with no search, when there is one."""
    st = view.start
    if not st or len(st.get("objectives") or []) != 1:
        return ""
    row = st["objectives"][0]
    key, opt = display_objective(row["objective"], row["optimum"])
    m = metric_name(key, view.kind)
    parts = []
    if row.get("initial") is not None:
        _, ini = display_objective(row["objective"], row["initial"])
        infeasible = " (infeasible)" if (st.get("initial") or {}).get("cv", 0) > 0 else ""
        parts.append(f"initial population's best {fmt(ini, m)}{infeasible} → {fmt(opt, m)}")
    free = st.get("free")
    if free and row.get("free") is not None:
        _, fv = display_objective(row["objective"], row["free"])
        infeasible = " (infeasible)" if free.get("cv", 0) > 0 else ""
        same = abs(row["free"] - row["optimum"]) <= 1e-9 * max(1.0, abs(row["optimum"]))
        tail = ": the optimum is that solution" if same and not infeasible else ""
        parts.append(f"{free['what']}, with no search, gives {fmt(fv, m)}{infeasible}{tail}")
    if not parts:
        return ""
    return f"  optimiser earned ({key}): " + "; ".join(parts)


# ------------------------------------------------------------------ the full tables
def full_tables(
    view: ResultView, *, title: str, spec: dict[str, Any] | None = None
) -> list[RenderableType]:
    """Every metric of the optimum beside every baseline (and the paper's start and optimum
    where it prints them), the per-joint table, the front size."""
    t = Table(box=box.SIMPLE_HEAD)
    t.add_column("quantity")
    t.add_column("optimum", justify="right")
    cols = list(view.baselines)
    for b in cols:
        t.add_column(baseline_name(b), justify="right", overflow="fold")
    paper = paper_entry(spec, view.task)
    prows = {r.metric: r for r in paper.rows if r.start is not None or r.optimum is not None} \
        if paper else {}  # fmt: skip
    if prows:
        t.add_column("paper: start", justify="right")
        t.add_column("paper: optimum", justify="right")

    def cells(key: str, m: MetricName) -> list[str]:
        out = [fmt(view.value(key, b), m) for b in cols]
        if prows:
            pr = prows.get(key)
            out += ["", ""] if pr is None else [fmt(pr.start, m) if pr.start is not None
                                                else "", fmt(pr.optimum, m)]  # fmt: skip
        return out

    blank = [""] * (len(cols) + (2 if prows else 0))
    checked = [view.verdict, *(view.baseline_verdicts.get(b, Verdict()) for b in cols)]
    if any(v.feasible is not None for v in checked):
        t.add_row("meets every constraint", *[verdict_cell(v) for v in checked],
                  *blank[len(cols):])  # fmt: skip
    for key, m, v in view.shown_objectives():
        goal = "maximised" if m.sense == "max" else "minimised"
        t.add_row(f"{label(m)} — {goal}", fmt(v, m), *cells(key, m))
    for key, m in view.shown_metrics():
        t.add_row(label(m), fmt(view.value(key), m), *cells(key, m))
    opt = view.optimizer
    if opt:
        t.add_row("generations / evaluations", f"{opt.get('n_gen')} / {opt.get('n_evals')}",
                  *blank)  # fmt: skip
        t.add_row("optimiser time (s)", fmt(opt.get("elapsed_s")), *blank)
    out: list[RenderableType] = [Text.from_markup(title), *task_lines(view.task), t]
    if paper and prows:
        out.append(Text(f"paper: {paper.source}", style="dim"))
    if view.table:
        out.append(joint_table(view.table))
    if view.multi_objective:
        size = "?" if view.front_size is None else str(view.front_size)
        names = ", ".join(label(m) for _, m, _ in view.shown_objectives())
        out.append(Text(f"Pareto front: {size} points ({names}); the optimum is its knee point"))
    return out


def joint_table(rows: list[dict[str, Any]], title: str = "per joint") -> Table:
    """Rows ``{metric, unit, values: [...], total}`` (seed 000 Table 2 style)."""
    n = max((len(r.get("values") or []) for r in rows), default=0)
    jt = Table(title=title, box=box.SIMPLE_HEAD)
    jt.add_column("quantity (symbol)")
    jt.add_column("unit")
    for i in range(n):
        jt.add_column(f"joint {i + 1}", justify="right")
    jt.add_column("total", justify="right")
    for row in rows:
        vals = list(row.get("values") or [])
        cells = [fmt(v) for v in vals] + [""] * (n - len(vals))
        total = row.get("total")
        jt.add_row(joint_row_name(str(row.get("metric", ""))), str(row.get("unit", "")), *cells,
                   "" if total is None else fmt(total))  # fmt: skip
    return jt
