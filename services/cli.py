"""The `legopt` command line.

    legopt run SPEC.yaml --out DIR     run one job in-process, print it, write DIR/result.json
    legopt db upgrade                  create / migrate the database (Alembic)
    legopt serve                       API + N worker processes on the embedded default
    legopt worker                      one Celery worker process
    legopt demo                        start the embedded service, submit the example studies
    legopt submit | status | results | sweep | replay | keys   talk to a running service

Exit codes: 0 success, 1 the job failed, 2 bad input (the message names the field).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated, Any

import typer
import yaml
from pydantic import ValidationError
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

app = typer.Typer(
    name="legopt",
    help="LegOpt: trajectory optimisation for legged-robot limbs and serial manipulators.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
db_app = typer.Typer(help="Database schema (Alembic).", no_args_is_help=True)
app.add_typer(db_app, name="db")

console = Console(width=None if sys.stdout.isatty() else 160)
err_console = Console(stderr=True, soft_wrap=True)


def bad_input(message: str) -> typer.Exit:
    """Print ``message`` to stderr and return the exit-2 exception to raise."""
    err_console.print(f"[bold red]error:[/] {message}")
    return typer.Exit(code=2)


def validation_lines(exc: ValidationError, data: Any = None) -> list[str]:
    """``field.path: reason`` for each error of a job spec's ValidationError."""
    from legcore.jobspec import spec_error_locations

    out = []
    for loc, msg in spec_error_locations(exc, data):
        where = ".".join(str(p) for p in loc)
        out.append(f"{where}: {msg}" if where else msg)
    return out


def load_spec_file(path: Path) -> dict[str, Any]:
    """Read a YAML or JSON job spec; exit 2 with a clear message if it cannot be read."""
    try:
        text = path.read_text()
    except OSError as exc:
        raise bad_input(f"SPEC: cannot read {path}: {exc.strerror}") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise bad_input(f"SPEC: {path} is not valid YAML/JSON: {exc}") from None
    if not isinstance(data, dict):
        raise bad_input(
            f"SPEC: {path} must contain a mapping (the job spec), not {type(data).__name__}"
        )
    return data


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        if v != v:
            return "—"
        return f"{v:.6g}"
    if v is None:
        return "—"
    return str(v)


def print_result(result: Any) -> None:
    """Rich tables of a `legcore.runner.RunResult`: best, baselines side by side, front."""
    best = result.best
    spec = result.spec
    title = f"{spec.problem.kind} — best solution ({result.optimizer['kind']}, seed {spec.seed})"
    t = Table(title=title, show_lines=False)
    t.add_column("quantity")
    t.add_column("value", justify="right")
    for k, v in best.objectives.items():
        t.add_row(f"objective {k}", _fmt(v))
    for k, v in best.metrics.items():
        t.add_row(k, _fmt(v))
    opt = result.optimizer
    t.add_row("generations / evaluations", f"{opt['n_gen']} / {opt['n_evals']}")
    t.add_row("optimiser time (s)", _fmt(opt["elapsed_s"]))
    console.print(t)
    if result.baselines:
        names = ["best", *result.baselines]
        sols = [best, *result.baselines.values()]
        keys: list[str] = []
        for s in sols:
            keys.extend(k for k in s.metrics if k not in keys)
        bt = Table(title="best vs baselines")
        bt.add_column("metric")
        for n in names:
            bt.add_column(n, justify="right")
        for k in keys:
            bt.add_row(k, *(_fmt(s.metrics.get(k, float("nan"))) for s in sols))
        console.print(bt)
    if best.table:
        print_joint_table(best.table)
    if len(result.pareto) > 1:
        console.print(
            f"Pareto front: {len(result.pareto)} points ({', '.join(result.objective_names)})"
        )


def print_joint_table(rows: list[dict[str, Any]], title: str = "per-joint metrics") -> None:
    """Seed 000 Table 2 style: rows with per-joint ``values`` and/or a ``total``."""
    n = max((len(r.get("values") or []) for r in rows), default=0)
    jt = Table(title=title)
    jt.add_column("metric")
    jt.add_column("unit")
    for i in range(n):
        jt.add_column(f"joint {i + 1}", justify="right")
    jt.add_column("total", justify="right")
    for row in rows:
        vals = list(row.get("values") or [])
        cells = [_fmt(v) for v in vals] + [""] * (n - len(vals))
        jt.add_row(
            str(row.get("metric", "")), str(row.get("unit", "")), *cells, _fmt(row.get("total"))
        )
    console.print(jt)


@app.command()
def run(
    spec_path: Annotated[Path, typer.Argument(metavar="SPEC", help="job spec, YAML or JSON")],
    out: Annotated[Path, typer.Option("--out", "-o", help="output directory")] = Path("out"),
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="no progress bar")] = False,
) -> None:
    """Run one job in-process: progress, a result table, DIR/result.json (+ recording.rrd)."""
    from legcore.jobspec import parse_job_spec
    from legcore.runner import finalize, prepare

    data = load_spec_file(spec_path)
    try:
        spec = parse_job_spec(data)
        prepared = prepare(spec)
    except ValidationError as exc:
        for line in validation_lines(exc, data):
            err_console.print(f"[bold red]error:[/] {line}")
        raise typer.Exit(code=2) from None
    except ValueError as exc:
        raise bad_input(str(exc)) from None
    total = prepared.total_generations
    r = prepared.new_run()
    with Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TextColumn("{task.fields[best]}"),
        console=console,
        disable=quiet,
    ) as bar:
        task = bar.add_task(spec.problem.kind, total=total, best="")
        fronts: dict[int, Any] = {}
        while not r.done:
            p = r.step()
            if p.front_F.ndim == 2 and p.front_F.shape[1] > 1 and len(p.front_F):
                fronts[p.generation] = p.front_F.copy()
            best = ", ".join(f"{v:.5g}" for v in p.best_f)
            bar.update(task, completed=p.generation, best=f"best [{best}]")
    result = finalize(prepared, r.result())
    print_result(result)
    out.mkdir(parents=True, exist_ok=True)
    (out / "result.json").write_text(json.dumps(result.to_dict(), indent=1, allow_nan=False))
    console.print(f"wrote {out / 'result.json'}")
    if spec.record:
        _record(result, out / "recording.rrd", fronts or None)


def _record(result: Any, path: Path, fronts: dict[int, Any] | None = None) -> None:
    try:
        from services.worker.rerun_writer import write_recording
    except ImportError:
        return
    try:
        write_recording(result, path, fronts=fronts)
    except Exception as exc:  # a recording failure never fails the run
        err_console.print(f"[yellow]warning:[/] recording failed: {type(exc).__name__}: {exc}")
        return
    console.print(f"wrote {path}  (open with: legopt replay {path})")


@db_app.command("upgrade")
def db_upgrade(
    revision: Annotated[str, typer.Argument(help="target revision")] = "head",
    url: Annotated[str | None, typer.Option(help="database URL (default: settings)")] = None,
) -> None:
    """Create or migrate the database schema to REVISION (default: head)."""
    from services.store.migrate import upgrade

    upgrade(url, revision)
    console.print(f"database at {revision}")


@db_app.command("downgrade")
def db_downgrade(
    revision: Annotated[str, typer.Argument(help="target revision, e.g. base")],
    url: Annotated[str | None, typer.Option(help="database URL (default: settings)")] = None,
) -> None:
    """Migrate the database schema down to REVISION."""
    from services.store.migrate import downgrade

    downgrade(url, revision)
    console.print(f"database at {revision}")


keys_app = typer.Typer(help="API keys of the local database.", no_args_is_help=True)
app.add_typer(keys_app, name="keys")

UrlOpt = Annotated[str | None, typer.Option("--url", help="API base URL (env LEGOPT_API_URL)")]
KeyOpt = Annotated[str | None, typer.Option("--key", help="API key (env LEGOPT_API_KEY)")]


def _client(url: str | None, key: str | None) -> Any:
    from services.client import Client

    return Client.from_env(url, key)


def _api_call(fn: Any, *args: Any) -> Any:
    """Call the API; a 4xx answer exits 2 with the server's reason, other failures exit 1."""
    import httpx

    from services.client import ApiError, format_detail

    try:
        return fn(*args)
    except ApiError as exc:
        err_console.print(f"[bold red]error:[/] HTTP {exc.status}: {format_detail(exc.detail)}")
        raise typer.Exit(code=2 if 400 <= exc.status < 500 else 1) from None
    except httpx.HTTPError as exc:
        err_console.print(f"[bold red]error:[/] cannot reach the API: {exc}")
        raise typer.Exit(code=1) from None


@app.command()
def serve(
    host: Annotated[str, typer.Option(help="bind address")] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="port")] = 8000,
    workers: Annotated[int, typer.Option(min=1, max=64, help="worker processes")] = 2,
    api_workers: Annotated[int, typer.Option(min=1, max=16, help="API processes")] = 1,
) -> None:
    """The embedded default: API + WORKERS real worker processes, SQLite, filesystem broker."""
    from services.embedded import serve as run_serve

    run_serve(host=host, port=port, workers=workers, api_workers=api_workers)


@app.command()
def worker(
    concurrency: Annotated[int, typer.Option(min=1, help="jobs at once (processes)")] = 1,
    name: Annotated[str, typer.Option(help="worker name")] = "worker",
    loglevel: Annotated[str, typer.Option(help="log level")] = "INFO",
) -> None:
    """One Celery worker on LEGOPT_BROKER_URL (Redis in compose, the filesystem otherwise)."""
    import os

    from services.embedded import worker_command, worker_env

    cmd = worker_command(name, concurrency, loglevel)
    os.execvpe(cmd[0], cmd, worker_env())


@keys_app.command("create")
def keys_create(name: Annotated[str, typer.Option(help="label of the key")] = "cli") -> None:
    """Create an API key in the configured database and print it (shown once)."""
    from services.embedded import ensure_database
    from services.store.keys import generate_api_key
    from services.store.repository import create_api_key
    from services.store.session import session_scope
    from services.store.settings import get_settings

    ensure_database(get_settings())
    raw, key_hash = generate_api_key()
    with session_scope() as s:
        create_api_key(s, name=name, key_hash=key_hash)
    console.print(raw)


@app.command()
def submit(
    spec_path: Annotated[Path, typer.Argument(metavar="SPEC", help="job spec, YAML or JSON")],
    wait: Annotated[bool, typer.Option("--wait", help="wait and print the result")] = False,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Submit a job spec to the service; with --wait, follow it and print its result."""
    data = load_spec_file(spec_path)
    with _client(url, key) as c:
        job = _api_call(c.submit, data)
        console.print(f"job {job['id']} {job['status']}")
        if wait:
            final = _follow(c, [job["id"]], [spec_path.stem])[0]
            _print_job_result(c, final)
            if final["status"] != "succeeded":
                raise typer.Exit(code=1)


@app.command()
def status(
    job_id: Annotated[
        str | None, typer.Argument(metavar="JOB", help="job id (all if omitted)")
    ] = None,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Status and progress of one job, or a table of the latest jobs."""
    with _client(url, key) as c:
        if job_id:
            job = _api_call(c.job, job_id)
            console.print_json(data=job)
            return
        page = _api_call(c.jobs)
        t = Table(title=f"jobs ({page['total']})")
        for col in ("id", "kind", "status", "progress", "best"):
            t.add_column(col)
        for j in page["items"]:
            t.add_row(
                j["id"], _job_kind(j), j["status"], _progress_text(j), _fmt(j.get("best_objective"))
            )
        console.print(t)


@app.command()
def results(
    job_id: Annotated[str, typer.Argument(metavar="JOB")],
    as_json: Annotated[bool, typer.Option("--json", help="print raw JSON")] = False,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Result of a finished job: best solution, metrics, baselines, front size."""
    with _client(url, key) as c:
        job = _api_call(c.job, job_id)
        if as_json:
            console.print_json(data=_api_call(c.result, job_id))
            return
        _print_job_result(c, job)


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
    with _client(url, key) as c:
        sw = _api_call(c.sweep, doc)
        ids = list(sw.get("job_ids", []))
        console.print(f"sweep {sw['id']}: {len(ids)} jobs")
        if wait and ids:
            _follow(c, ids, [f"job {i + 1}" for i in range(len(ids))])
            _print_sweep(_api_call(c.get_sweep, sw["id"]))


@app.command()
def replay(
    target: Annotated[str, typer.Argument(metavar="JOB", help="job id or a .rrd file")],
    save: Annotated[Path | None, typer.Option("--save", help="save the recording here")] = None,
    web: Annotated[bool, typer.Option("--web", help="serve the web viewer on localhost")] = False,
    port: Annotated[int, typer.Option(help="web viewer port")] = 9090,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Open a job's Rerun recording in the viewer (or serve the web viewer with --web)."""
    from services.worker import rerun_writer

    path = Path(target)
    if not path.exists():
        with _client(url, key) as c:
            data = _api_call(c.recording, target)
        path = save or Path(f"{target}.rrd")
        path.write_bytes(data)
        console.print(f"saved {path} ({len(data)} bytes)")
    elif save is not None:
        save.write_bytes(path.read_bytes())
        path = save
    import signal

    def _interrupt(*_: object) -> None:
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, _interrupt)  # a terminated replay also stops its viewer
    handle = rerun_writer.open_viewer(path, web=True if web else None, port=port)
    if handle.url:
        console.print(f"Rerun web viewer: {handle.url}  (Ctrl-C to stop)")
    try:
        handle.wait()
    except KeyboardInterrupt:
        pass
    finally:
        handle.stop()


def _job_kind(job: dict[str, Any]) -> str:
    return str(job.get("spec", {}).get("problem", {}).get("kind", job.get("kind", "")))


def _progress_text(job: dict[str, Any]) -> str:
    g, total = job.get("generation", 0), job.get("total_generations", 0)
    return f"{g}/{total}" if total else str(g)


def _follow(c: Any, ids: list[str], labels: list[str]) -> list[dict[str, Any]]:
    """Progress bars for ``ids`` until all are terminal; returns their final states."""
    import time

    from services.client import TERMINAL

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
            i: bar.add_task(label, total=None, status="queued")
            for i, label in zip(ids, labels, strict=True)
        }
        while len(final) < len(ids):
            for job_id in ids:
                if job_id in final:
                    continue
                job = _api_call(c.job, job_id)
                total = job.get("total_generations") or None
                best = job.get("best_objective")
                best_txt = "" if best is None else f" best {_fmt(best)}"
                bar.update(
                    tasks[job_id],
                    total=total,
                    completed=job.get("generation", 0),
                    status=job["status"] + best_txt,
                )
                if job["status"] in TERMINAL:
                    final[job_id] = job
            time.sleep(0.5)
    return [final[i] for i in ids]


def _print_job_result(c: Any, job: dict[str, Any]) -> None:
    if job["status"] != "succeeded":
        msg = job.get("error") or ""
        console.print(f"job {job['id']}: [bold]{job['status']}[/] {msg}")
        return
    res = _api_call(c.result, job["id"])
    print_result_doc(res, title=f"{_job_kind(job)} — job {job['id']}")
    for w in job.get("warnings") or []:
        console.print(f"[yellow]warning:[/] {w}")


def print_result_doc(res: dict[str, Any], title: str = "result") -> None:
    """Tables of a stored result (``GET /jobs/{id}/result``): best, baselines side by side."""
    t = Table(title=title)
    t.add_column("quantity")
    t.add_column("value", justify="right")
    objectives = res.get("objectives") or {}
    names = objectives.get("names", []) if isinstance(objectives, dict) else []
    values = objectives.get("values", {}) if isinstance(objectives, dict) else {}
    if isinstance(values, dict):
        for k, v in values.items():
            t.add_row(f"objective {k}", _fmt(v))
    else:
        for k, v in zip(names, values, strict=False):
            t.add_row(f"objective {k}", _fmt(v))
    metrics = res.get("metrics") or {}
    for k, v in metrics.items():
        t.add_row(k, _fmt(v))
    console.print(t)
    summary = res.get("summary") or {}
    if isinstance(summary, dict) and summary.get("table"):
        print_joint_table(summary["table"], title="per-joint metrics of the best solution")
    baselines = res.get("baselines") or {}
    if isinstance(baselines, list):
        baselines = {b["name"]: b.get("metrics", {}) for b in baselines}
    if baselines:
        bt = Table(title="best vs baselines")
        bt.add_column("metric")
        bt.add_column("best", justify="right")
        cols = list(baselines)
        for n in cols:
            bt.add_column(n, justify="right")
        for k in metrics:
            row = [_fmt(metrics[k])]
            for n in cols:
                bm = baselines[n].get("metrics", baselines[n])
                row.append(_fmt(bm.get(k)) if isinstance(bm, dict) else "—")
            bt.add_row(k, *row)
        console.print(bt)


def _print_sweep(sw: dict[str, Any]) -> None:
    table = sw.get("table") or {}
    rows = table.get("items", []) if isinstance(table, dict) else list(table)
    t = Table(title=f"sweep {sw.get('id', '')}")
    if not rows:
        console.print_json(data=sw)
        return
    cols = list(rows[0].keys())
    for col in cols:
        t.add_column(col)
    for r in rows:
        t.add_row(*(_fmt(r.get(col)) for col in cols))
    console.print(t)


@app.command()
def demo(
    workers: Annotated[int, typer.Option(min=1, max=16, help="worker processes")] = 2,
    port: Annotated[int, typer.Option(help="API port (0: a free one)")] = 0,
    examples: Annotated[str, typer.Option(help="glob of example specs to submit")] = "*.yaml",
) -> None:
    """Start the embedded service, submit the example studies over HTTP, show progress and
    results, and say how to replay them. Everything stays in ./legopt-data."""
    import socket
    import subprocess
    import time

    from services.client import Client

    root = Path(__file__).resolve().parents[1]
    specs = sorted((root / "examples").glob(examples))
    if not specs:
        raise bad_input(f"examples: no spec matches {examples!r} in {root / 'examples'}")
    if port == 0:
        with socket.socket() as sock:
            sock.bind(("127.0.0.1", 0))
            port = sock.getsockname()[1]
    url = f"http://127.0.0.1:{port}"
    from services.store.settings import get_settings

    data_dir = Path(get_settings().data_dir)
    data_dir.mkdir(parents=True, exist_ok=True)
    log_path = data_dir / "demo-service.log"
    console.print(
        f"starting the embedded LegOpt service on {url} with {workers} workers "
        f"(its log: {log_path}) …"
    )
    log = log_path.open("ab")
    server = subprocess.Popen(
        [sys.executable, "-m", "services.cli", "serve", "--port", str(port),
         "--workers", str(workers)],
        stdout=log, stderr=subprocess.STDOUT,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 120
        while True:
            if server.poll() is not None:
                err_console.print(f"[bold red]error:[/] the service stopped; see {log_path}")
                raise typer.Exit(code=1)
            try:
                Client(url).health()
                break
            except Exception:
                if time.monotonic() > deadline:
                    err_console.print("[bold red]error:[/] the service did not start in 120 s")
                    raise typer.Exit(code=1) from None
                time.sleep(0.5)
        with Client.from_env(url) as c:
            ids, labels = [], []
            for path in specs:
                job = _api_call(c.submit, load_spec_file(path))
                ids.append(job["id"])
                labels.append(path.stem)
            console.print(f"submitted {len(ids)} example studies")
            finals = _follow(c, ids, labels)
            failed = 0
            for label, job in zip(labels, finals, strict=True):
                console.rule(label)
                _print_job_result(c, job)
                failed += job["status"] != "succeeded"
        console.rule("replay")
        console.print("the recordings are kept in the artifact store; open one in the Rerun viewer "
                      "(add --web where there is no display):")  # fmt: skip
        artifacts = Path(get_settings().artifact_dir)
        for label, job_id in zip(labels, ids, strict=True):
            rrd = artifacts / job_id / "recording.rrd"
            console.print(f"  {label}: .venv/bin/legopt replay {rrd}")
        console.print(
            f"everything stays under {data_dir}; with `legopt serve` running, "
            "`legopt replay JOB_ID` and `legopt results JOB_ID` fetch them over HTTP"
        )
        if failed:
            raise typer.Exit(code=1)
    finally:
        from services.embedded import stop_processes

        stop_processes([server], timeout=30)
        log.close()


def main() -> None:  # pragma: no cover - console script entry
    app()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(app())
