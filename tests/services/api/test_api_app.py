"""App-level behaviour: health and readiness, OpenAPI (examples, security), lazy database."""

from __future__ import annotations

from pathlib import Path

from fastapi.testclient import TestClient

from legcore.studies.registry import studies
from services.api.app import create_app
from services.store.settings import Settings

API = "/api/v1"


def test_health_needs_no_key_and_no_database(tmp_path: Path) -> None:
    settings = Settings.from_env(env={}, data_dir=tmp_path / "nothing-here")
    app = create_app(settings, enqueue=lambda _id: None)
    with TestClient(app) as c:
        assert c.get(f"{API}/health").json() == {"status": "ok"}
        assert c.get(f"{API}/openapi.json").status_code == 200
        assert c.get(f"{API}/docs").status_code == 200
    assert not (tmp_path / "nothing-here").exists()  # nothing touched the database


def test_ready_when_migrated(client: TestClient) -> None:
    r = client.get(f"{API}/ready")
    assert r.status_code == 200 and r.json()["status"] == "ready"


def test_not_ready_when_not_migrated(tmp_path: Path) -> None:
    settings = Settings.from_env(env={}, data_dir=tmp_path)
    with TestClient(create_app(settings, enqueue=lambda _id: None)) as c:
        r = c.get(f"{API}/ready")
    assert r.status_code == 503
    assert "legopt db upgrade" in r.json()["detail"]


def test_not_ready_when_database_unreachable(tmp_path: Path) -> None:
    settings = Settings.from_env(
        env={}, data_dir=tmp_path, database_url="postgresql://nobody@127.0.0.1:1/none"
    )
    with TestClient(create_app(settings, enqueue=lambda _id: None)) as c:
        r = c.get(f"{API}/ready")
    assert r.status_code == 503 and "unreachable" in r.json()["detail"]


def test_openapi_has_examples_security_and_pagination(client: TestClient) -> None:
    spec = client.get(f"{API}/openapi.json").json()
    submit = spec["paths"][f"{API}/jobs"]["post"]
    examples = submit["requestBody"]["content"]["application/json"]["examples"]
    assert set(examples) == set(studies())
    for kind, example in examples.items():
        assert example["value"] == {"problem": {"kind": kind}}
    body_schema = submit["requestBody"]["content"]["application/json"]["schema"]
    assert {"robot", "problem", "optimizer", "seed", "budget", "record"} <= set(
        body_schema["properties"]
    )
    assert body_schema["additionalProperties"] is False
    assert "APIKeyHeader" in spec["components"]["securitySchemes"]
    assert "security" in submit
    assert "security" not in spec["paths"][f"{API}/health"]["get"]
    params = {p["name"] for p in spec["paths"][f"{API}/jobs"]["get"]["parameters"]}
    assert {"limit", "offset", "status", "sweep_id"} <= params
    assert "422" in submit["responses"] and "401" in submit["responses"]
