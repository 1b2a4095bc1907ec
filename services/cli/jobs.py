"""`legopt submit | status | results | cancel | delete | sweep | replay`: talk to a running service.

Every JOB (and SWEEP) argument takes a whole id or any unambiguous prefix of one (the tables
print the first 8 characters); an unknown or ambiguous prefix exits 2 naming it.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from services.cli.common import (
    KeyOpt,
    UrlOpt,
    api_call,
    app,
    client,
    console,
    load_spec_file,
    resolve_id,
)
from services.cli.display import full_tables, summary_block
from services.cli.objectives import best_text, objective_names_of
from services.cli.result_view import ResultView
from services.cli.views import job_block, job_title, jobs_table, short, sweep_table

__all__ = ["follow", "print_job_result", "short", "sweep_cancelled_text"]

JobArg = Annotated[str, typer.Argument(metavar="JOB", help="job id or an unambiguous prefix")]


# ------------------------------------------------------------------ commands
@app.command()
def submit(
    spec_path: Annotated[Path, typer.Argument(metavar="SPEC", help="job spec, YAML or JSON")],
    wait: Annotated[bool, typer.Option("--wait", help="wait and print the result")] = False,
    verbose: Annotated[
        bool, typer.Option("--verbose", "-v", help="with --wait: every metric and baseline")
    ] = False,
    quiet: Annotated[
        bool, typer.Option("--quiet", "-q", help="print the job id only (for scripts)")
    ] = False,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Submit a job spec to the service; with --wait, follow it and print its summary."""
    data = load_spec_file(spec_path)
    with client(url, key) as c:
        job = api_call(c.submit, data)
        if quiet:
            final = api_call(c.wait, job["id"]) if wait else job
            print(job["id"])
            if wait and final["status"] != "succeeded":
                raise typer.Exit(code=1)
            return
        console.print(f"job {job['id']} {job['status']}")
        if wait:
            final = follow(c, [job], [spec_path.stem])[0]
            print_job_result(c, final, label=spec_path.stem, verbose=verbose)
            if final["status"] != "succeeded":
                raise typer.Exit(code=1)


@app.command()
def status(
    target: Annotated[
        str | None,
        typer.Argument(metavar="ID", help="job or sweep id or prefix (omitted: latest jobs)"),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="the full record as JSON")] = False,
    limit: Annotated[int, typer.Option(min=1, max=1000, help="jobs listed")] = 20,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """A line per job of the latest ones; or one job (kind, robot, optimiser, status, progress,
    best, times); or one sweep (a row per job)."""
    with client(url, key) as c:
        if target is None:
            page = api_call(c.jobs, limit=limit)
            if as_json:
                console.print_json(data=page)
                return
            console.print(jobs_table(page))
            return
        col, full = resolve_id(c, target, field="ID", collections=("jobs", "sweeps"))
        if col == "sweeps":
            sw = api_call(c.get_sweep, full, limit=1000)
            if as_json:
                console.print_json(data=sw)
            else:
                console.print(sweep_table(sw))
            return
        job = api_call(c.job, full)
        if as_json:
            console.print_json(data=job)
        else:
            console.print(job_block(job))


@app.command()
def results(
    job_id: JobArg,
    as_json: Annotated[bool, typer.Option("--json", help="the stored result as JSON")] = False,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """A finished job: every metric beside every baseline, per-joint table, then its summary."""
    with client(url, key) as c:
        _, full = resolve_id(c, job_id)
        if as_json:
            console.print_json(data=api_call(c.result, full))
            return
        job = api_call(c.job, full)
        print_job_result(c, job, label=job.get("name") or short(full), verbose=True)
        if job["status"] != "succeeded":
            raise typer.Exit(code=1)


@app.command()
def cancel(
    ids: Annotated[list[str], typer.Argument(metavar="ID...", help="job or sweep ids or prefixes")],
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Cancel jobs, or every unfinished job of a sweep in one request (a running job stops
    after its current generation)."""
    with client(url, key) as c:
        targets = [resolve_id(c, i, field="ID", collections=("jobs", "sweeps")) for i in ids]
        for col, full in targets:
            if col == "sweeps":
                console.print(sweep_cancelled_text(full, api_call(c.cancel_sweep, full)))
                continue
            job = _cancel_one(c, full)
            state = job["status"]
            if job.get("_finished"):
                console.print(f"job {short(full)}: already finished ({state}), nothing to cancel")
                continue
            if state not in ("cancelled",) and job.get("cancel_requested"):
                state = "cancel requested (it stops after its current generation)"
            console.print(f"job {short(full)}: {state}")


@app.command()
def delete(
    ids: Annotated[list[str], typer.Argument(metavar="ID...", help="job or sweep ids or prefixes")],
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Delete finished jobs and everything stored for them (progress, front, result,
    recording), which frees storage quota; a sweep: every job of it, then the sweep. A queued
    or running job (or a sweep with one): cancel it first."""
    with client(url, key) as c:
        for given in ids:
            col, full = resolve_id(c, given, field="ID", collections=("jobs", "sweeps"))
            if col == "sweeps":
                api_call(c.delete_sweep, full)
                console.print(f"sweep {short(full)}: deleted with its jobs")
                continue
            api_call(c.delete_job, full)
            console.print(f"job {short(full)}: deleted")


def sweep_cancelled_text(sweep_id: str, answer: dict[str, Any]) -> str:
    """What ``POST /sweeps/{id}/cancel`` did, in a line."""
    done = [f"{answer.get('cancelled', 0)} cancelled"]
    if answer.get("stopping"):
        done.append(f"{answer['stopping']} stopping after their current generation")
    done.append(f"{answer.get('already_finished', 0)} already finished")
    return f"sweep {short(sweep_id)}: " + ", ".join(done)


def _cancel_or_none(c: Any, job_id: str) -> dict[str, Any] | None:
    """Cancel one job; ``None`` when it already finished (the API's 409)."""
    from services.client import ApiError

    try:
        return dict(c.cancel(job_id))
    except ApiError as exc:
        if exc.status == 409:
            return None
        raise


def _cancel_one(c: Any, job_id: str) -> dict[str, Any]:
    """Cancel one job. A job that finished meanwhile is not an error for the CLI (cancelling is
    idempotent): the answer is then its final state, marked ``_finished``."""
    job = api_call(_cancel_or_none, c, job_id)
    if job is None:
        job = dict(api_call(c.job, job_id))
        job["_finished"] = True
    return dict(job)


@app.command()
def sweep(
    sweep_path: Annotated[
        Path, typer.Argument(metavar="SWEEP", help="sweep doc: base + grid/list/seeds")
    ],
    wait: Annotated[bool, typer.Option("--wait", help="wait and print the table")] = False,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Submit a sweep (one job per grid point) and optionally wait for its aggregated table."""
    doc = load_spec_file(sweep_path)
    with client(url, key) as c:
        sw = api_call(c.sweep, doc)
        ids = list(sw.get("job_ids", []))
        console.print(f"sweep {sw['id']}: {len(ids)} jobs")
        if wait and ids:
            jobs = [{"id": i} for i in ids]
            follow(c, jobs, [f"job {k + 1}" for k in range(len(ids))])
            console.print(sweep_table(api_call(c.get_sweep, sw["id"], limit=1000)))


@app.command()
def replay(
    target: Annotated[str, typer.Argument(metavar="JOB", help="job id or prefix, or a .rrd file")],
    save: Annotated[
        Path | None, typer.Option("--save", help="save the recording here (no viewer unless --web)")
    ] = None,
    web: Annotated[bool, typer.Option("--web", help="serve the web viewer on localhost")] = False,
    port: Annotated[int, typer.Option(help="web viewer port (0: a free one)")] = 0,
    point: Annotated[
        int | None,
        typer.Option("--point", min=0, help="front point K of the job (recording made on demand)"),
    ] = None,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Open a job's Rerun recording in the viewer (the web viewer with --web), or --save it;
    with --point K, the recording of the K-th point of its Pareto front. Without --save the
    download goes to a temporary file, removed when the viewer stops."""
    import signal
    import tempfile

    from services.recording import replay

    path = Path(target)
    scratch: tempfile.TemporaryDirectory[str] | None = None
    if not path.exists():
        with client(url, key) as c:
            _, full = resolve_id(c, target)
            if point is None:
                data = api_call(c.recording, full)
            else:
                data = api_call(c.point_recording, full, point)
        name = f"{full}.rrd" if point is None else f"{full}-point-{point}.rrd"
        if save is None:
            scratch = tempfile.TemporaryDirectory(prefix="legopt-replay-")
            path = Path(scratch.name) / name
        else:
            path = save
        path.write_bytes(data)
        if save is not None:
            console.print(f"saved {path} ({len(data)} bytes)")
    elif save is not None:
        save.write_bytes(path.read_bytes())
        path = save
        console.print(f"saved {path}")
    if save is not None and not web:
        return

    def _interrupt(*_: object) -> None:
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, _interrupt)  # a terminated replay also stops its viewer
    try:
        handle = replay.open_viewer(path, web=True if web else None, port=port)
        if handle.url:
            console.print(f"Rerun web viewer: {handle.url}  (Ctrl-C to stop)")
        try:
            handle.wait()
        except KeyboardInterrupt:
            pass
        finally:
            handle.stop()
    finally:
        if scratch is not None:
            scratch.cleanup()


# ------------------------------------------------------------------ results and progress
def result_view(c: Any, job: dict[str, Any]) -> tuple[ResultView, dict[str, Any]]:
    """The finished job's view (its result and, when multi-objective, its front size)."""
    res = api_call(c.result, job["id"])
    kind = job.get("kind") or ((job.get("spec") or {}).get("problem") or {}).get("kind", "")
    front = None
    if len(res.get("objective_names") or []) > 1:
        front = int(api_call(c.pareto, job["id"], limit=1).get("total", 0))
    return ResultView.from_api(kind, res, front), res


def print_job_result(c: Any, job: dict[str, Any], *, label: str, verbose: bool = False) -> None:
    """The summary block of a succeeded job (and with ``verbose`` the full tables), or its
    status and error."""
    if job["status"] != "succeeded":
        msg = job.get("error") or ""
        console.print(f"[bold]{label}[/] — job {short(job['id'])}: [bold]{job['status']}[/] {msg}")
        return
    view, res = result_view(c, job)
    title = job_title(job, label, res)
    if verbose:
        for r in full_tables(view, title=title, spec=job.get("spec")):
            console.print(r)
    console.print(summary_block(view, title=title, spec=job.get("spec")))
    for w in job.get("warnings") or []:
        console.print(f"  [yellow]warning:[/] {w}")


def follow(c: Any, jobs: list[dict[str, Any]], labels: list[str]) -> list[dict[str, Any]]:
    """Progress bars for ``jobs`` (dicts with an ``id`` and, when known, a ``spec``) until all
    are terminal; returns their final states. The best so far is shown as the summary will
    show it (a maximised quantity positive)."""
    from services.client import TERMINAL

    names = {j["id"]: objective_names_of(j) for j in jobs}
    final: dict[str, dict[str, Any]] = {}
    with Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[status]}"),
        TimeElapsedColumn(),
        console=console,
    ) as bar:
        tasks = {
            j["id"]: bar.add_task(label, total=None, status="queued")
            for j, label in zip(jobs, labels, strict=True)
        }
        while len(final) < len(jobs):
            for jid in tasks:
                if jid in final:
                    continue
                job = api_call(c.job, jid)
                if names[jid] is None:
                    names[jid] = objective_names_of(job)
                best = best_text(names[jid], job.get("best_objective"))
                bar.update(tasks[jid], total=job.get("total_generations") or None,
                           completed=job.get("generation", 0),
                           status=job["status"] + (f"  {best}" if best else ""))  # fmt: skip
                if job["status"] in TERMINAL:
                    final[jid] = job
            time.sleep(0.5)
    return [final[j["id"]] for j in jobs]
