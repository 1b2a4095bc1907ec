"""Fixtures of the API tests: a migrated temporary SQLite database and artifact directory per
test, an app whose ``enqueue`` records job ids, and two API keys."""

from __future__ import annotations

import shutil
import sqlite3
from collections.abc import Iterator
from pathlib import Path

import pytest
from api_helpers import new_key
from fastapi.testclient import TestClient

from services.api.app import create_app
from services.api.deps import ApiContext
from services.cli import jobs as cli_jobs
from services.client import Client
from services.store import migrate
from services.store.settings import Settings

API = "/api/v1"

DB_NAME = "legopt.db"


@pytest.fixture(scope="session")
def migrated_template(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A SQLite file migrated to head once per run (copied for each test)."""
    path = tmp_path_factory.mktemp("template") / DB_NAME
    migrate.upgrade(f"sqlite:///{path.as_posix()}")
    with sqlite3.connect(path) as conn:  # fold the WAL into the main file before copying
        conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    return path


@pytest.fixture
def settings(tmp_path: Path, migrated_template: Path) -> Settings:
    """Settings on a fresh migrated database and an empty artifact directory."""
    shutil.copy(migrated_template, tmp_path / DB_NAME)
    return Settings.from_env(env={}, data_dir=tmp_path)


@pytest.fixture
def sent() -> list[str]:
    """Job ids the app enqueued, in order."""
    return []


@pytest.fixture
def client(settings: Settings, sent: list[str]) -> Iterator[TestClient]:
    """A test client of an app recording its enqueues in ``sent``."""
    app = create_app(settings, enqueue=sent.append)
    with TestClient(app) as c:
        yield c


@pytest.fixture
def ctx(client: TestClient) -> ApiContext:
    """The app's context (database sessions and artifact store for direct store calls)."""
    context: ApiContext = client.app.state.context  # type: ignore[attr-defined]
    return context


@pytest.fixture
def alice(ctx: ApiContext) -> dict[str, str]:
    """Headers of a first API key."""
    return {"X-API-Key": new_key(ctx, "alice")[0]}


@pytest.fixture
def bob(ctx: ApiContext) -> dict[str, str]:
    """Headers of a second API key."""
    return {"X-API-Key": new_key(ctx, "bob")[0]}


@pytest.fixture
def cli_calls(
    client: TestClient, alice: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> list[str]:
    """``legopt``'s API client (its job and sweep verbs, ``services.cli.jobs``) talking to
    the test app (no server), as ``alice``; the requests it makes."""
    calls: list[str] = []

    def make(_url: str | None, _key: str | None) -> Client:
        c = Client("http://testserver", alice["X-API-Key"])
        c.http.close()
        c.http = TestClient(client.app, base_url=f"http://testserver{API}", headers=alice)
        c.http.event_hooks["request"].append(lambda r: calls.append(f"{r.method} {r.url.path}"))
        return c

    monkeypatch.setattr(cli_jobs, "client", make)
    return calls
