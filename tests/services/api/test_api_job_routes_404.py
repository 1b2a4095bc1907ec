"""Every route of one job (``/jobs/{job_id}…``, enumerated from the app) answers another key's
job exactly as a job that does not exist: 404 ``job '<id>' not found`` (the shared lookup,
``services.api.lookups``), whatever else the request holds — before any 409 about the job's
state and, on the routes that take the job as the ``OwnedJob`` dependency, before any 422
about the query. ``tests/security/test_cross_tenant.py`` checks every route with a path id
against an unknown id; this one pins the job routes' one message."""

from __future__ import annotations

import re
import uuid
from typing import Any

from api_helpers import finish_like_a_worker
from fastapi import routing
from fastapi.testclient import TestClient

from services.api.deps import ApiContext

API = "/api/v1"
PARAM = re.compile(r"{(\w+)}")
#: The path parameters beside ``job_id``: a front point, a trial, the stored baseline.
OTHERS = {"k": "0", "t": "0", "name": "parabolic"}
#: Query parameters that are out of range on the routes that take them (a 422 for Alice).
BAD_QUERIES = {
    "/jobs/{job_id}/motion": "point=-1",
    "/jobs/{job_id}/trials": "generation=0",
    "/jobs/{job_id}/trials/columns": "max_rows=1",
}


def _job_routes(client: TestClient) -> list[tuple[str, str]]:
    iterate = getattr(routing, "iter_route_contexts", None)  # FastAPI >= 0.160: lazy includes
    app: Any = client.app
    routes = list(iterate(app.routes)) if iterate is not None else list(app.routes)
    found = []
    for route in routes:
        path = getattr(route, "path", None)
        if not isinstance(path, str) or not path.startswith(f"{API}/jobs/{{job_id}}"):
            continue
        for method in sorted(set(getattr(route, "methods", None) or ()) - {"HEAD", "OPTIONS"}):
            found.append((method, path.removeprefix(API)))
    return found


def _url(path: str, job_id: str) -> str:
    return API + PARAM.sub(lambda m: job_id if m[1] == "job_id" else OTHERS[m[1]], path)


def test_every_job_route_is_the_same_404_for_another_keys_job(
    client: TestClient, ctx: ApiContext, alice: dict[str, str], bob: dict[str, str]
) -> None:
    spec = {"problem": {"kind": "path_tracking"}, "budget": {"generations": 2}}
    done = client.post(f"{API}/jobs", json=spec, headers=alice).json()["id"]
    finish_like_a_worker(ctx, done, n_pareto=3)
    queued = client.post(f"{API}/jobs", json=spec, headers=alice).json()["id"]
    routes = _job_routes(client)
    assert len(routes) >= 20, routes
    assert {p for _, p in routes} >= set(BAD_QUERIES), routes
    # deletes last, so that every other route still sees Alice's jobs
    for method, path in sorted(routes, key=lambda r: r[0] == "DELETE"):
        for job_id in (done, queued, str(uuid.uuid4())):
            r = client.request(method, _url(path, job_id), headers=bob)
            where = f"{method} {path} as Bob ({job_id})"
            assert r.status_code == 404, f"{where}: {r.status_code} {r.text[:300]}"
            assert r.json() == {"detail": f"job {job_id!r} not found"}, where
    assert client.get(f"{API}/jobs/{done}", headers=alice).status_code == 200


def test_another_keys_job_is_a_404_before_a_bad_query(
    client: TestClient, alice: dict[str, str], bob: dict[str, str]
) -> None:
    spec = {"problem": {"kind": "path_tracking"}, "budget": {"generations": 2}}
    job_id = client.post(f"{API}/jobs", json=spec, headers=alice).json()["id"]
    for path, query in BAD_QUERIES.items():
        url = f"{_url(path, job_id)}?{query}"
        assert client.get(url, headers=alice).status_code == 422, url
        r = client.get(url, headers=bob)
        assert r.status_code == 404 and r.json() == {"detail": f"job {job_id!r} not found"}, url
