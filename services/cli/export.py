"""`legopt export`: the dashboard's downloads from the command line — the job list, a job's
front or history, a sweep's cell table or its jobs one row each — as CSV, JSON or Parquet, from
a running service. Ids and ``--sweep`` take a prefix (unknown or ambiguous: exit 2 naming it);
a ``--robot`` that names no robot is exit 2 too (the API's 422). Without ``--out`` the file is
saved under the server's name, ``legopt-<what>-<id8>.<format>`` (the job list:
``legopt-jobs.<format>``).

    legopt export jobs --status succeeded --kind path_tracking --format parquet
    legopt export jobs --sweep 2253                     # legopt-jobs.csv
    legopt export front JOB --out front.csv
    legopt export history JOB --format json --out -      # to standard output
    legopt export cells SWEEP                           # legopt-cells-<id8>.csv
    legopt export sweep-jobs SWEEP --format parquet      # legopt-sweep-jobs-<id8>.parquet
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
    help="Download the job list, a job's front or history, or a sweep's cells or jobs (CSV, "
    "JSON, Parquet), as legopt-<what>-<id8>.<format>.",
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
                 "server's file name, legopt-<what>-<id8>.<format>, in the current directory)"),
]  # fmt: skip


def _save(
    c: Any, path: str, params: dict[str, Any], out: Path | None, what: str, ident: str | None
) -> None:
    """GET ``path`` and write the file to ``out`` (``-``: standard output; None: the name the
    server gives in the current directory, else the same pattern's
    ``legopt-<what>-<first 8 of ident>.<format>``)."""
    response = api_call(c._req, "GET", path, params=params)
    data = response.content
    if out is not None and str(out) == "-":
        sys.stdout.buffer.write(data)
        sys.stdout.buffer.flush()
        return
    if out is None:
        from services.api.export_formats import filename

        m = re.search(r'filename="?([^";]+)"?', response.headers.get("content-disposition", ""))
        name = Path(m.group(1)).name if m else ""  # in the current directory, whatever it says
        out = Path(name or filename(what, params["format"], ident))
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
    robot: Annotated[
        str | None, typer.Option(help="only this robot (catalog, yours or your jobs')")
    ] = None,
    sweep: Annotated[
        str | None, typer.Option(help="only the jobs of this sweep (id or prefix)")
    ] = None,
    search: Annotated[
        str | None,
        typer.Option("--search", "-q", help="words to match (one of 3 characters or more)"),
    ] = None,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Your job list (the dashboard's filters), newest first; the best value so far of each
    job's first objective with its quantity and unit. An unknown --sweep prefix or --robot is
    an error (exit 2), not an empty file."""
    with client(url, key) as c:
        sweep_id = None
        if sweep is not None:
            _, sweep_id = resolve_id(c, sweep, field="--sweep", collections=("sweeps",))
        params = {"format": format.value, "status": status or None, "kind": kind,
                  "optimizer": optimizer, "robot": robot, "sweep_id": sweep_id,
                  "q": search}  # fmt: skip
        _save(c, "/export/jobs", {k: v for k, v in params.items() if v}, out, "jobs", None)


def _export_one(
    ident: str,
    what: str,
    path: str,
    format: Format,
    out: Path | None,
    url: str | None,
    key: str | None,
    *,
    sweep: bool = False,
) -> None:
    """Save the export ``path`` (``{}``: the full id of job — or, with ``sweep``, sweep —
    ``ident``, an id or prefix) as ``legopt-<what>-<id8>.<format>`` unless ``out``."""
    with client(url, key) as c:
        if sweep:
            _, full = resolve_id(c, ident, field="SWEEP", collections=("sweeps",))
        else:
            _, full = resolve_id(c, ident)
        _save(c, path.format(full), {"format": format.value}, out, what, full)


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
    _export_one(job, "front", "/jobs/{}/front/export", format, out, url, key)


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
    _export_one(job, "history", "/jobs/{}/history/export", format, out, url, key)


@export_app.command("cells")
def export_cells(
    sweep: Annotated[str, typer.Argument(metavar="SWEEP", help="sweep id or prefix")],
    format: FormatOpt = Format.csv,
    out: OutOpt = None,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """A sweep's cells: swept values, job counts, mean ± sd of every objective and metric."""
    _export_one(sweep, "cells", "/sweeps/{}/cells/export", format, out, url, key, sweep=True)


@export_app.command("sweep-jobs")
def export_sweep_jobs(
    sweep: Annotated[str, typer.Argument(metavar="SWEEP", help="sweep id or prefix")],
    format: FormatOpt = Format.csv,
    out: OutOpt = None,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """A sweep's jobs, one row each beside its cells: id, cell, swept values, seed, status,
    then each objective, hypervolume and metric of its result (SI units)."""
    path = "/sweeps/{}/jobs/export"
    _export_one(sweep, "sweep-jobs", path, format, out, url, key, sweep=True)


__all__ = ["export_app"]
