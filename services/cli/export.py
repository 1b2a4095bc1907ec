"""`legopt export`: the dashboard's downloads from the command line — the job list, a job's
front or history, a sweep's cell table — as CSV, JSON or Parquet, from a running service.

    legopt export jobs --status succeeded --kind path_tracking --format parquet
    legopt export front JOB --out front.csv
    legopt export history JOB --format json --out -      # to standard output
    legopt export cells SWEEP
"""

from __future__ import annotations

import re
import sys
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer

from services.cli.common import KeyOpt, UrlOpt, api_call, client, console, resolve_id

export_app = typer.Typer(
    help="Download the job list, a job's front or history, or a sweep's cells (CSV, JSON, "
    "Parquet).",
    no_args_is_help=True,
)


class Format(StrEnum):
    """File formats of the exports."""

    csv = "csv"
    json = "json"
    parquet = "parquet"


FormatOpt = Annotated[Format, typer.Option("--format", "-f", help="csv, json or parquet")]
OutOpt = Annotated[
    Path | None,
    typer.Option("--out", "-o", help="file to write ('-': standard output; default: the "
                 "server's file name in the current directory)"),
]  # fmt: skip


def _save(c: Any, path: str, params: dict[str, Any], out: Path | None) -> None:
    response = api_call(c._req, "GET", path, params=params)
    data = response.content
    if out is not None and str(out) == "-":
        sys.stdout.buffer.write(data)
        sys.stdout.buffer.flush()
        return
    if out is None:
        m = re.search(r'filename="?([^";]+)"?', response.headers.get("content-disposition", ""))
        out = Path(m.group(1) if m else Path(path).name)
    out.write_bytes(data)
    console.print(f"saved {out} ({len(data)} bytes)")


@export_app.command("jobs")
def export_jobs(
    format: FormatOpt = Format.csv,
    out: OutOpt = None,
    status: Annotated[
        list[str] | None, typer.Option("--status", help="only this status (repeatable)")
    ] = None,
    kind: Annotated[str | None, typer.Option(help="only this study kind")] = None,
    optimizer: Annotated[str | None, typer.Option(help="only this optimizer")] = None,
    robot: Annotated[str | None, typer.Option(help="only this robot")] = None,
    sweep: Annotated[str | None, typer.Option(help="only the jobs of this sweep")] = None,
    search: Annotated[str | None, typer.Option("--search", "-q", help="words to match")] = None,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Your job list (the dashboard's filters), newest first."""
    params = {"format": format.value, "status": status or None, "kind": kind,
              "optimizer": optimizer, "robot": robot, "sweep_id": sweep, "q": search}  # fmt: skip
    with client(url, key) as c:
        _save(c, "/export/jobs", {k: v for k, v in params.items() if v}, out)


@export_app.command("front")
def export_front(
    job: Annotated[str, typer.Argument(metavar="JOB", help="job id or prefix")],
    format: FormatOpt = Format.csv,
    out: OutOpt = None,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """A job's final Pareto front: index, objectives, each point's metrics (metric.<name>),
    decision variables."""
    with client(url, key) as c:
        _, full = resolve_id(c, job)
        _save(c, f"/jobs/{full}/front/export", {"format": format.value}, out)


@export_app.command("history")
def export_history(
    job: Annotated[str, typer.Argument(metavar="JOB", help="job id or prefix")],
    format: FormatOpt = Format.csv,
    out: OutOpt = None,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """A job's progress per generation: evaluations, best of each objective so far,
    hypervolume, time (several objectives: each front's minimum and its compromise point)."""
    with client(url, key) as c:
        _, full = resolve_id(c, job)
        _save(c, f"/jobs/{full}/history/export", {"format": format.value}, out)


@export_app.command("cells")
def export_cells(
    sweep: Annotated[str, typer.Argument(metavar="SWEEP", help="sweep id or prefix")],
    format: FormatOpt = Format.csv,
    out: OutOpt = None,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """A sweep's cells: swept values, job counts, mean ± sd of every objective and metric."""
    with client(url, key) as c:
        _, full = resolve_id(c, sweep, field="SWEEP", collections=("sweeps",))
        _save(c, f"/sweeps/{full}/cells/export", {"format": format.value}, out)


__all__ = ["export_app"]
