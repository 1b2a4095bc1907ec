"""What `legopt status` prints: one line per job, a block for one job, a row per job of a
sweep; and the title line of a study's summary."""

from __future__ import annotations

from datetime import datetime
from typing import Any

from rich import box
from rich.table import Table
from rich.text import Text

from services.cli.objectives import best_text, objective_names_of
from services.cli.result_view import fmt
from services.verdict import violations_text

__all__ = [
    "job_block",
    "job_title",
    "jobs_table",
    "progress_text",
    "short",
    "status_text",
    "sweep_table",
]


def short(job_id: str) -> str:
    """The first 8 characters of an id (what the tables print; any prefix is accepted)."""
    return job_id[:8]


def _robot(spec: dict[str, Any]) -> str:
    robot = spec.get("robot")
    if isinstance(robot, dict):
        return f"{robot.get('name', '?')} (inline {robot.get('kind', 'dh')})"
    return str(robot) if robot else "the study's default"


def _optimiser(job: dict[str, Any]) -> str:
    opt = (job.get("spec") or {}).get("optimizer") or {}
    return str(opt.get("kind", "the study's default")).upper() if opt else "the study's default"


def _time(ts: str | None) -> str:
    if not ts:
        return "—"
    return datetime.fromisoformat(ts).strftime("%Y-%m-%d %H:%M:%S")


def _seconds(a: str | None, b: str | None) -> str:
    if not a or not b:
        return ""
    dt = (datetime.fromisoformat(b) - datetime.fromisoformat(a)).total_seconds()
    return f" ({dt:.1f} s)"


def status_text(job: dict[str, Any], suffix: str = "") -> Text:
    """The job's status, ``succeeded (infeasible)`` in red when its optimum violates a
    constraint (the run completed; the answer is infeasible), ``succeeded`` in green when it
    was checked feasible."""
    status = str(job.get("status", ""))
    feasible = job.get("feasible")
    if status == "succeeded" and feasible is False:
        return Text(f"succeeded (infeasible){suffix}", style="bold red")
    if status == "succeeded" and feasible is True:
        return Text(f"succeeded{suffix}", style="green")
    return Text(status + suffix)


def progress_text(job: dict[str, Any]) -> str:
    g, total = job.get("generation", 0), job.get("total_generations", 0)
    return f"{g}/{total}" if total else str(g)


def job_block(job: dict[str, Any]) -> Table:
    """`legopt status JOB`: the job in a dozen lines (no spec; `--json` has it)."""
    spec = job.get("spec") or {}
    kind = job.get("kind") or (spec.get("problem") or {}).get("kind", "")
    t = Table(box=None, show_header=False, padding=(0, 2))
    t.add_column(style="bold")
    t.add_column()
    t.add_row("job", job["id"])
    if job.get("name"):
        t.add_row("name", job["name"])
    t.add_row("kind", kind)
    t.add_row("robot", _robot(spec))
    t.add_row("optimiser", _optimiser(job))
    cancel = " (cancel requested)" if job.get("cancel_requested") else ""
    t.add_row("status", status_text(job, f"{cancel}, attempt {job.get('attempts', 0)}"))
    if job.get("status") == "succeeded" and job.get("feasible") is False:
        what = violations_text(job.get("violations")) or "the optimum violates a constraint"
        t.add_row("verdict", Text(f"INFEASIBLE: {what}", style="bold red"))
    elif job.get("status") == "succeeded" and job.get("feasible") is True:
        t.add_row("verdict", Text("feasible: the optimum meets every constraint", style="green"))
    pct = f" ({100 * job.get('progress', 0):.0f} %)" if job.get("total_generations") else ""
    t.add_row("progress", f"{progress_text(job)} generations{pct}")
    t.add_row("best", best_text(objective_names_of(job), job.get("best_objective")) or "—")
    t.add_row("created", _time(job.get("created_at")))
    t.add_row("started", _time(job.get("started_at")))
    t.add_row("finished", _time(job.get("finished_at"))
              + _seconds(job.get("started_at"), job.get("finished_at")))  # fmt: skip
    if job.get("sweep_id"):
        t.add_row("sweep", job["sweep_id"])
    if job.get("error"):
        t.add_row("error", str(job["error"]))
    for w in job.get("warnings") or []:
        t.add_row("warning", str(w))
    return t


def jobs_table(page: dict[str, Any]) -> Table:
    """`legopt status`: one line per job, newest first."""
    t = Table(title=f"latest {len(page['items'])} of {page['total']} jobs", box=box.SIMPLE_HEAD)
    for col in ("id", "name / kind", "status", "progress", "best", "created"):
        t.add_column(col)
    for j in page["items"]:
        kind = j.get("kind") or ""
        best = best_text(objective_names_of(j), j.get("best_objective"))
        t.add_row(short(j["id"]), j.get("name") or kind, status_text(j), progress_text(j),
                  best or "—", _time(j.get("created_at")))  # fmt: skip
    return t


def sweep_table(sw: dict[str, Any]) -> Table:
    """A sweep: one row per job with the value of each swept path, status and objectives."""
    table = sw.get("table") or {}
    rows = table.get("items", []) if isinstance(table, dict) else list(table)
    counts = ", ".join(f"{n} {s}" for s, n in (sw.get("counts") or {}).items() if n)
    t = Table(title=f"sweep {sw.get('id', '')} — {sw.get('state', '')} ({counts})",
              box=box.SIMPLE_HEAD)  # fmt: skip
    columns = [str(c) for c in sw.get("columns") or []]
    names = list(sw.get("objective_names") or [])
    t.add_column("job")
    for col in columns:
        t.add_column(col, justify="right")
    t.add_column("status")
    t.add_column("progress", justify="right")
    t.add_column("best")
    for r in rows:
        over = r.get("overrides") or {}
        objs = r.get("objectives")
        if isinstance(objs, dict):
            best = ", ".join(f"{k} {fmt(v)}" for k, v in objs.items())
        else:
            best = best_text(names, r.get("best_objective"))
        prog = r.get("progress")
        cells = [fmt(over.get(c)) for c in columns]
        t.add_row(short(str(r.get("job_id", ""))), *cells, status_text(r),
                  "" if prog is None else f"{100 * prog:.0f} %", best or "—")  # fmt: skip
    return t


def job_title(job: dict[str, Any], label: str, res: dict[str, Any] | None = None) -> str:
    """``label — kind · robot · optimiser · N generations · T s · job 1234abcd``."""
    spec = job.get("spec") or {}
    kind = job.get("kind") or (spec.get("problem") or {}).get("kind", "")
    opt = ((res or {}).get("summary") or {}).get("optimizer") or {}
    parts = [kind, _robot(spec), str(opt.get("kind") or _optimiser(job)).upper()]
    if opt.get("n_gen") is not None:
        parts.append(f"{opt['n_gen']} generations")
    if opt.get("elapsed_s") is not None:
        parts.append(f"{opt['elapsed_s']:.1f} s")
    parts.append(f"job {short(job['id'])}")
    return f"[bold]{label}[/] — " + " · ".join(parts)
