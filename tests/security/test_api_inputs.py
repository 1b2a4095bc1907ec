"""Hostile request bodies against the in-process API: each is a 422 (or 413) naming where the
problem is, never a 500, and the API keeps answering (issue 8, defect 10): a tiny hexapod
pose-grid step (``extent / 1e-320`` overflows), NaN / Infinity / 1e309 anywhere in a body,
nesting 65 to 100 000 levels deep, oversized bodies, absurd job sizes, NUL characters.
Amplification (defect 9): ``test_api_amplification.py``.

The API tests run on both databases (``db_settings``: SQLite, and PostgreSQL where it answers).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any

import pytest

from services.api.body_limit import DEFAULT_MAX_BODY_BYTES
from services.store.settings import Settings
from tests.security.api_inputs_helpers import API, JSON, Api, error_at, in_process_api

#: ``services.api.json_guard.MAX_JSON_DEPTH`` (imported in the tests: this module must load on
#: the code before the fix, to show each test failing there on its own).
MAX_JSON_DEPTH = 64


@pytest.fixture(scope="module")
def api(db_settings: Settings) -> Iterator[Api]:
    with in_process_api(db_settings) as api:
        yield api


# --------------------------------------------------------------------------- defect 10


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("pose_yaw_step", 1e-320),  # extent / step = inf: OverflowError -> 500 before
        ("pose_xy_step", 5e-324),
        ("pose_xy_step", 1e-300),
        ("pose_yaw_step", 1e-7),
    ],
)
def test_tiny_hexapod_step_is_422_at_the_step_with_its_range(
    api: Api, field: str, value: float
) -> None:
    body = {"problem": {"kind": "hexapod_workspace", field: value}}
    r = api.post("/jobs", json.dumps(body))
    err = error_at(r, ["body", "problem", field])
    assert "allowed range" in err["msg"] and "2000000" in err["msg"], err
    assert len(err["msg"]) < 400, "the message must not print a 300-digit pose count"

    sweep = {
        "base": {"problem": {"kind": "hexapod_workspace"}},
        "grid": {f"problem.{field}": [value]},
    }
    r = api.post("/sweeps", json.dumps(sweep))
    error_at(r, ["body", "grid", f"problem.{field}", 0])


def test_suggested_hexapod_step_is_accepted(api: Api) -> None:
    r = api.post("/jobs", json.dumps({"problem": {"kind": "hexapod_workspace", "pose_xy_step": 0}}))
    assert r.status_code == 422
    tiny = {"problem": {"kind": "hexapod_workspace", "pose_xy_step": 1e-9}}
    msg = error_at(api.post("/jobs", json.dumps(tiny)), ["body", "problem", "pose_xy_step"])["msg"]
    smallest = float(msg.split("use a step >= ")[1].split(" ")[0])
    body = {"problem": {"kind": "hexapod_workspace", "pose_xy_step": smallest}}
    r = api.post("/jobs", json.dumps(body))
    assert r.status_code == 202, f"the step the message suggests is refused: {r.text[:300]}"


SWEEP = '{"base": {"problem": {"kind": "path_tracking"}}, %s}'
ROBOT_SPEC = (
    '{"kind": "dh", "name": "a", "joints": [{"a": %s, "mass": 1.0, "com": [0, 0, 0], '
    '"inertia": [[0.001, 0, 0], [0, 0.001, 0], [0, 0, 0.001]]}]}'
)
NON_FINITE = ["NaN", "Infinity", "-Infinity", "1e309", "-1e400"]
NON_FINITE_CASES = [
    ("/sweeps", SWEEP % '"seeds": [%s]', ["body", "seeds", 0]),
    ("/sweeps", SWEEP % '"seeds": [1, 2, %s]', ["body", "seeds", 2]),
    ("/sweeps", SWEEP % '"grid": {"seed": [%s]}', ["body", "grid", "seed", 0]),
    ("/sweeps", SWEEP % '"list": [{"problem.v_max": %s}]', ["body", "list", 0, "problem.v_max"]),
    ("/robots", '{"name": "r", "catalog": %s}', ["body", "catalog"]),
    ("/robots", '{"name": %s, "catalog": "puma560"}', ["body", "name"]),
    ("/robots", '{"name": "r", "spec": ' + ROBOT_SPEC + "}", ["body", "spec", "joints", 0, "a"]),
    ("/robots/validate", '{"spec": ' + ROBOT_SPEC + "}", ["body", "spec", "joints", 0, "a"]),
    ("/jobs", '{"problem": {"kind": "path_tracking"}, "seed": %s}', ["body", "seed"]),
    ("/jobs", '{"problem": {"kind": "path_tracking"}, "robot": %s}', ["body", "robot"]),
    ("/jobs", '{"problem": {"kind": "swing_energy", "w1": %s}}', ["body", "problem", "w1"]),
]


@pytest.mark.parametrize("literal", NON_FINITE)
@pytest.mark.parametrize(("path", "template", "loc"), NON_FINITE_CASES)
def test_non_finite_number_is_422_at_its_location(
    api: Api, path: str, template: str, loc: list[Any], literal: str
) -> None:
    r = api.post(path, template % literal)
    err = error_at(r, loc, "finite_number")
    assert "finite" in err["msg"]


DEPTHS = [MAX_JSON_DEPTH + 1, 700, 900, 5000, 100_000]


def _nested(depth: int, kind: str) -> str:
    if kind == "list":
        return "[" * depth + "1" + "]" * depth
    return '{"a": ' * depth + "1" + "}" * depth


@pytest.mark.parametrize("depth", DEPTHS)
def test_deep_nesting_is_422_before_anything_recursive(api: Api, depth: int) -> None:
    from services.api.json_guard import MAX_JSON_DEPTH as limit

    assert limit == MAX_JSON_DEPTH
    cases = [
        ("/sweeps", SWEEP % f'"grid": {{"problem.x": [{_nested(depth, "list")}]}}'),
        ("/sweeps", SWEEP % f'"list": [{{"problem.x": {_nested(depth, "dict")}}}]'),
        ("/jobs", f'{{"problem": {{"kind": "path_tracking", "x": {_nested(depth, "dict")}}}}}'),
        ("/robots", f'{{"name": "deep", "spec": {_nested(depth, "dict")}}}'),
    ]
    for path, body in cases:
        r = api.post(path, body)
        assert r.status_code == 422, f"{path} depth {depth}: {r.status_code} {r.text[:300]}"
        (err,) = r.json()["detail"]
        assert err["type"] == "json_too_deep", err
        assert err["loc"][0] == "body" and f"{limit}" in err["msg"]
        if depth < 500:  # parsed, then located at the first level past the limit
            assert len(err["loc"]) == 1 + limit, (path, depth, err["loc"][:8])


def test_nesting_at_the_limit_passes_the_guard(api: Api) -> None:
    body = SWEEP % f'"grid": {{"problem.x": [{_nested(MAX_JSON_DEPTH - 3, "list")}]}}'
    r = api.post("/sweeps", body)
    assert r.status_code == 422 and r.json()["detail"][0]["type"] != "json_too_deep", r.text[:300]


def test_malformed_bodies_are_422_not_400_or_500(api: Api) -> None:
    r = api.post("/jobs", b'{"problem": {"kind": "path_tracking"}, "seed": ' + b"9" * 5000 + b"}")
    assert error_at(r, ["body"], "json_invalid")
    body = b'{"name": "\xc3\x28", "catalog": "puma560"}'
    assert error_at(api.post("/robots", body), ["body", body.index(b"\xc3")], "json_invalid")
    r = api.post("/robots", b'{"name": "x", "catalog": "puma560", "\\ud800": 1}')
    assert r.status_code == 422, r.text
    r = api.post("/jobs", '{"problem": {"kind": "path_tracking"}, "seed": ' + "9" * 400 + "}")
    assert error_at(r, ["body", "seed"])


def test_oversized_bodies_are_413(api: Api) -> None:
    big = json.dumps({"problem": {"kind": "path_tracking"}, "name": "x" * DEFAULT_MAX_BODY_BYTES})
    assert api.post("/jobs", big).status_code == 413

    def chunks() -> Iterator[bytes]:  # no Content-Length: counted while streaming
        yield b'{"base": {"problem": {"kind": "path_tracking"}}, "seeds": ['
        for _ in range(DEFAULT_MAX_BODY_BYTES // 50_000 + 2):
            yield b"1, " * 16_667
        yield b"1]}"

    r = api.client.post(f"{API}/sweeps", content=chunks(), headers={**api.headers, **JSON})
    assert r.status_code == 413, r.text[:300]


GA = {"kind": "ga", "params": {"pop_size": 2000}}
ABSURD = [
    ({"optimizer": {"kind": "ga", "params": {"pop_size": 10**6}}}, ["body", "optimizer", "params"]),
    ({"budget": {"generations": 100_000}, "optimizer": GA}, ["body", "budget"]),
    ({"budget": {"generations": 10**12}}, ["body", "budget", "generations"]),
    ({"budget": {"evaluations": 10**30}}, ["body", "budget", "evaluations"]),
]


@pytest.mark.parametrize(("extra", "loc_prefix"), ABSURD)
def test_absurd_job_sizes_are_422(api: Api, extra: dict[str, Any], loc_prefix: list[Any]) -> None:
    r = api.post("/jobs", json.dumps({"problem": {"kind": "swing_energy"}, **extra}))
    assert r.status_code == 422, r.text[:300]
    locs = [e["loc"][: len(loc_prefix)] for e in r.json()["detail"]]
    assert loc_prefix in locs, r.json()


def test_sweep_over_the_job_limit_is_422(api: Api) -> None:
    # LEGOPT_MAX_SWEEP_JOBS: 10 000 (refused from the axes' sizes, before any job is made)
    body = {"base": {"problem": {"kind": "path_tracking"}}, "grid": {"seed": list(range(10_001))}}
    r = api.post("/sweeps", json.dumps(body))
    assert r.status_code == 422 and "limit" in r.json()["detail"][0]["msg"]


NUL = "\x00"


def test_nul_characters_in_ids_and_queries_are_never_500(api: Api) -> None:
    """PostgreSQL text cannot hold a NUL character (psycopg raises ``DataError`` before the
    query runs) where SQLite stores it: an id, a query parameter or a name holding one must be
    refused or not found on both databases, never a 500."""
    schema = api.client.get(f"{API}/openapi.json").json()
    failures = []
    for path, operations in schema["paths"].items():
        for method, op in operations.items():
            params = op.get("parameters", [])
            names = [p["name"] for p in params if p["in"] == "path"]
            real = path
            for name in names:
                real = real.replace(f"{{{name}}}", "00000000-0000-4000-8000-000000000000")
            calls: list[tuple[str, dict[str, str]]] = []
            if names:
                url = path
                for name in names:
                    url = url.replace(f"{{{name}}}", "%00x")  # NUL, percent-encoded
                calls.append((url, {}))
            if method == "get":
                calls += [(real, {p["name"]: NUL}) for p in params if p["in"] == "query"]
            for url, query in calls:
                r = api.client.request(method.upper(), url, params=query, headers=api.headers)
                if r.status_code >= 500:
                    failures.append(f"{method.upper()} {url!r} {query}: {r.status_code}")
    bodies = [
        ("/robots", {"name": f"r{NUL}", "catalog": "puma560"}),
        ("/jobs", {"problem": {"kind": "path_tracking"}, "robot": f"x{NUL}"}),
        ("/sweeps", {"base": {"problem": {"kind": "path_tracking"}, "robot": NUL}, "seeds": [1]}),
    ]
    for path, body in bodies:
        r = api.post(path, json.dumps(body))
        if r.status_code >= 500:
            failures.append(f"POST {path} {json.dumps(body)}: {r.status_code}")
    assert not failures, f"{len(failures)} requests with a NUL answered 5xx:\n" + "\n".join(
        failures
    )


def test_api_answers_after_the_hostile_inputs(api: Api) -> None:
    assert api.client.get(f"{API}/health").json() == {"status": "ok"}
    r = api.post("/jobs", json.dumps({"problem": {"kind": "path_tracking"}, "seed": 1}))
    assert r.status_code == 202, r.text[:300]
