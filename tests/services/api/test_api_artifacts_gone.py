"""Nothing the database knows depends on a file (issue 20): real jobs run by the real executor,
then their artifact files (local directory) or objects (S3, a real moto server over HTTP)
removed, or the S3 store unreachable — every job and sweep route answers 200, a clear 404
naming what is missing, or 503 for the unreachable store, never a 500. And recordings download
from the S3 backend with HTTP Range support (the Rerun viewer fetches ranges), streamed or
redirected to a presigned URL, byte-identical to their recorded SHA-256."""

from __future__ import annotations

import hashlib
import os
import re
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from urllib.parse import quote

import httpx
import pytest
from api_helpers import fresh_app
from fastapi.testclient import TestClient

from services.api.app import create_app
from services.client import Client
from services.store import output_queries as oq
from services.store.settings import Settings
from services.worker.execute import execute_job
from tests.s3_server import aws_env, free_port, moto_server, s3_client

pytestmark = pytest.mark.slow  # real jobs: the quick lane leaves it out

API = "/api/v1"
SPEC: dict[str, Any] = {
    "name": "artifacts gone",
    "problem": {"kind": "path_tracking", "objective": "energy_time"},
    "optimizer": {"kind": "nsga2", "params": {"pop_size": 24}},
    "budget": {"generations": 8},
    "seed": 2,
}
PREFIX = "legopt/gone"


@pytest.fixture(scope="module")
def env(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """One job and a sweep of two, recorded, run to the end with the local artifact store."""
    with fresh_app(tmp_path_factory.mktemp("gone"), "alice") as app:
        client, settings, alice = app.client, app.settings, app.keys["alice"]
        r = client.post(f"{API}/jobs", json=SPEC, headers=alice)
        assert r.status_code == 202, r.text
        job = r.json()["id"]
        r = client.post(f"{API}/sweeps", json={"base": SPEC, "seeds": [1, 2]}, headers=alice)
        assert r.status_code == 202, r.text
        sweep, members = r.json()["id"], r.json()["job_ids"]
        for j in [job, *members]:
            assert execute_job(j, settings).status == "succeeded"
        baselines = client.get(f"{API}/jobs/{job}/front", headers=alice).json()["baselines"]
        yield {"client": client, "settings": settings, "alice": alice, "job": job,
               "sweep": sweep, "baseline": quote(baselines[0]["name"]), "mp": app.mp}  # fmt: skip


@pytest.fixture(scope="module")
def s3env(env: dict[str, Any]) -> Iterator[dict[str, Any]]:
    """The same jobs' files copied to a bucket of a moto server, plus one job whose worker wrote
    its files to S3 itself; settings of the S3 store."""
    aws_env(env["mp"])
    with moto_server() as endpoint:
        client = s3_client(endpoint)
        client.create_bucket(Bucket="legopt-gone")
        root = env["settings"].artifact_dir
        for path in root.rglob("*"):
            if path.is_file():
                key = f"{PREFIX}/{path.relative_to(root).as_posix()}"
                client.put_object(Bucket="legopt-gone", Key=key, Body=path.read_bytes())
        settings: Settings = env["settings"].with_overrides(
            artifacts_url=f"s3://legopt-gone/{PREFIX}", s3_endpoint_url=endpoint
        )
        r = env["client"].post(f"{API}/jobs", json={**SPEC, "seed": 3}, headers=env["alice"])
        s3_job = r.json()["id"]
        assert execute_job(s3_job, settings).status == "succeeded"
        assert not (root / s3_job).exists()  # on S3 only
        yield {**env, "s3": client, "s3_settings": settings, "s3_job": s3_job}


def app_client(settings: Settings) -> TestClient:
    return TestClient(create_app(settings, enqueue=lambda _j: None))


def job_routes(client: TestClient, env: dict[str, Any]) -> list[str]:
    """Every GET route of a job or a sweep (from the OpenAPI document), filled in."""
    paths = client.get(f"{API}/openapi.json").json()["paths"]
    values = {"job_id": env["job"], "sweep_id": env["sweep"], "k": "0", "t": "0",
              "name": env["baseline"]}  # fmt: skip
    routes = []
    for path, ops in paths.items():
        params = re.findall(r"{(\w+)}", path)
        if "get" not in ops or not params or not set(params) <= set(values):
            continue
        routes.append(re.sub(r"{(\w+)}", lambda m: values[m.group(1)], path))
    assert len(routes) >= 15 and any(r.endswith("/recording") for r in routes)
    return routes


def check_every_route(client: TestClient, env: dict[str, Any], allowed: set[int]) -> dict:
    """GET every job and sweep route: never a 500, only ``allowed`` statuses, a 404 or 503
    says what; returns {route: response}."""
    answers = {}
    for route in job_routes(client, env):
        r = client.get(route, headers=env["alice"])
        assert r.status_code in allowed, f"{route}: {r.status_code} {r.text[:300]}"
        if r.status_code in (404, 503):
            assert r.json()["detail"], route
        answers[route] = r
    return answers


def check_database_answers(answers: dict, env: dict[str, Any], reachable: bool = True) -> None:
    """What the database holds is served whatever happened to the files: the study's extras
    are made again from the stored spec and front (``reachable``: the store takes the new
    file), or are empty with a warning saying why."""
    job = f"{API}/jobs/{env['job']}"
    assert answers[job].json()["status"] == "succeeded"
    result = answers[f"{job}/result"].json()
    if reachable:
        assert result["objectives"] and result["summary"]["extras"]
        assert "extras_warning" not in result["summary"]
    else:
        assert result["objectives"] and result["summary"]["extras"] == {}
        assert "unavailable" in result["summary"]["extras_warning"]
    front = answers[f"{job}/front"].json()
    assert front["points"] and front["baselines"]
    for route in (
        f"{job}/pareto",
        f"{job}/generations",
        f"{job}/front/export",
        f"{job}/history/export",
        f"{job}/spec.yaml",
        f"{API}/sweeps/{env['sweep']}",
    ):
        assert answers[route].status_code == 200, route  # fmt: skip


def test_removed_files_are_404s_naming_them(env: dict[str, Any]) -> None:
    root: Path = env["settings"].artifact_dir
    aside = root.with_name("artifacts-aside")
    os.rename(root, aside)
    try:
        with app_client(env["settings"]) as client:
            answers = check_every_route(client, env, {200, 404, 409})
        check_database_answers(answers, env)
        rec = answers[f"{API}/jobs/{env['job']}/recording"]
        assert rec.status_code == 404
        assert f"the recording of job {env['job']} is missing" in rec.json()["detail"]
        merged = answers[f"{API}/sweeps/{env['sweep']}/recording"]
        assert merged.status_code == 404 and "is missing" in merged.json()["detail"]
        # a front point's and a baseline's recording are made again (only the DB is needed)
        point = answers[f"{API}/jobs/{env['job']}/pareto/0/recording"]
        assert point.status_code == 200 and point.content[:4] == b"RRF2"
        baseline = answers[f"{API}/jobs/{env['job']}/baselines/{env['baseline']}/recording"]
        assert baseline.status_code == 200
    finally:  # the files back, but not over those made again (their rows name them now)
        for path in sorted(aside.rglob("*")):
            back = root / path.relative_to(aside)
            if path.is_file() and not back.exists():
                back.parent.mkdir(parents=True, exist_ok=True)
                os.replace(path, back)
        shutil.rmtree(aside)


def test_removed_objects_are_404s_naming_them(s3env: dict[str, Any]) -> None:
    s3, bucket = s3env["s3"], "legopt-gone"
    kept = {o["Key"]: s3.get_object(Bucket=bucket, Key=o["Key"])["Body"].read()
            for o in s3.list_objects_v2(Bucket=bucket)["Contents"]}  # fmt: skip
    s3.delete_objects(Bucket=bucket, Delete={"Objects": [{"Key": k} for k in kept]})
    try:
        with app_client(s3env["s3_settings"]) as client:
            answers = check_every_route(client, s3env, {200, 404, 409})
        check_database_answers(answers, s3env)
        rec = answers[f"{API}/jobs/{s3env['job']}/recording"]
        assert rec.status_code == 404 and "is missing" in rec.json()["detail"]
        assert answers[f"{API}/sweeps/{s3env['sweep']}/recording"].status_code == 404
        assert answers[f"{API}/jobs/{s3env['job']}/pareto/0/recording"].status_code == 200
    finally:  # the objects back, but not over those made again (their rows name them now)
        made = {o["Key"] for o in s3.list_objects_v2(Bucket=bucket).get("Contents", [])}
        for key, body in kept.items():
            if key not in made:
                s3.put_object(Bucket=bucket, Key=key, Body=body, ChecksumAlgorithm="SHA256")


def test_an_unreachable_store_is_503_and_the_rest_of_the_page_200(
    s3env: dict[str, Any],
) -> None:
    dead = s3env["s3_settings"].with_overrides(s3_endpoint_url=f"http://127.0.0.1:{free_port()}")
    with app_client(dead) as client:
        answers = check_every_route(client, s3env, {200, 409, 503})
        check_database_answers(answers, s3env, reachable=False)
        job = f"{API}/jobs/{s3env['job']}"
        assert "cannot be reached" in answers[f"{job}/result"].json()["summary"]["extras_warning"]
        for route in (f"{job}/recording", f"{job}/pareto/0/recording",
                      f"{API}/sweeps/{s3env['sweep']}/recording"):  # fmt: skip
            r = answers[route]
            assert r.status_code == 503 and r.headers["retry-after"], route
            assert "artifact store cannot be reached" in r.json()["detail"]
        front = answers[f"{job}/front"].json()
        assert front["points"] and front["point_metrics"] == "unavailable"
        assert "cannot be reached" in front["point_metrics_note"]


def test_s3_recording_downloads_honour_ranges(s3env: dict[str, Any]) -> None:
    alice, job = s3env["alice"], s3env["s3_job"]
    with app_client(s3env["s3_settings"]) as client:
        full = client.get(f"{API}/jobs/{job}/recording", headers=alice)
        assert full.status_code == 200, full.text
        sha = full.headers["x-checksum-sha256"]
        assert hashlib.sha256(full.content).hexdigest() == sha and full.content[:4] == b"RRF2"
        with client.app.state.context.read() as s:  # type: ignore[attr-defined]
            art = oq.get_artifact(s, job, "recording")
        assert art is not None and art.sha256 == sha and art.size_bytes == len(full.content)
        assert full.headers["accept-ranges"] == "bytes"
        assert full.headers["content-disposition"] == f'attachment; filename="{job}.rrd"'
        size = len(full.content)

        def get(byte_range: str) -> Any:
            return client.get(f"{API}/jobs/{job}/recording", headers={**alice, "Range": byte_range})

        first = get("bytes=0-99")
        assert first.status_code == 206 and first.content == full.content[:100]
        assert first.headers["content-range"] == f"bytes 0-99/{size}"
        assert first.headers["content-length"] == "100"
        assert first.headers["x-checksum-sha256"] == sha
        middle = get(f"bytes=100-{size + 50}")  # past the end: up to the end
        assert middle.status_code == 206 and middle.content == full.content[100:]
        assert get("bytes=-10").content == full.content[-10:]
        assert get("bytes=0-1,5-9").status_code == 200  # several ranges: the whole file
        past = get(f"bytes={size}-")
        assert past.status_code == 416 and past.headers["content-range"] == f"bytes */{size}"
        # a front point's recording is made on demand and stored on S3 as well
        point = client.get(f"{API}/jobs/{job}/pareto/0/recording", headers=alice)
        assert point.status_code == 200
        assert hashlib.sha256(point.content).hexdigest() == point.headers["x-checksum-sha256"]
        assert get("bytes=0-3").content == b"RRF2"


def test_s3_recording_can_redirect_to_a_presigned_url(s3env: dict[str, Any]) -> None:
    alice, job = s3env["alice"], s3env["s3_job"]
    presign = s3env["s3_settings"].with_overrides(artifacts_presign=True)
    app = create_app(presign, enqueue=lambda _j: None)
    with TestClient(app) as client:
        r = client.get(f"{API}/jobs/{job}/recording", headers=alice, follow_redirects=False)
    http = TestClient(
        app, base_url=f"http://testserver{API}", headers=alice, follow_redirects=False
    )
    with http:
        legopt = Client("http://testserver")  # what `legopt replay` uses
        legopt.http = http
        via_client = legopt.recording(job)  # follows the redirect, without the API key
    assert r.status_code == 307 and r.headers["x-checksum-sha256"]
    url = r.headers["location"]
    assert url.startswith(presign.s3_endpoint_url) and "Signature" in url
    body = httpx.get(url).content  # from the store itself, over HTTP
    assert hashlib.sha256(body).hexdigest() == r.headers["x-checksum-sha256"]
    assert via_client == body
    part = httpx.get(url, headers={"Range": "bytes=0-99"})
    assert part.status_code == 206 and part.content == body[:100]
