"""Conventions every route keeps (issue 22): every response carries ``X-Content-Type-Options:
nosniff`` (answers, errors of every layer, files, pages); every 422 has the validation errors'
shape (a list of ``{loc, msg, type}``), in the answers and in the OpenAPI document; an integer
field of a request refuses a boolean (``seeds: [false]`` is not seed 0) naming the field; the
dashboard's and the viewer's pages allow no inline script or style and no eval, and hold none
(the browser tests, tests/web, check the pages work under that policy)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
from api_helpers import locs
from fastapi import HTTPException
from fastapi.testclient import TestClient

from legcore.studies.registry import studies
from services.api.app import create_app
from services.api.deps import ApiContext
from services.store import api_keys
from services.store import repository as repo
from services.store.keys import generate_api_key
from services.store.settings import Settings
from services.store.states import KeyRole

API = "/api/v1"
KIND = sorted(studies())[0]
NOSNIFF = ("x-content-type-options", "nosniff")


def _app_with_failing_routes(settings: Settings) -> Any:
    """The app plus two routes of a test's own: an ``HTTPException(422, "text")`` and a bug."""
    app = create_app(settings, enqueue=lambda _id: None, max_body_bytes=4096)

    @app.get(f"{API}/test-only/422")
    def text_422() -> None:
        raise HTTPException(422, "a message, not a list")

    @app.get(f"{API}/test-only/500")
    def bug() -> None:
        raise RuntimeError("a bug")

    return app


def test_every_response_says_nosniff(settings: Settings, alice: dict[str, str]) -> None:
    # ``alice`` is a key in the same database: this app reads it too
    with TestClient(_app_with_failing_routes(settings), raise_server_exceptions=False) as c:
        answers = {
            "health": c.get(f"{API}/health"),
            "json": c.get(f"{API}/jobs", headers=alice),
            "401": c.get(f"{API}/jobs"),
            "404": c.get(f"{API}/jobs/nope", headers=alice),
            "404 route": c.get(f"{API}/no-such-route"),
            "422 query": c.get(f"{API}/jobs?limit=x", headers=alice),
            "422 guard": c.post(f"{API}/jobs", content=b'{"a": NaN}', headers=alice),
            "413": c.post(f"{API}/jobs", content=b"[" + b" " * 5000 + b"]", headers=alice),
            "422 text": c.get(f"{API}/test-only/422"),
            "500": c.get(f"{API}/test-only/500"),
            "csv": c.get(f"{API}/export/jobs", headers=alice),
            "dashboard": c.get("/"),
            "static": c.get("/static/js/app.js"),
            "swagger": c.get(f"{API}/docs"),
            "redirect": c.get("/docs", follow_redirects=False),
        }
    statuses = {name: r.status_code for name, r in answers.items()}
    assert statuses == {
        "health": 200, "json": 200, "401": 401, "404": 404, "404 route": 404,
        "422 query": 422, "422 guard": 422, "413": 413, "422 text": 422, "500": 500,
        "csv": 200, "dashboard": 200, "static": 200, "swagger": 200, "redirect": 307,
    }  # fmt: skip
    for name, r in answers.items():
        assert (NOSNIFF[0], NOSNIFF[1]) in r.headers.items(), name


def test_every_422_is_a_list_of_located_errors(settings: Settings, alice: dict[str, str]) -> None:
    with TestClient(_app_with_failing_routes(settings)) as c:
        r = c.get(f"{API}/test-only/422")
        assert r.json() == {
            "detail": [{"type": "value_error", "loc": [], "msg": "a message, not a list"}]
        }
        bodies = [
            c.get(f"{API}/jobs?limit=x", headers=alice),
            c.post(f"{API}/jobs", content=b'{"a": NaN}', headers=alice),
            c.post(f"{API}/jobs", content=b"{", headers=alice),
            c.post(f"{API}/jobs", json={"problem": {"kind": "nope"}}, headers=alice),
            c.get(f"{API}/sweeps/x/recording?jobs=y", headers=alice),  # 404: no such sweep
        ]
        for r in bodies[:-1]:
            assert r.status_code == 422 and isinstance(r.json()["detail"], list), r.text
            assert all({"loc", "msg", "type"} <= set(e) for e in r.json()["detail"])
        assert bodies[-1].status_code == 404 and isinstance(bodies[-1].json()["detail"], str)
        spec = c.get(f"{API}/openapi.json").json()
    validation = {"$ref": "#/components/schemas/HTTPValidationError"}
    for path, operations in spec["paths"].items():
        for method, op in operations.items():
            doc = op.get("responses", {}).get("422")
            if doc is not None:
                assert doc["content"]["application/json"]["schema"] == validation, (method, path)


@pytest.mark.parametrize(
    ("body", "loc"),
    [
        ({"seeds": [False]}, ["body", "seeds", 0]),
        ({"seeds": [1, True]}, ["body", "seeds", 1]),
        ({"grid": {"seed": [0, False]}}, ["body", "grid", "seed", 1]),
        ({"grid": {"budget.generations": [True]}}, ["body", "grid", "budget.generations", 0]),
        ({"list": [{"budget.window": True}]}, ["body", "list", 0, "budget.window"]),
    ],
)
def test_a_sweep_refuses_booleans_as_integers(
    client: TestClient, ctx: ApiContext, alice: dict[str, str], body: dict[str, Any], loc: list[Any]
) -> None:
    sweep = {"base": {"problem": {"kind": KIND}}, **body}
    r = client.post(f"{API}/sweeps", json=sweep, headers=alice)
    assert loc in locs(r), r.text
    with ctx.read() as s:
        assert repo.list_sweeps(s, limit=10, offset=0).total == 0  # nothing stored


def test_a_job_refuses_booleans_as_integers(client: TestClient, alice: dict[str, str]) -> None:
    base: dict[str, Any] = {"problem": {"kind": "swing_energy"}}
    for extra, loc in [
        ({"seed": True}, ["body", "seed"]),
        ({"seed": False}, ["body", "seed"]),
        ({"budget": {"generations": True}}, ["body", "budget", "generations"]),
        ({"budget": {"evaluations": False}}, ["body", "budget", "evaluations"]),
        ({"optimizer": {"kind": "ga", "refine_max_iter": True}},
         ["body", "optimizer", "refine_max_iter"]),
        ({"optimizer": {"kind": "ga", "params": {"pop_size": True}}},
         ["body", "optimizer", "params", "pop_size"]),
        ({"problem": {"kind": "swing_energy", "n_via": True}}, ["body", "problem", "n_via"]),
    ]:  # fmt: skip
        r = client.post(f"{API}/jobs", json={**base, **extra}, headers=alice)
        assert loc in locs(r), (extra, r.text)
    ok = client.post(f"{API}/jobs", json={**base, "seed": 3, "record": True}, headers=alice)
    assert ok.status_code == 202 and ok.json()["spec"]["seed"] == 3  # booleans where bool


def test_a_key_refuses_booleans_as_integer_limits(client: TestClient, ctx: ApiContext) -> None:
    raw, key_hash = generate_api_key()
    with ctx.write() as s:
        api_keys.create_api_key(s, name="root", key_hash=key_hash, role=KeyRole.ADMIN)
    admin = {"X-API-Key": raw}
    for field in ("max_active_jobs", "max_storage_bytes"):
        r = client.post(f"{API}/keys", json={"name": "k", field: True}, headers=admin)
        assert locs(r) == [["body", field]], r.text
    assert client.post(f"{API}/keys", json={"name": "k", "max_active_jobs": 2},
                       headers=admin).status_code == 201  # fmt: skip


def test_the_description_states_the_conventions(tmp_path: Path) -> None:
    """The API's description states both conventions (the OpenAPI page shows it)."""
    app = create_app(Settings.from_env(env={}, data_dir=tmp_path), enqueue=lambda _id: None)
    assert "every 422 has this shape" in (app.description or "")
    assert "X-Content-Type-Options: nosniff" in (app.description or "")


def test_the_pages_allow_and_hold_no_inline_script_or_style(client: TestClient) -> None:
    from services.web import STATIC_DIR

    for path in ("/", "/viewer/"):
        csp = client.get(path).headers["content-security-policy"]
        assert "'unsafe-inline'" not in csp and "'unsafe-eval'" not in csp, (path, csp)
        assert "script-src 'self'" in csp and "default-src 'self'" in csp, (path, csp)
    for page in ("index.html", "viewer.html"):
        html = (STATIC_DIR / page).read_text()
        assert not re.search(r"<script(?![^>]*\bsrc=)[^>]*>", html), page  # only files
        assert "<style" not in html and not re.search(r"\sstyle=", html), page
    for js in sorted((STATIC_DIR / "js").rglob("*.js")):
        text = js.read_text()
        for refused in ("eval(", "new Function", 'setAttribute("style"', "innerHTML"):
            assert refused not in text, (js.name, refused)
