"""``legopt studies`` — the study kinds of the running service (over HTTP).

    legopt studies                      # every kind: what it needs, which robots it accepts
    legopt studies quadruped_gait       # one kind, with its parameters and defaults
    legopt studies quadruped_gait --robot my_go1
    legopt studies --json               # the raw answer of GET /api/v1/studies

A kind registered by a plug-in (docs/plugins.md) is listed like a built-in one. Exit codes as
``legopt``: 0 success, 1 the service failed or is unreachable, 2 bad input.
"""

from __future__ import annotations

from typing import Annotated, Any

import typer
from rich.table import Table

from services.cli.common import KeyOpt, UrlOpt, api_call, app, client, console

__all__ = ["studies"]


def _type(prop: dict[str, Any]) -> str:
    if "type" in prop:
        return str(prop["type"])
    kinds = [str(p.get("type", p.get("$ref", "?")).split("/")[-1]) for p in prop.get("anyOf", [])]
    return " | ".join(kinds) if kinds else "?"


def _print_params(item: dict[str, Any]) -> None:
    props: dict[str, Any] = item["params_schema"].get("properties", {})
    t = Table(title=f"{item['kind']}: parameters (problem.*)")
    for col in ("name", "type", "default", "description"):
        t.add_column(col, overflow="fold")
    derived = set(item.get("robot_relative") or ())
    for name, prop in props.items():
        if name == "kind":
            continue
        default = item["defaults"].get(name)
        shown = "from the robot" if name in derived and default is None else _short(default)
        t.add_row(name, _type(prop), shown, str(prop.get("description", "")))
    console.print(t)


def _short(value: Any, width: int = 40) -> str:
    text = str(value)
    return text if len(text) <= width else text[: width - 1] + "…"


def _print_robots(item: dict[str, Any], robot: str | None) -> None:
    fits = [r for r in item["robots"] if robot is None or robot in (r["robot"], r["id"])]
    t = Table(title=f"{item['kind']}: robots")
    for col in ("robot", "source", "accepted", "why not"):
        t.add_column(col, overflow="fold")
    for r in fits:
        t.add_row(r["robot"], r["source"], "yes" if r["accepted"] else "no", why_not(r))
    console.print(t)


def why_not(fit: dict[str, Any]) -> str:
    """``field: reason`` of a refused robot × study (empty when accepted)."""
    if fit.get("accepted"):
        return ""
    field = fit.get("field")
    return f"{field}: {fit.get('reason') or ''}" if field else str(fit.get("reason") or "")


@app.command("studies")
def studies(
    kind: Annotated[str | None, typer.Argument(help="one study kind (default: all)")] = None,
    robot: Annotated[
        str | None, typer.Option("--robot", help="only this robot (name or id)")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print the raw JSON")] = False,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Study kinds: what each needs from a robot, which robots it accepts (and why not), and
    with KIND its parameters and defaults."""
    params = {"kind": kind} if kind is not None else {}
    with client(url, key) as c:
        data = api_call(c.get, "/studies", **params)
    if as_json:
        console.print_json(data=data)
        return
    items: list[dict[str, Any]] = data["items"]
    if kind is None:
        t = Table(title=f"study kinds ({len(items)})")
        for col in ("kind", "seed", "needs", "accepts"):
            t.add_column(col, overflow="fold")
        for it in items:
            ok = [r["robot"] for r in it["robots"]
                  if r["accepted"] and (robot is None or robot in (r["robot"], r["id"]))]
            seed = it["seed_paper"] + (f" (plug-in {it['plugin']})" if it["plugin"] else "")
            t.add_row(it["kind"], seed, "\n".join(it["needs"]) or "any robot",
                      ", ".join(ok) or "—")
        console.print(t)
    for it in items if kind is not None else []:
        console.print(f"[bold]{it['kind']}[/bold] — {it['title']}")
        if it["description"]:
            console.print(it["description"])
        console.print(f"needs: {'; or '.join(it['needs']) or 'any robot'}")
        console.print(f"defaults: robot {it['default_robot']}, optimizer "
                      f"{it['default_optimizer'].get('kind')}, {it['default_generations']} "
                      "generations")
        _print_params(it)
        _print_robots(it, robot)
    if robot is not None and kind is None:
        for it in items:
            for r in it["robots"]:
                if robot in (r["robot"], r["id"]) and not r["accepted"]:
                    console.print(f"{it['kind']}: {why_not(r)}")
    for name, err in data.get("plugin_errors", {}).items():
        console.print(f"[yellow]plug-in {name} not loaded: {err}[/yellow]")
