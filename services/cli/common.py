"""What every `legopt` command shares: the Typer app, the consoles, input errors (exit 2),
the API client and id prefixes.

Exit codes: 0 success, 1 the job failed (or the API cannot be reached), 2 bad input (the message
names the field).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated, Any

import typer
import yaml
from pydantic import ValidationError
from rich.console import Console

__all__ = [
    "KeyOpt",
    "UrlOpt",
    "api_call",
    "app",
    "bad_input",
    "client",
    "console",
    "err_console",
    "load_spec_file",
    "resolve_id",
    "validation_lines",
]

app = typer.Typer(
    name="legopt",
    help="LegOpt: trajectory optimisation for legged-robot limbs and serial manipulators.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _print_version(value: bool) -> None:
    if value:
        from importlib.metadata import PackageNotFoundError, version

        try:
            print(f"legopt {version('legopt')}")
        except PackageNotFoundError:  # a source tree that was never installed
            print("legopt (not installed: run python3 run.py legopt --version)")
        raise typer.Exit()


@app.callback()
def _private_files(
    _version: Annotated[
        bool,
        typer.Option(
            "--version", callback=_print_version, is_eager=True, help="Print the version and exit."
        ),
    ] = False,
) -> None:
    """Everything legopt writes (database, artifacts, keys, broker) is private: umask 077."""
    from services.embedded import restrict_umask

    restrict_umask()


console = Console(width=None if sys.stdout.isatty() else 160)
err_console = Console(stderr=True, soft_wrap=True)

UrlOpt = Annotated[str | None, typer.Option("--url", help="API base URL (env LEGOPT_API_URL)")]
KeyOpt = Annotated[str | None, typer.Option("--key", help="API key (env LEGOPT_API_KEY)")]


def free_port() -> int:
    """A TCP port free on 127.0.0.1 now (for a service or viewer this command starts)."""
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def bad_input(message: str) -> typer.Exit:
    """Print ``message`` to stderr and return the exit-2 exception to raise."""
    from rich.markup import escape

    err_console.print(f"[bold red]error:[/] {escape(message)}")
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
    from services.spec_files import inline_robot_files

    try:
        return inline_robot_files(data, path.parent)
    except ValueError as exc:
        raise bad_input(f"SPEC: {exc}") from None


def client(url: str | None, key: str | None) -> Any:
    """The API client (URL and key from the options, the environment or ./legopt-data)."""
    from services.client import Client

    return Client.from_env(url, key)


def api_call(fn: Any, *args: Any, **kwargs: Any) -> Any:
    """Call the API; a 4xx answer exits 2 with the server's reason, other failures exit 1."""
    import httpx

    from services.client import ApiError, format_detail

    try:
        return fn(*args, **kwargs)
    except ApiError as exc:
        err_console.print(f"[bold red]error:[/] HTTP {exc.status}: {format_detail(exc.detail)}")
        raise typer.Exit(code=2 if 400 <= exc.status < 500 else 1) from None
    except httpx.HTTPError as exc:
        url = getattr(getattr(fn, "__self__", None), "url", "")
        err_console.print(
            f"[bold red]error:[/] cannot reach the API {url}: {exc} (is `legopt serve` running?)"
        )
        raise typer.Exit(code=1) from None


def resolve_id(
    c: Any, given: str, *, field: str = "JOB", collections: tuple[str, ...] = ("jobs",)
) -> tuple[str, str]:
    """``(collection, full id)`` of an id or an unambiguous id prefix among your jobs (and
    sweeps when ``collections`` includes "sweeps"); exit 2 naming ``field`` otherwise."""
    from services.client import ApiError, is_full_id

    what = " or ".join(col.rstrip("s") for col in collections)
    if is_full_id(given):
        if len(collections) == 1:
            return collections[0], given.lower()

        def find() -> str | None:  # a whole id: ask for it rather than list everything
            for col in collections:
                try:
                    c.get(f"/{col}/{given.lower()}")
                except ApiError as exc:
                    if exc.status != 404:
                        raise
                    continue
                return col
            return None

        found = api_call(find)
        if found is None:
            raise bad_input(f"{field}: no {what} {given!r}")
        return found, given.lower()
    matches = [(col, i) for col in collections for i in api_call(c.ids_with_prefix, col, given)]
    if not matches:
        raise bad_input(f"{field}: no {what} id starts with {given!r}")
    if len(matches) > 1:
        shown = ", ".join(i for _, i in matches[:5]) + (" …" if len(matches) > 5 else "")
        raise bad_input(
            f"{field}: {given!r} is ambiguous: it starts {len(matches)} ids ({shown}); "
            "give more characters"
        )
    return matches[0]
