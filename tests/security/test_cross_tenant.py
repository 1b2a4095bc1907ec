"""Cross-tenant access on every route of the in-process app (issue 8, security suite).

Alice creates one of everything (a robot, a sweep whose first job finished like a worker would
finish it, with a real Rerun recording); then Bob calls every method of every route that takes
a path id with Alice's ids. Bob must get exactly what he gets for an id that does not exist: a
404 (or, on a route that documents a 403 because it needs an admin key, that 403), never 200 or
500, never a different message — the answer is no oracle of what exists. Bob's listings never
show Alice's items, and ids or idempotency keys of Alice's put in Bob's bodies and queries are
unknown to him.

Runs on both databases (``db_settings``: SQLite, and PostgreSQL where it answers): a 404 must
not become a 500 where PostgreSQL types an id column more strictly than SQLite does.

Routes are enumerated from the app itself (``app.routes``), so a route added later is covered
the day it appears; a path parameter (or a request body) this test cannot fill makes it fail
with "add a fixture for {path}".
"""

from __future__ import annotations

import re
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from fastapi import FastAPI, routing
from fastapi.testclient import TestClient
from httpx import Response

from services.api.app import create_app
from services.api.deps import ApiContext
from services.store.api_keys import create_api_key
from services.store.keys import generate_api_key
from services.store.settings import Settings
from tests.services.api.api_helpers import dh_spec

API = "/api/v1"
PATH_PARAM = re.compile(r"{(\w+)(?::[^}]*)?}")

#: Request bodies of routes that take a path id AND a body (none today); key: (METHOD, path).
BODIES: dict[tuple[str, str], Any] = {}

DH_ARM = dh_spec()


@dataclass
class Tenants:
    """The app, Alice's and Bob's headers, and the ids of Alice's resources by parameter name
    (``robot_id``, ``job_id``, ``sweep_id``, ``key_id``)."""

    app: FastAPI
    client: TestClient
    alice: dict[str, str]
    bob: dict[str, str]
    ids: dict[str, str]
    alice_job_ids: list[str]


def _key(ctx: ApiContext, name: str) -> tuple[dict[str, str], str]:
    raw, key_hash = generate_api_key()
    with ctx.write() as session:
        record = create_api_key(session, name=name, key_hash=key_hash)
    return {"X-API-Key": raw}, record.id


def _real_recording(tmp: Path) -> bytes:
    """A small valid .rrd (the merged sweep recording reads it back)."""
    from services.recording.writer import write_recording
    from tests.recording_fixtures import arm_motion, fake_result

    path = tmp / "job.rrd"
    write_recording(fake_result(arm_motion(K=50)), path)  # type: ignore[arg-type]
    return path.read_bytes()


@pytest.fixture(scope="module")
def tenants(db_settings: Settings) -> Iterator[Tenants]:
    from tests.services.api.api_helpers import finish_like_a_worker

    data = db_settings.data_dir
    app = create_app(db_settings, enqueue=lambda _job_id: None)
    ctx: ApiContext = app.state.context
    alice, alice_key_id = _key(ctx, "alice")
    bob, _ = _key(ctx, "bob")
    with TestClient(app, raise_server_exceptions=False) as client:
        r = client.post(f"{API}/robots", json={"name": "alice_arm", "spec": DH_ARM}, headers=alice)
        assert r.status_code == 201, r.text
        robot_id = r.json()["id"]
        sweep = {
            "base": {"problem": {"kind": "path_tracking"}, "budget": {"generations": 2}},
            "seeds": [1, 2],
        }
        r = client.post(f"{API}/sweeps", json=sweep, headers=alice)
        assert r.status_code == 202, r.text
        sweep_id, job_ids = r.json()["id"], r.json()["job_ids"]
        finish_like_a_worker(ctx, job_ids[0], recording=_real_recording(data))
        # a queued job of no sweep (Alice's own calls of every route cancel her sweep's jobs)
        r = client.post(f"{API}/jobs", json=sweep["base"], headers=alice)
        assert r.status_code == 202, r.text
        job_ids.append(r.json()["id"])
        ids = {"robot_id": robot_id, "job_id": job_ids[0], "sweep_id": sweep_id}
        ids["key_id"] = alice_key_id
        ids["k"] = ids["t"] = "0"  # a front point, a trial
        ids["name"] = "parabolic"  # the baseline finish_like_a_worker stores
        yield Tenants(app, client, alice, bob, ids, job_ids)


@dataclass(frozen=True)
class RouteCase:
    """One method of one route of the app."""

    method: str
    path: str
    params: tuple[str, ...]
    has_body: bool
    documents_403: bool


def app_routes(app: FastAPI) -> list[RouteCase]:
    """Every HTTP method of every route of ``app`` (routers included, prefixes applied)."""
    iterate = getattr(routing, "iter_route_contexts", None)  # FastAPI >= 0.160: lazy includes
    routes = list(iterate(app.routes)) if iterate is not None else list(app.routes)
    cases = []
    for route in routes:
        path = getattr(route, "path", None)
        methods = getattr(route, "methods", None) or set()
        if not isinstance(path, str):
            continue
        responses = getattr(route, "responses", None) or {}
        for method in sorted(set(methods) - {"HEAD", "OPTIONS"}):
            cases.append(
                RouteCase(
                    method=method,
                    path=path,
                    params=tuple(PATH_PARAM.findall(path)),
                    has_body=getattr(route, "body_field", None) is not None,
                    documents_403=403 in responses or "403" in responses,
                )
            )
    return cases


def fill(path: str, ids: dict[str, str]) -> str:
    """``path`` with each ``{name}`` replaced by ``ids[name]``; fails naming the route when
    this test has no id for a parameter."""
    missing = [name for name in PATH_PARAM.findall(path) if name not in ids]
    assert not missing, (
        f"add a fixture for {path}: tests/security/test_cross_tenant.py has no id of Alice's "
        f"for {missing} (create the resource in the `tenants` fixture and add it to `ids`)"
    )
    return PATH_PARAM.sub(lambda m: ids[m.group(1)], path)


def call(client: TestClient, case: RouteCase, url: str, headers: dict[str, str]) -> Response:
    body = BODIES.get((case.method, case.path))
    if case.has_body:
        assert body is not None, (
            f"add a fixture for {case.path}: {case.method} takes a request body; add one to "
            "BODIES in tests/security/test_cross_tenant.py"
        )
    return client.request(case.method, url, headers=headers, json=body)


def masked(response: Response, *ids: str) -> str:
    """The response text with the given ids replaced (to compare two answers)."""
    text = response.text
    for ident in ids:
        text = text.replace(ident, "<id>")
    return text


@pytest.mark.slow
def test_every_route_with_a_path_id_is_404_for_another_key(tenants: Tenants) -> None:
    with_ids = [c for c in app_routes(tenants.app) if c.params]
    assert len(with_ids) >= 9, [f"{c.method} {c.path}" for c in with_ids]
    # destructive methods last, so every other route still sees Alice's resources
    with_ids.sort(key=lambda c: c.method == "DELETE")
    for case in with_ids:
        url = fill(case.path, tenants.ids)
        nobody = {name: str(uuid.uuid4()) for name in tenants.ids}
        as_bob = call(tenants.client, case, url, tenants.bob)
        expected = 403 if case.documents_403 else 404
        where = f"{case.method} {url} as Bob (Alice's ids)"
        assert as_bob.status_code == expected, f"{where}: {as_bob.status_code} {as_bob.text[:300]}"
        unknown = call(tenants.client, case, fill(case.path, nobody), tenants.bob)
        assert unknown.status_code == as_bob.status_code, (where, unknown.text[:300])
        assert masked(as_bob, *tenants.ids.values()) == masked(unknown, *nobody.values()), (
            f"{where}: the answer differs from the one for an id that does not exist, so it "
            f"tells Bob that Alice's exists: {as_bob.text[:200]!r} vs {unknown.text[:200]!r}"
        )

    # Alice's resources are intact, and each route does answer Alice (the ids were real)
    for case in with_ids:
        if case.documents_403:  # admin routes: Alice is no admin either
            continue
        r = call(tenants.client, case, fill(case.path, tenants.ids), tenants.alice)
        assert r.status_code < 500 and r.status_code != 404, (
            f"{case.method} {case.path} as Alice: {r.status_code} {r.text[:300]}"
        )


def test_listings_of_another_key_never_show_alice_items(tenants: Tenants) -> None:
    alice_ids = [v for name, v in tenants.ids.items() if name not in ("k", "t", "name")]
    alice_ids += tenants.alice_job_ids
    listings = [c for c in app_routes(tenants.app) if c.method == "GET" and not c.params]
    assert len(listings) >= 5, listings
    queries = {
        f"{API}/robots": ["include_catalog=true&limit=1000"],
        f"{API}/jobs": [
            f"sweep_id={tenants.ids['sweep_id']}",
            "status=succeeded&status=queued&limit=1000",
        ],
    }
    for case in listings:
        for query in ["", *queries.get(case.path, [])]:
            url = f"{case.path}?{query}" if query else case.path
            r = tenants.client.get(url, headers=tenants.bob)
            assert r.status_code < 500, f"GET {url} as Bob: {r.status_code} {r.text[:300]}"
            leaked = [i for i in alice_ids if i in r.text]
            assert not leaked, f"GET {url} as Bob shows Alice's {leaked}"


def test_alice_references_are_unknown_to_bob(tenants: Tenants) -> None:
    client, bob, ids = tenants.client, tenants.bob, tenants.ids
    for robot in (ids["robot_id"], "alice_arm"):
        job = {"problem": {"kind": "path_tracking"}, "robot": robot}
        r = client.post(f"{API}/jobs", json=job, headers=bob)
        assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["body", "robot"], r.text
        sweep = {"base": job, "seeds": [1]}
        r = client.post(f"{API}/sweeps", json=sweep, headers=bob)
        assert r.status_code == 422, r.text
    r = client.post(
        f"{API}/sweeps", json={"base": {"problem": {"kind": "path_tracking"}}}, headers=bob
    )
    assert r.status_code == 202, r.text
    bobs = r.json()["id"]
    r = client.get(f"{API}/sweeps/{bobs}/recording?jobs={ids['job_id']}", headers=bob)
    assert r.status_code in (404, 422) and "RRF" not in r.text, r.text[:300]
    assert client.get(f"{API}/jobs?sweep_id={ids['sweep_id']}", headers=bob).json()["total"] == 0


def test_bob_cannot_cancel_or_delete_alice_jobs(tenants: Tenants) -> None:
    queued = tenants.alice_job_ids[-1]  # of no sweep: still queued
    sweep = tenants.ids["sweep_id"]
    for method, url in (
        ("POST", f"{API}/jobs/{queued}/cancel"),
        ("DELETE", f"{API}/jobs/{queued}"),
        ("POST", f"{API}/sweeps/{sweep}/cancel"),
    ):
        r = tenants.client.request(method, url, headers=tenants.bob)
        assert r.status_code == 404, f"{method} {url} as Bob: {r.status_code} {r.text[:200]}"
    r = tenants.client.get(f"{API}/jobs/{queued}", headers=tenants.alice)
    assert r.status_code == 200 and r.json()["status"] == "queued", r.text[:300]
    assert r.json()["cancel_requested"] is False


def test_idempotency_keys_are_per_api_key(tenants: Tenants) -> None:
    client, alice, bob = tenants.client, tenants.alice, tenants.bob
    job = {"problem": {"kind": "path_tracking"}, "budget": {"generations": 2}, "seed": 7}
    other = {**job, "seed": 8}

    key = {"Idempotency-Key": f"shared-{uuid.uuid4()}"}
    first = client.post(f"{API}/jobs", json=job, headers={**alice, **key})
    assert first.status_code == 202, first.text
    same = client.post(f"{API}/jobs", json=job, headers={**bob, **key})
    assert same.status_code == 202 and same.json()["id"] != first.json()["id"], (
        f"Bob's request with Alice's idempotency key answered Alice's job: {same.text[:300]}"
    )

    key = {"Idempotency-Key": f"shared-{uuid.uuid4()}"}
    assert client.post(f"{API}/jobs", json=job, headers={**alice, **key}).status_code == 202
    r = client.post(f"{API}/jobs", json=other, headers={**bob, **key})
    assert r.status_code == 202, f"Bob learns that Alice used this key: {r.text[:300]}"


def test_a_route_without_a_fixture_fails_asking_for_one() -> None:
    app = FastAPI()

    @app.get("/api/v1/widgets/{widget_id}")
    def widget(widget_id: str) -> dict[str, str]:
        return {"id": widget_id}

    (case,) = [c for c in app_routes(app) if c.params]
    assert case.params == ("widget_id",)
    with pytest.raises(AssertionError, match=r"add a fixture for /api/v1/widgets/\{widget_id\}"):
        fill(case.path, {"job_id": "x"})
