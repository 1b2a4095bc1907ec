"""``legopt robots add | list | show`` — robot models of the running service (over HTTP).

    legopt robots add arm.urdf --name arm --locked-joints finger1,finger2=0.01
    legopt robots add solo12.urdf --legs auto                 # a legged robot
    legopt robots add solo12.urdf --legs auto --leg FL        # one leg, as a serial chain
    legopt robots add go1.urdf --legs FL=FL_foot,FR=hip:FR_hip_joint,...
    legopt robots list [--catalog]
    legopt robots show NAME_OR_ID [--json]

The file is read here and sent inline; the service validates and builds it (a 4xx answer exits
2 with the reason naming the field). Exit codes as ``legopt``: 0 success, 1 the service failed
or is unreachable, 2 bad input.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table

from services.cli.common import KeyOpt, UrlOpt, api_call, bad_input, client, console
from services.spec_files import read_urdf_file, robot_name_from

__all__ = ["parse_legs", "parse_locked_joints", "robot_spec_from_file", "robots_app"]

robots_app = typer.Typer(help="Robot models of the running service.", no_args_is_help=True)


def parse_locked_joints(items: list[str]) -> dict[str, float | None]:
    """``["a,b=0.1", "c=home"]`` → ``{"a": None, "b": 0.1, "c": None}`` (None: the joint's
    home value); ``ValueError("--locked-joints: …")`` on a bad value."""
    out: dict[str, float | None] = {}
    for item in items:
        for part in item.split(","):
            part = part.strip()
            if not part:
                continue
            name, sep, value = part.partition("=")
            name, value = name.strip(), value.strip()
            if not name:
                raise ValueError(f"--locked-joints: {part!r} has no joint name")
            if not sep or value in ("", "home", "null"):
                out[name] = None
                continue
            try:
                v = float(value)
            except ValueError:
                raise ValueError(
                    f"--locked-joints: {name}={value!r} is not a number (rad or m) or 'home'"
                ) from None
            if not math.isfinite(v):
                raise ValueError(f"--locked-joints: {name}={value!r} must be finite")
            out[name] = v
    return out


def parse_legs(text: str) -> str | dict[str, dict[str, str]]:
    """``"auto"``, or ``"LF=LF_FOOT,RF=hip:RF_HAA,LH=hip:LH_HAA+foot:LH_FOOT"`` → the spec's
    ``legs`` (a bare name is the foot frame); ``ValueError("--legs: …")`` otherwise."""
    if text.strip() == "auto":
        return "auto"
    legs: dict[str, dict[str, str]] = {}
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        leg, sep, rest = part.partition("=")
        if not sep or not leg.strip() or not rest.strip():
            raise ValueError(f"--legs: {part!r} must read LEG=FOOT, LEG=hip:JOINT or 'auto'")
        entry: dict[str, str] = {}
        for item in rest.split("+"):
            key, colon, value = item.strip().partition(":")
            if not colon:
                key, value = "foot", key
            if key not in ("hip", "foot") or not value.strip():
                raise ValueError(f"--legs: {item!r} must read FOOT, foot:FRAME or hip:JOINT")
            entry[key] = value.strip()
        legs[leg.strip()] = entry
    if not legs:
        raise ValueError("--legs: give 'auto' or LEG=FOOT pairs")
    return legs


def robot_spec_from_file(
    path: Path,
    *,
    name: str | None = None,
    locked_joints: list[str] | None = None,
    legs: str | None = None,
    leg: str | None = None,
    tool_frame: str | None = None,
) -> dict[str, Any]:
    """The inline URDF robot spec of ``legopt robots add`` (``ValueError`` naming the option)."""
    spec: dict[str, Any] = {
        "kind": "urdf",
        "name": name or robot_name_from(path),
        "urdf": read_urdf_file(path, "FILE"),
    }
    if locked_joints:
        spec["locked_joints"] = parse_locked_joints(locked_joints)
    if legs is not None:
        spec["legs"] = parse_legs(legs)
    if leg is not None:
        spec["leg"] = leg
    if tool_frame is not None:
        spec["tool_frame"] = tool_frame
    return spec


def _print_robot(robot: dict[str, Any]) -> None:
    caps = robot.get("capabilities") or {}
    summary = robot.get("summary") or {}
    head = f"robot {robot.get('name')} (id {robot.get('id')}, {robot.get('source')})"
    if caps.get("kind") == "legged":
        legs = ", ".join(f"{g['name']} ({g['n_joints']} joints, foot {g['foot_frame']})"
                         for g in caps.get("legs", []))  # fmt: skip
        console.print(f"{head}: legged, {caps.get('n_actuated')} joints; legs {legs}")
    else:
        console.print(
            f"{head}: serial chain of {caps.get('n_actuated')} joints, end frame "
            f"{caps.get('end_frame')}"
        )
    t = Table(title="capabilities", show_header=False)
    t.add_column("what")
    t.add_column("value")
    t.add_row("joints", ", ".join(caps.get("joint_names", [])))
    t.add_row("mass", f"{summary.get('mass_kg', float('nan')):.4g} kg")
    t.add_row("closed-form IK", str(caps.get("ik_family") or "—"))
    elec = f"{caps.get('electrical_joints')} of {caps.get('n_actuated')} joints"
    t.add_row("motor data (Kt, Ke, R)", elec)
    t.add_row("torque limits", "yes" if caps.get("torque_limits") else "not on every joint")
    console.print(t)
    fits = robot.get("studies")
    if fits:
        s = Table(title="study kinds (with their default task)")
        for col in ("study", "accepts", "default task, or why not"):
            s.add_column(col, overflow="fold")
        for f in fits:
            s.add_row(f["kind"], "yes" if f["accepted"] else "no", _fit_text(f))
        console.print(s)


def _fit_text(fit: dict[str, Any]) -> str:
    """The rules of an accepted study's default task (or its paper's preset), or the field to
    change and why it is refused."""
    if not fit.get("accepted"):
        field = fit.get("field")
        return f"{field}: {fit.get('reason')}" if field else str(fit.get("reason"))
    if fit.get("preset"):
        return f"the paper's settings ({fit['preset']})"
    rules = fit.get("rules") or {}
    return "; ".join(f"{k}: {v}" for k, v in rules.items()) or "its defaults"


def _find(c: Any, reference: str) -> dict[str, Any]:
    """Your robot by id (or a catalog name), else by name among your robots."""
    from services.client import ApiError

    try:
        return c.robot(reference)
    except ApiError as exc:
        if exc.status != 404:
            raise
    offset = 0
    while True:
        page = c.robots(limit=1000, offset=offset)
        for item in page["items"]:
            if item["name"] == reference:
                return c.robot(item["id"])
        offset += len(page["items"])
        if not page["items"] or offset >= page["total"]:
            raise ApiError(404, f"no robot {reference!r} among yours or the catalog")


@robots_app.command("remove")
def remove(
    reference: Annotated[str, typer.Argument(metavar="NAME", help="your robot's name or id")],
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Delete one of your stored robots (jobs that ran it keep their copy)."""
    with client(url, key) as c:
        robot = api_call(_find, c, reference)
        if robot.get("builtin"):
            raise bad_input(f"NAME: {reference!r} is a catalog robot: only your own can be removed")
        api_call(c.delete_robot, robot["id"])
    console.print(f"robot {robot.get('name') or reference}: removed")


@robots_app.command("add")
def add(
    file: Annotated[Path, typer.Argument(metavar="FILE.urdf", help="the robot's URDF file")],
    name: Annotated[
        str | None, typer.Option("--name", help="robot name (default: the file's stem)")
    ] = None,
    locked_joints: Annotated[
        list[str] | None,
        typer.Option(
            "--locked-joints",
            help="joints held fixed: NAME[=VALUE],… (no value: the home value)",
        ),
    ] = None,
    legs: Annotated[
        str | None,
        typer.Option("--legs", help="a legged robot: 'auto' or LEG=FOOT,LEG=hip:JOINT,…"),
    ] = None,
    leg: Annotated[
        str | None, typer.Option("--leg", help="store only this leg, as a serial chain")
    ] = None,
    tool_frame: Annotated[
        str | None, typer.Option("--tool-frame", help="the chain's end frame (serial robots)")
    ] = None,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Store a robot from a URDF file in the service (validated and built there)."""
    try:
        spec = robot_spec_from_file(
            file,
            name=name,
            locked_joints=locked_joints,
            legs=legs,
            leg=leg,
            tool_frame=tool_frame,
        )
    except ValueError as exc:
        raise bad_input(str(exc)) from None
    with client(url, key) as c:
        robot = api_call(c.add_robot, spec["name"], spec)
    _print_robot(robot)


@robots_app.command("list")
def list_robots(
    include_catalog: Annotated[
        bool, typer.Option("--catalog", help="list the catalog robots first")
    ] = False,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """Your robots (and the catalog's with --catalog)."""
    with client(url, key) as c:
        items: list[dict[str, Any]] = []
        while True:
            page = api_call(
                c.robots, include_catalog=include_catalog, limit=1000, offset=len(items)
            )
            items += page["items"]
            if not page["items"] or len(items) >= page["total"]:
                break
    t = Table(title=f"robots ({len(items)})")
    for col in ("id", "name", "source"):
        t.add_column(col)
    for r in items:
        t.add_row(str(r["id"]), str(r["name"]), str(r["source"]))
    console.print(t)


@robots_app.command("show")
def show(
    reference: Annotated[str, typer.Argument(metavar="NAME", help="robot name, id or catalog")],
    as_json: Annotated[bool, typer.Option("--json", help="print the raw JSON")] = False,
    url: UrlOpt = None,
    key: KeyOpt = None,
) -> None:
    """One robot: its model summary, capabilities and the study kinds that accept it with their
    default task, or why not (with --json, the whole record)."""
    with client(url, key) as c:
        robot = api_call(_find, c, reference)
    if as_json:
        console.print_json(data=robot)
        return
    _print_robot(robot)
