"""The `legopt` verbs that work on this machine without a service: run, db, serve, worker, keys.

    legopt run SPEC.yaml --out DIR     run one job in-process, print it, write DIR/result.json
    legopt db upgrade                  create / migrate the database (Alembic)
    legopt serve                       API + N worker processes on the embedded default
    legopt worker                      one Celery worker process
    legopt keys create | list | revoke API keys of the local database
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import typer
from pydantic import ValidationError
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from services.cli.common import (
    app,
    bad_input,
    console,
    err_console,
    load_spec_file,
    validation_lines,
)
from services.cli.display import full_tables, summary_block
from services.cli.objectives import best_text
from services.cli.result_view import ResultView

__all__ = ["print_result"]

db_app = typer.Typer(help="Database schema (Alembic).", no_args_is_help=True)
app.add_typer(db_app, name="db")


def print_result(result: Any, *, verbose: bool = False) -> None:
    """The summary block of a `legcore.runner.RunResult` (and with ``verbose`` every metric
    beside every baseline, the per-joint table and the front size first)."""
    doc = result.to_dict()
    view = ResultView.from_run(doc)
    spec = doc["spec"]
    opt = doc.get("optimizer") or {}
    robot = spec.get("robot")
    robot = robot.get("name", "inline") if isinstance(robot, dict) else robot or "default robot"
    title = (f"[bold]{spec.get('name') or spec['problem']['kind']}[/] — {spec['problem']['kind']}"
             f" · {robot} · {str(opt.get('kind', '')).upper()} · {opt.get('n_gen')} generations"
             f" · {opt.get('elapsed_s', 0):.1f} s")  # fmt: skip
    if verbose:
        for r in full_tables(view, title=title, spec=spec):
            console.print(r)
    console.print(summary_block(view, title=title, spec=spec))


@app.command()
def run(
    spec_path: Annotated[Path, typer.Argument(metavar="SPEC", help="job spec, YAML or JSON")],
    out: Annotated[Path, typer.Option("--out", "-o", help="output directory")] = Path("out"),
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="no progress bar")] = False,
    verbose: Annotated[
        bool, typer.Option("--verbose", "-v", help="every metric and baseline, per-joint table")
    ] = False,
) -> None:
    """Run one job in-process: progress, its summary, DIR/result.json (+ recording.rrd)."""
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
    names = list(prepared.problem.objective_names)
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
            best = best_text(names, [float(v) for v in p.best_f])
            bar.update(task, completed=p.generation, best=best)
    result = finalize(prepared, r.result())
    print_result(result, verbose=verbose)
    out.mkdir(parents=True, exist_ok=True)
    (out / "result.json").write_text(json.dumps(result.to_dict(), indent=1, allow_nan=False))
    console.print(f"wrote {out / 'result.json'}")
    if spec.record:
        _record(result, out / "recording.rrd", fronts or None)


def _record(result: Any, path: Path, fronts: dict[int, Any] | None = None) -> None:
    try:
        from services.recording.writer import write_recording
        from services.store.settings import get_settings
    except ImportError:
        return
    try:
        write_recording(result, path, fronts=fronts, mesh_roots=get_settings().mesh_root_dirs)
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


@app.command()
def serve(
    host: Annotated[str, typer.Option(help="bind address")] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="port")] = 8000,
    workers: Annotated[int, typer.Option(min=1, max=64, help="worker processes")] = 2,
    api_workers: Annotated[int, typer.Option(min=1, max=16, help="API processes")] = 1,
    stop_timeout: Annotated[
        float,
        typer.Option(
            min=0.0,
            help="seconds a worker gets on shutdown to finish its job before SIGKILL "
            "(the job is then resumed from its checkpoint)",
        ),
    ] = 10.0,
) -> None:
    """The embedded default: API + WORKERS real worker processes, SQLite, filesystem broker.
    Restarts a process that dies; SIGTERM or Ctrl-C stops them all."""
    from services.embedded import serve as run_serve

    code = run_serve(
        host=host, port=port, workers=workers, api_workers=api_workers,
        stop_timeout_s=stop_timeout,
    )  # fmt: skip
    if code:
        raise typer.Exit(code=code)


@app.command()
def worker(
    concurrency: Annotated[int, typer.Option(min=1, help="jobs at once (processes)")] = 1,
    name: Annotated[str, typer.Option(help="worker name")] = "worker",
    loglevel: Annotated[str, typer.Option(help="log level")] = "INFO",
) -> None:
    """One Celery worker on LEGOPT_BROKER_URL (Redis in compose, the filesystem otherwise)."""
    import os

    from services.embedded import worker_command, worker_env
    from services.store.settings import get_settings
    from services.worker.celery_app import EMBEDDED_PREFORK_REFUSED, prefork_refused

    if prefork_refused(get_settings().broker_url, "prefork", concurrency):
        raise bad_input(f"concurrency: {EMBEDDED_PREFORK_REFUSED}")
    cmd = worker_command(name, concurrency, loglevel)
    os.execvpe(cmd[0], cmd, worker_env(concurrency))


@keys_app.command("create")
def keys_create(
    name: Annotated[str, typer.Option(help="label of the key")] = "cli",
    admin: Annotated[bool, typer.Option("--admin", help="may create and revoke keys")] = False,
    expires_in_days: Annotated[
        float | None, typer.Option(min=0.001, help="days until the key stops working")
    ] = None,
) -> None:
    """Create an API key in the configured database and print it (shown once)."""
    from datetime import timedelta

    from services.embedded import ensure_database
    from services.store.api_keys import create_api_key
    from services.store.keys import generate_api_key
    from services.store.session import session_scope
    from services.store.settings import get_settings
    from services.store.sql import now_utc

    ensure_database(get_settings())
    raw, key_hash = generate_api_key()
    expires = None if expires_in_days is None else now_utc() + timedelta(days=expires_in_days)
    with session_scope() as s:
        create_api_key(
            s, name=name, key_hash=key_hash, role="admin" if admin else "user", expires_at=expires
        )
    console.print(raw)


@keys_app.command("list")
def keys_list() -> None:
    """The keys of the configured database: id, name, role, expiry, revocation."""
    from services.store.api_keys import list_api_keys
    from services.store.session import session_scope

    table = Table("id", "name", "role", "created", "expires", "revoked")
    with session_scope() as s:
        offset = 0
        while True:
            page = list_api_keys(s, limit=1000, offset=offset)
            for k in page.items:
                table.add_row(
                    k.id, k.name, k.role.value, f"{k.created_at:%Y-%m-%d %H:%M}",
                    f"{k.expires_at:%Y-%m-%d %H:%M}" if k.expires_at else "never",
                    f"{k.revoked_at:%Y-%m-%d %H:%M}" if k.revoked_at else "",
                )  # fmt: skip
            offset += len(page.items)
            if offset >= page.total or not page.items:
                break
    console.print(table)


@keys_app.command("revoke")
def keys_revoke(key_id: Annotated[str, typer.Argument(help="id of the key (keys list)")]) -> None:
    """Revoke a key: it is refused from now on; what it created stays."""
    from services.store.api_keys import get_api_key, revoke_api_key
    from services.store.session import session_scope

    with session_scope() as s:
        if get_api_key(s, key_id) is None:
            raise bad_input(f"key_id: no API key {key_id!r} (see `legopt keys list`)")
        revoked = revoke_api_key(s, key_id)
    console.print(f"revoked {key_id}" if revoked else f"{key_id} was already revoked")
