"""docker-compose.yml and the Dockerfile agree with the code and keep the deployment private
(issue 8, defect 12): the API and MinIO are published on loopback only, the volumes are mounted
where the settings point and owned by the image's user, every command runs with umask 077, and
each command names a module, app and queue that exist.

The file runs the layout of several hosts (issue 20): the API and the workers share nothing but
the database, the broker and an S3 artifact store (MinIO, its bucket made by a one-shot
service) — no volume is mounted by two services, a worker mounts none — every ``LEGOPT_*``
variable it sets is a setting, and every service has the restart policy of what it is.

No Docker engine is needed: the files are parsed (PyYAML) and the names they use are looked up
in the source without importing it (importing the Celery app would create broker folders).
``docker-compose config`` (or ``docker compose config``) checks the file too where installed;
under ``LEGOPT_REQUIRE_COMPOSE=1`` (``.ci/run``, when it installed one) a missing one fails.
"""

from __future__ import annotations

import ast
import importlib.util
import json
import os
import re
import shutil
import subprocess
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import pytest
import typer
import yaml

from services.cli import app as cli_app
from services.embedded import worker_command
from services.store.artifacts import artifact_store
from services.store.artifacts.s3 import S3ArtifactStore
from services.store.settings import ENV_PREFIX, Settings

ROOT = Path(__file__).resolve().parents[1]
COMPOSE_FILE = ROOT / "docker-compose.yml"
COMPOSE_TEXT = COMPOSE_FILE.read_text()
COMPOSE = yaml.safe_load(COMPOSE_TEXT)
DOCKERFILE = (ROOT / "Dockerfile").read_text()
SERVICES: dict[str, Any] = COMPOSE["services"]
APP_SERVICES = ("migrate", "api", "worker")
#: The services that publish a port (on loopback): the API and MinIO (S3 API, console).
PUBLISHERS = {"api", "minio"}
#: Services others wait for to *finish* (``service_completed_successfully``).
ONE_SHOTS = {
    dep
    for svc in SERVICES.values()
    for dep, cond in (svc.get("depends_on") or {}).items()
    if isinstance(cond, dict) and cond.get("condition") == "service_completed_successfully"
}
SETTING_VARS = {ENV_PREFIX + name.upper() for name in Settings.model_fields}


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
    """Compose's ``${VAR:-default}`` with the defaults (no .env), ``$$`` as ``$``."""
    return re.sub(r"\$\{\w+:-([^}]*)\}", r"\1", str(value)).replace("$$", "$")


def _option(cmd: list[str], *names: str) -> str:
    for n in names:
        if n in cmd:
            return cmd[cmd.index(n) + 1]
    raise AssertionError(f"none of {names} in {cmd}")


def _env(service: str) -> dict[str, str]:
    env = SERVICES[service]["environment"]
    assert isinstance(env, dict), f"{service}: environment as a mapping"
    return {k: _expand(v) for k, v in env.items()}


def _mounts(service: str) -> dict[str, str]:
    """``{target: source}`` of a service's volumes (short syntax)."""
    volumes = SERVICES[service].get("volumes") or []
    assert all(isinstance(v, str) for v in volumes), f"{service}: volumes in the short syntax"
    return dict(v.split(":", 2)[:2][::-1] for v in volumes)


def test_published_ports_are_on_loopback_only() -> None:
    assert SERVICES["api"]["ports"], "the API publishes a port"
    for name, svc in SERVICES.items():
        ports = svc.get("ports") or []
        if name not in PUBLISHERS:
            assert not ports, f"{name} publishes a port"
        for p in ports:
            assert str(p).startswith("127.0.0.1:"), f"{name}: port {p!r} published beyond loopback"


def test_no_volume_is_shared_and_workers_mount_none() -> None:
    """Several hosts on one: what the API and the workers share goes over the network (database,
    broker, S3), never through a volume — a worker mounts none (a named volume would be shared
    by every replica of ``--scale worker=N``), no volume is mounted by two services."""
    owners: dict[str, list[str]] = {}
    for name in SERVICES:
        for source in _mounts(name).values():
            assert not source.startswith((".", "/", "~")), f"{name}: bind mount {source}"
            owners.setdefault(source, []).append(name)
    shared = {v: names for v, names in owners.items() if len(names) > 1}
    assert not shared, f"volumes mounted by several services: {shared}"
    assert set(owners) <= set(COMPOSE["volumes"]), "a mounted volume is not declared"
    assert "volumes" not in SERVICES["worker"], "a worker mounts a volume"
    for name in ("api", "worker"):
        env = _env(name)
        assert "LEGOPT_ARTIFACT_DIR" not in env, f"{name}: artifacts in a directory"
        assert Settings.from_env(env=env).artifacts_s3 is not None, f"{name}: artifacts not on S3"
    # the API's data dir is its own named volume; a worker's is the image's anonymous volume,
    # one per container (created owned by the image's user, see below)
    api_data = _env("api")["LEGOPT_DATA_DIR"]
    assert api_data in _mounts("api"), f"api: LEGOPT_DATA_DIR={api_data} is not a mounted volume"
    volume = re.search(r"^VOLUME (\[.*\])$", DOCKERFILE, re.M)
    assert volume and _env("worker")["LEGOPT_DATA_DIR"] in json.loads(volume.group(1))


def test_every_legopt_variable_is_a_setting() -> None:
    """A misspelt ``LEGOPT_*`` name would be ignored silently (``Settings.from_env`` skips
    unknown ones): every one the compose file names is a field of ``Settings``; the
    Dockerfile's are settings or read by the code (``LEGOPT_CACHE_DIR``: legcore's cache)."""
    names = set(re.findall(r"\bLEGOPT_[A-Z0-9_]*[A-Z0-9]\b", COMPOSE_TEXT))
    assert {"LEGOPT_DATABASE_URL", "LEGOPT_ARTIFACTS_URL"} <= names
    assert not names - SETTING_VARS, f"not settings: {sorted(names - SETTING_VARS)}"
    source = "\n".join(
        p.read_text() for d in ("services", "legcore") for p in (ROOT / d).rglob("*.py")
    )
    for name in set(re.findall(r"\bLEGOPT_[A-Z0-9_]*[A-Z0-9]\b", DOCKERFILE)) - SETTING_VARS:
        assert f'"{name}"' in source, f"Dockerfile: {name} is neither a setting nor read"
    for name in APP_SERVICES:
        Settings.from_env(env=_env(name))  # every value parses


def test_api_and_workers_store_artifacts_in_the_bucket_minio_init_creates() -> None:
    minio, init = SERVICES["minio"], SERVICES["minio-init"]
    for svc in (minio, init):
        image, _, tag = svc["image"].rpartition(":")
        assert image.endswith(("minio/minio", "minio/mc")) and tag.startswith("RELEASE."), (
            f"{svc['image']}: not pinned to a release"
        )
    assert minio["command"] == ["server", "/data", "--console-address", ":9001"]
    assert _mounts("minio")["/data"] in COMPOSE["volumes"]
    assert minio["healthcheck"]["test"] == ["CMD", "mc", "ready", "local"]
    creds = (_env("minio")["MINIO_ROOT_USER"], _env("minio")["MINIO_ROOT_PASSWORD"])
    assert len(creds[1]) >= 8, "MinIO refuses a root password shorter than 8 characters"
    # the bucket: made by the one-shot service once MinIO is healthy (the store never makes it)
    init_env = _env("minio-init")
    assert (init_env["MINIO_ROOT_USER"], init_env["MINIO_ROOT_PASSWORD"]) == creds
    script = " ".join(_expand(c) for c in init["command"])
    assert init["entrypoint"] == ["/bin/sh", "-c"]
    login = 'mc alias set local http://minio:9000 "$MINIO_ROOT_USER" "$MINIO_ROOT_PASSWORD"'
    assert login in script
    assert 'mc mb --ignore-existing "local/$ARTIFACTS_BUCKET"' in script
    assert init["depends_on"]["minio"]["condition"] == "service_healthy"
    for name in ("api", "worker"):
        env = _env(name)
        settings = Settings.from_env(env=env)
        assert settings.artifacts_s3 == (init_env["ARTIFACTS_BUCKET"], "jobs")
        endpoint = urlsplit(settings.s3_endpoint_url)
        assert (endpoint.scheme, endpoint.hostname, endpoint.port) == ("http", "minio", 9000)
        assert (env["AWS_ACCESS_KEY_ID"], env["AWS_SECRET_ACCESS_KEY"]) == creds
        assert env["AWS_DEFAULT_REGION"]  # boto3 reads AWS_DEFAULT_REGION (not AWS_REGION)
        # a presigned URL would name http://minio:9000, which only the compose network resolves
        assert not settings.artifacts_presign
        deps = SERVICES[name]["depends_on"]
        assert deps["minio-init"]["condition"] == "service_completed_successfully"
        store = artifact_store(settings)  # the S3 backend (a client; nothing is sent)
        assert isinstance(store, S3ArtifactStore)
        assert store.location == settings.artifacts_url
        assert store.key("j/1/result.json") == "jobs/j/1/result.json"


def test_every_service_has_the_restart_policy_of_what_it_is() -> None:
    assert ONE_SHOTS == {"migrate", "minio-init"}
    for name, svc in SERVICES.items():
        policy = svc.get("restart")
        if name in ONE_SHOTS:  # runs once; others wait for it to finish
            assert policy == "no" or str(policy).startswith("on-failure"), f"{name}: {policy!r}"
        else:  # long-running: back after a crash, a memory recycle and a reboot
            assert policy in ("unless-stopped", "always"), f"{name}: restart {policy!r}"


def _compose_cli() -> list[str] | None:
    """``docker-compose`` (Debian's package), else the ``docker compose`` plugin, else None."""
    if shutil.which("docker-compose"):
        return ["docker-compose"]
    if shutil.which("docker"):
        probe = subprocess.run(["docker", "compose", "version"], capture_output=True, timeout=60)
        if probe.returncode == 0:
            return ["docker", "compose"]
    return None


def test_docker_compose_config_accepts_the_file(tmp_path: Path) -> None:
    """Compose itself validates the file (schema, interpolation, ``<<`` merges, dependency
    conditions) and resolves the app services' environments to what the tests above read."""
    cli = _compose_cli()
    if cli is None:
        why = "neither docker-compose nor the docker compose plugin is installed"
        if os.environ.get("LEGOPT_REQUIRE_COMPOSE") == "1":
            pytest.fail(f"LEGOPT_REQUIRE_COMPOSE=1 requires compose: {why}")
        pytest.skip(f"{why} (.ci/run installs Debian's docker-compose)")
    # the defaults only: no .env, none of the variables the file interpolates
    interpolated = set(re.findall(r"\$\{(\w+)", COMPOSE_TEXT))
    env = {k: v for k, v in os.environ.items() if k not in interpolated}
    empty = tmp_path / "empty.env"
    empty.write_text("")
    base = [*cli, "--env-file", str(empty), "-f", str(COMPOSE_FILE)]
    for args in (["config", "-q"], ["config"]):
        run = subprocess.run(
            [*base, *args], capture_output=True, text=True, env=env, cwd=ROOT, timeout=120
        )
        assert run.returncode == 0, f"{' '.join(cli)} {' '.join(args)}: {run.stderr}"
    resolved = yaml.safe_load(run.stdout)["services"]
    assert set(resolved) == set(SERVICES)
    for name in APP_SERVICES:
        got = {k: str(v) for k, v in resolved[name]["environment"].items()}
        assert got == _env(name), f"{name}: compose resolves another environment"


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
