"""`legopt demo`: the embedded service, the example studies over HTTP, one summary per study.

The demo starts `legopt serve` (API + worker processes, SQLite and the filesystem broker under
the data directory), submits ``examples/<glob>``, shows a progress bar per job, prints one
compact block per study (:func:`services.cli.display.summary_block`; ``--verbose`` adds the full
tables), says where to look next, and stops the service. The jobs stay in the data directory:
a later `legopt serve` shows them again.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table

from services.cli.common import (
    api_call,
    app,
    bad_input,
    console,
    err_console,
    free_port,
    load_spec_file,
)
from services.cli.jobs import follow, print_job_result, short

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
#: The port `legopt serve` listens on by default (what the "next" lines refer to).
SERVE_PORT = 8000


#: How long (s) the demo waits for its service to answer while the service process lives (a
#: busy machine can take minutes; a dead service is reported at once).
START_TIMEOUT_S = 600.0
#: A line every this many seconds while it waits, so a slow start is never silent.
START_NOTE_EVERY_S = 30.0


def _wait_healthy(url: str, server: subprocess.Popen[bytes], log_path: Path) -> None:
    from services.client import Client

    started = time.monotonic()
    next_note = started + START_NOTE_EVERY_S
    while True:
        if server.poll() is not None:
            err_console.print(f"[bold red]error:[/] the service stopped; see {log_path}")
            raise typer.Exit(code=1)
        try:
            Client(url).health()
            return
        except Exception:
            now = time.monotonic()
            if now - started > START_TIMEOUT_S:
                err_console.print(f"[bold red]error:[/] the service did not start in "
                                  f"{START_TIMEOUT_S:.0f} s; see {log_path}")  # fmt: skip
                raise typer.Exit(code=1) from None
            if now >= next_note:
                console.print(f"  still starting after {now - started:.0f} s (a busy machine is "
                              f"slower; its log: {log_path}) …")  # fmt: skip
                next_note = now + START_NOTE_EVERY_S
            time.sleep(0.5)


def _has_dashboard(url: str) -> bool:
    """True when the service answers its root with an HTML page (the dashboard)."""
    import httpx

    try:
        r = httpx.get(url + "/", timeout=5)
    except httpx.HTTPError:
        return False
    return r.status_code == 200 and "html" in r.headers.get("content-type", "")


def _next_steps(ids: list[str], data_dir: Path, dashboard: bool) -> Table:
    """Where to look next: the commands, with the demo's own job ids."""
    first = short(ids[0]) if ids else "JOB"
    title = (f"next — the demo's service has stopped; the jobs stay in {data_dir}. "
             f"Start [bold]legopt serve[/] (port {SERVE_PORT}), then:")  # fmt: skip
    t = Table(box=None, show_header=False, padding=(0, 2), title_justify="left", title=title)
    t.add_column(style="bold", no_wrap=True)
    t.add_column()
    where = f"http://127.0.0.1:{SERVE_PORT}"
    if dashboard:
        t.add_row(f"open {where}/", "the dashboard: jobs, fronts, progress")
    t.add_row(f"legopt results {first}", "every metric of a study beside all its baselines")
    t.add_row(f"legopt replay {first} --web", "its Rerun recording in the browser")
    t.add_row("legopt status", "the jobs, one line each")
    return t


@app.command()
def demo(
    workers: Annotated[int, typer.Option(min=1, max=16, help="worker processes")] = 2,
    port: Annotated[int, typer.Option(help="API port (0: a free one)")] = 0,
    examples: Annotated[
        list[str] | None,
        typer.Option(help="glob of example specs in examples/ (repeat for several; default all)"),
    ] = None,
    generations: Annotated[
        int | None,
        typer.Option(min=1, help="run every example for this many generations (a quick look)"),
    ] = None,
    verbose: Annotated[
        bool, typer.Option("--verbose", "-v", help="every metric and baseline of each study")
    ] = False,
) -> None:
    """The embedded service, the example studies over HTTP, one summary per study.

    Everything stays in ./legopt-data (LEGOPT_DATA_DIR)."""
    from services.client import Client
    from services.embedded import stop_processes
    from services.store.settings import get_settings
    from services.supervisor import die_with_parent

    specs: list[Path] = []
    for pattern in examples or ["*.yaml"]:
        found = sorted(EXAMPLES.glob(pattern))
        if not found:
            raise bad_input(f"examples: no spec matches {pattern!r} in {EXAMPLES}")
        specs.extend(p for p in found if p not in specs)
    docs = [load_spec_file(p) for p in specs]
    if generations is not None:
        for d in docs:
            d["budget"] = {"generations": generations}
    port = port or free_port()
    url = f"http://127.0.0.1:{port}"
    data_dir = Path(get_settings().data_dir)
    data_dir.mkdir(parents=True, exist_ok=True)
    log_path = data_dir / "demo-service.log"
    console.print(f"starting the LegOpt service on {url} with {workers} workers "
                  f"(its log: {log_path}) …")  # fmt: skip
    log = log_path.open("ab")
    demo_pid = os.getpid()
    # SIGTERM to demo unwinds through `finally` like Ctrl-C; serve gets SIGTERM from the kernel
    # if demo dies any other way (kill -9), and runs in its own process group so that a
    # Ctrl-C reaches demo only, which then stops it once.
    previous_term = signal.signal(signal.SIGTERM, lambda *_: sys.exit(128 + signal.SIGTERM))
    server = subprocess.Popen(
        [sys.executable, "-m", "services.cli", "serve", "--port", str(port),
         "--workers", str(workers)],
        stdout=log, stderr=subprocess.STDOUT, process_group=0,
        preexec_fn=lambda: die_with_parent(signal.SIGTERM, demo_pid),
    )  # fmt: skip
    try:
        _wait_healthy(url, server, log_path)
        if _has_dashboard(url):
            console.print(f"the dashboard is live at {url}/ while the demo runs")
        with Client.from_env(url) as c:
            jobs: list[dict[str, Any]] = []
            for doc in docs:
                job = api_call(c.submit, doc)
                jobs.append({"id": job["id"], "spec": doc})
            labels = [p.stem for p in specs]
            console.print(f"submitted {len(jobs)} example studies")
            finals = follow(c, jobs, labels)
            console.rule("results")
            for label, job, doc in zip(labels, finals, docs, strict=True):
                job.setdefault("spec", doc)
                print_job_result(c, job, label=label, verbose=verbose)
                console.print()
            dashboard = _has_dashboard(url)
        console.print(_next_steps([j["id"] for j in finals], data_dir, dashboard))
        if any(j["status"] != "succeeded" for j in finals):
            raise typer.Exit(code=1)
    finally:
        stop_processes([server], timeout=30)
        log.close()
        signal.signal(signal.SIGTERM, previous_term)
