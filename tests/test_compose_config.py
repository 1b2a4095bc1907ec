"""docker-compose.yml and the Dockerfile agree with the code and keep the deployment private
(issue 8, defect 12): the API is published on loopback only, the volumes are mounted where the
settings point and owned by the image's user, every command runs with umask 077, and each
command names a module, app and queue that exist.

No Docker engine is needed: the files are parsed (PyYAML) and the names they use are looked up
in the source without importing it (importing the Celery app would create broker folders).
"""

from __future__ import annotations

import ast
import importlib.util
import json
import re
from pathlib import Path
from typing import Any

import pytest
import typer
import yaml

from services.cli import app as cli_app
from services.embedded import worker_command
from services.store.settings import Settings

ROOT = Path(__file__).resolve().parents[1]
COMPOSE = yaml.safe_load((ROOT / "docker-compose.yml").read_text())
DOCKERFILE = (ROOT / "Dockerfile").read_text()
SERVICES: dict[str, Any] = COMPOSE["services"]
APP_SERVICES = ("migrate", "api", "worker")


def _defines(module: str, name: str) -> bool:
    """Whether ``module`` (found on the path, not imported) binds ``name`` at top level or
    serves it from a module ``__getattr__`` (a lazily built app)."""
    spec = importlib.util.find_spec(module)
    assert spec is not None and spec.origin, f"module {module} not found"
    tree = ast.parse(Path(spec.origin).read_text())
    for node in tree.body:
        targets: list[ast.expr] = []
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, ast.AnnAssign):
            targets = [node.target]
        elif isinstance(node, ast.FunctionDef | ast.ClassDef):
            if node.name == name:
                return True
            if node.name == "__getattr__" and any(
                isinstance(c, ast.Constant) and c.value == name for c in ast.walk(node)
            ):
                return True
        if any(isinstance(t, ast.Name) and t.id == name for t in targets):
            return True
    return False


def _expand(value: object) -> str:
    """Compose's ``${VAR:-default}`` with the defaults (no .env)."""
    return re.sub(r"\$\{\w+:-([^}]*)\}", r"\1", str(value))


def _option(cmd: list[str], *names: str) -> str:
    for n in names:
        if n in cmd:
            return cmd[cmd.index(n) + 1]
    raise AssertionError(f"none of {names} in {cmd}")


def _env(service: str) -> dict[str, str]:
    env = SERVICES[service]["environment"]
    assert isinstance(env, dict), f"{service}: environment as a mapping"
    return {k: _expand(v) for k, v in env.items()}


def test_api_port_is_published_on_loopback_only() -> None:
    ports = SERVICES["api"]["ports"]
    assert ports, "the API publishes a port"
    for p in ports:
        assert str(p).startswith("127.0.0.1:"), f"API port {p!r} published beyond loopback"
    for name, svc in SERVICES.items():
        if name != "api":
            assert "ports" not in svc, f"{name} publishes a port"


def test_volumes_are_where_the_settings_point_and_declared() -> None:
    declared = set(COMPOSE["volumes"])
    for name in ("api", "worker"):
        env = _env(name)
        mounts = dict(v.split(":", 1)[::-1] for v in SERVICES[name]["volumes"])
        for var in ("LEGOPT_DATA_DIR", "LEGOPT_ARTIFACT_DIR"):
            assert env[var] in mounts, f"{name}: {var}={env[var]} is not a mounted volume"
            assert mounts[env[var]] in declared, f"{name}: volume {mounts[env[var]]} undeclared"
    settings = Settings.from_env(env=_env("api"))
    assert str(settings.artifact_dir) == _env("api")["LEGOPT_ARTIFACT_DIR"]


def test_image_mount_points_are_owned_by_its_user_before_volume_and_user() -> None:
    lines = [ln.strip() for ln in DOCKERFILE.replace("\\\n", " ").splitlines()]
    user = next(i for i, ln in enumerate(lines) if ln.startswith("USER "))
    volume = next(i for i, ln in enumerate(lines) if ln.startswith("VOLUME "))
    image_user = lines[user].split()[1]
    mount_points = set(json.loads(lines[volume].split(" ", 1)[1]))
    assert {"/data", "/artifacts"} <= mount_points
    setup = " ".join(lines[:volume])
    for d in mount_points:
        assert re.search(rf"mkdir -p [^&]*{d}\b", setup), f"{d} not created before VOLUME"
        assert re.search(rf"chown {image_user}(:{image_user})? [^&]*{d}\b", setup), (
            f"{d} not owned by {image_user} before VOLUME"
        )
    assert volume < user, "VOLUME after USER: the mount points would not be the user's"


def test_every_command_runs_with_umask_077() -> None:
    entry = re.search(r"^ENTRYPOINT (\[.*\])$", DOCKERFILE, re.M)
    assert entry, "the Dockerfile has an exec-form ENTRYPOINT"
    argv = json.loads(entry.group(1))
    assert argv[:2] == ["/bin/sh", "-c"] and argv[2].startswith("umask 077 &&")
    assert 'exec "$@"' in argv[2]
    for name in APP_SERVICES:
        assert "entrypoint" not in SERVICES[name], f"{name} overrides the image's entrypoint"


@pytest.mark.parametrize("name", APP_SERVICES)
def test_app_services_build_the_image_with_the_shared_env(name: str) -> None:
    svc = SERVICES[name]
    assert svc["build"] == "."
    env = _env(name)
    for var in ("LEGOPT_DATABASE_URL", "LEGOPT_BROKER_URL"):
        assert var in env and env[var] == _expand(COMPOSE["x-legopt-env"][var])


def test_migrate_runs_a_legopt_command_that_exists() -> None:
    cmd = SERVICES["migrate"]["command"]
    assert cmd[0] == "legopt"
    assert 'legopt = "services.cli:app"' in (ROOT / "pyproject.toml").read_text()
    group = typer.main.get_command(cli_app)
    for word in cmd[1:]:
        group = group.commands[word]  # type: ignore[attr-defined]


def test_api_command_names_the_asgi_app() -> None:
    cmd = [str(a) for a in SERVICES["api"]["command"]]
    assert cmd[0] == "uvicorn"
    module, attr = cmd[1].split(":")
    assert _defines(module, attr), f"{cmd[1]} is not defined"
    assert _option(cmd, "--host") == "0.0.0.0"  # inside the container; published on loopback
    assert _option(cmd, "--port") == str(SERVICES["api"]["ports"][0]).rsplit(":", 1)[1]
    health = " ".join(SERVICES["api"]["healthcheck"]["test"])
    assert "/api/v1/ready" in health


def test_worker_command_is_the_one_the_code_runs() -> None:
    cmd = [str(a) for a in SERVICES["worker"]["command"]]
    ours = worker_command("w", concurrency=2)
    assert cmd[:4] == ["celery", "-A", _option(ours, "-A"), "worker"]
    module, attr = _option(cmd, "-A").split(":")
    assert _defines(module, attr), f"{_option(cmd, '-A')} is not defined"
    queue = _option(cmd, "-Q")
    assert queue == _option(ours, "-Q")
    celery_app = Path(str(importlib.util.find_spec(module).origin)).read_text()  # type: ignore[union-attr]
    assert f'QUEUE = "{queue}"' in celery_app
    # prefork: SIGTERM remapped to a cold shutdown hands the job in hand back
    assert _option(cmd, "--pool", "-P") == "prefork"
    env = _env("worker")
    assert env["REMAP_SIGTERM"] == "SIGQUIT"
    assert env["NUMBA_NUM_THREADS"] == "1"
    health = SERVICES["worker"]["healthcheck"]["test"][1]
    assert f"-A {_option(cmd, '-A')}" in health
