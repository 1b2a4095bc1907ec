"""Hostile request bodies against the in-process API: each is a 422 (or 413) naming where the
problem is, never a 500, and the API keeps answering (issue 8, defects 9 and 10): a tiny hexapod
pose-grid step (``extent / 1e-320`` overflows), NaN / Infinity / 1e309 anywhere in a body,
nesting 65 to 100 000 levels deep, oversized bodies, absurd job sizes; and amplification: a
sweep of an inline URDF robot builds it once (not twice per job), points share the base instead
of deep-copying it, and a sweep building many distinct large robots is refused.

The API tests run on both databases (``db_settings``: SQLite, and PostgreSQL where it answers).
"""

from __future__ import annotations

import copy
import json
import random
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from httpx import Response

import legcore.robots.build as robot_build
from legcore.robots import catalog
from legcore.runner import job_size, prepare
from legcore.studies.registry import studies
from services.api.app import create_app
from services.api.body_limit import DEFAULT_MAX_BODY_BYTES
from services.api.deps import ApiContext
from services.api.sweeps import expand
from services.api.validation import check_job_spec
from services.store.keys import generate_api_key
from services.store.repository import create_api_key
from services.store.settings import Settings
from services.store.spec_paths import set_path

API = "/api/v1"
JSON = {"content-type": "application/json"}
#: ``services.api.json_guard.MAX_JSON_DEPTH`` (imported in the tests: this module must load on
#: the code before the fix, to show each test failing there on its own).
MAX_JSON_DEPTH = 64


@dataclass
class Api:
    """The in-process app, its context and one API key's headers."""

    client: TestClient
    ctx: ApiContext
    headers: dict[str, str]

    def post(self, path: str, body: str | bytes) -> Response:
        """POST a raw JSON text (Python's json would refuse to write NaN for us)."""
        return self.client.post(f"{API}{path}", content=body, headers={**self.headers, **JSON})


@pytest.fixture(scope="module")
def api(db_settings: Settings) -> Iterator[Api]:
    app = create_app(db_settings, enqueue=lambda _job_id: None)
    ctx: ApiContext = app.state.context
    raw, key_hash = generate_api_key()
    with ctx.write() as session:
        create_api_key(session, name="alice", key_hash=key_hash)
    with TestClient(app, raise_server_exceptions=False) as client:
        yield Api(client, ctx, {"X-API-Key": raw})


def error_at(response: Response, loc: list[Any], type_: str | None = None) -> dict[str, Any]:
    """The validation error of a 422 located at ``loc`` (fails naming what came instead)."""
    assert response.status_code == 422, f"{response.status_code}: {response.text[:500]}"
    errors = response.json()["detail"]
    for err in errors:
        if err["loc"] == loc and (type_ is None or err["type"] == type_):
            return dict(err)
    raise AssertionError(f"no {type_ or 'error'} at {loc}; got {errors}")


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
    body = {"base": {"problem": {"kind": "path_tracking"}}, "grid": {"seed": list(range(1001))}}
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


# --------------------------------------------------------------------------- defect 9 (CPU)


def urdf_leg(n_fixed: int = 40) -> str:
    """A 3-joint URDF leg (swing_energy accepts it) plus ``n_fixed`` fixed links: size knob."""

    def link(name: str) -> str:
        return (
            f'<link name="{name}"><inertial><mass value="0.5"/><origin xyz="0.05 0 0"/>'
            '<inertia ixx="0.001" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>'
        )

    parts = ['<?xml version="1.0"?><robot name="leg"><link name="base"/>']
    axes = ["0 0 1", "0 1 0", "0 1 0"]
    for j in range(3):
        parent = f"l{j - 1}" if j else "base"
        parts.append(link(f"l{j}"))
        parts.append(
            f'<joint name="j{j}" type="revolute"><parent link="{parent}"/><child link="l{j}"/>'
            f'<origin xyz="{0.1 if j else 0} 0 0"/><axis xyz="{axes[j]}"/>'
            '<limit lower="-2.5" upper="2.5" effort="50" velocity="3"/></joint>'
        )
    for k in range(n_fixed):
        parts.append(link(f"f{k}"))
        parts.append(
            f'<joint name="fj{k}" type="fixed"><parent link="l{k % 3}"/><child link="f{k}"/>'
            '<origin xyz="0.01 0 0"/></joint>'
        )
    return "".join(parts) + "</robot>"


@pytest.fixture
def urdf_builds(api: Api, monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Names of the URDF robots built (by the API or by legcore's prepare) during a test.

    The app validates in its own process meanwhile (``validation_processes=0``): a validation
    process would not see the patched builder (nor a patched ``spec_cache`` limit)."""
    inline = api.ctx.settings.with_overrides(validation_processes=0)
    monkeypatch.setattr(api.ctx, "settings", inline)
    built: list[str] = []
    original = robot_build._build_urdf

    def counting(spec: Any) -> Any:
        built.append(spec.name)
        return original(spec)

    monkeypatch.setattr(robot_build, "_build_urdf", counting)
    return built


def urdf_sweep(**axes: Any) -> dict[str, Any]:
    robot = {"kind": "urdf", "name": "leg", "urdf": urdf_leg()}
    base = {"problem": {"kind": "swing_energy"}, "robot": robot, "budget": {"generations": 5}}
    return {"base": {**base, "optimizer": {"kind": "ga", "params": {}}}, **axes}


def test_sweep_builds_its_inline_robot_once(api: Api, urdf_builds: list[str]) -> None:
    rates = [round(0.01 * (i + 1), 2) for i in range(12)]
    r = api.post("/sweeps", json.dumps(urdf_sweep(grid={"optimizer.params.mutation_rate": rates})))
    assert r.status_code == 202, r.text[:300]
    assert len(urdf_builds) == 1, f"12 jobs built the same robot {len(urdf_builds)} times"

    urdf_builds.clear()
    r = api.post("/sweeps", json.dumps(urdf_sweep(seeds=list(range(12)))))
    assert r.status_code == 202 and len(urdf_builds) == 1, len(urdf_builds)

    urdf_builds.clear()
    bad = urdf_sweep(seeds=list(range(12)))
    bad["base"]["robot"]["urdf"] = urdf_leg().replace('upper="2.5"', 'upper="-3"')
    r = api.post("/sweeps", json.dumps(bad))
    assert r.status_code == 422 and len(urdf_builds) == 1, (r.status_code, len(urdf_builds))


def test_job_builds_its_inline_robot_once(api: Api, urdf_builds: list[str]) -> None:
    body = {k: v for k, v in urdf_sweep()["base"].items()}
    r = api.post("/jobs", json.dumps(body))
    assert r.status_code == 202 and len(urdf_builds) == 1, (r.text[:300], len(urdf_builds))


def test_many_distinct_large_robots_are_refused(
    api: Api, urdf_builds: list[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from services.api import spec_cache

    monkeypatch.setattr(spec_cache, "MAX_BUILD_CHARS", 60_000)  # the 8 MB budget, scaled down
    size = len(urdf_leg()) + spec_cache.BUILD_OVERHEAD_CHARS
    body = urdf_sweep(grid={"robot.gravity.2": [-9.0 - i / 10 for i in range(40)]})
    r = api.post("/sweeps", json.dumps(body))
    err = error_at(r, ["body", "base", "robot"], "too_much_work")
    assert "split the sweep" in err["msg"]
    assert len(urdf_builds) <= 60_000 // size, f"{len(urdf_builds)} builds of {size} chars"


def test_points_share_the_base_instead_of_copying_it() -> None:
    gravity = [0.0, 0.0, -9.81]
    robot: dict[str, Any] = {"kind": "urdf", "name": "leg", "urdf": urdf_leg(), "gravity": gravity}
    base: dict[str, Any] = {"problem": {"kind": "swing_energy", "w1": 1.0}, "robot": robot}
    points = expand(base, grid={"problem.w1": [1.0, 2.0, 3.0]}, seeds=[1, 2])
    assert all(p.spec["robot"] is robot for p in points), "the robot was copied per point"
    assert points[0].spec["problem"] is not base["problem"] and base["problem"]["w1"] == 1.0
    (swept,) = expand(base, grid={"robot.gravity.2": [-1.0]})
    assert swept.spec["robot"]["gravity"] == [0.0, 0.0, -1.0] and gravity[2] == -9.81
    assert swept.spec["robot"]["urdf"] is robot["urdf"]


def test_copy_on_write_equals_set_path_on_a_deep_copy() -> None:
    from services.store.spec_paths import with_overrides

    rng = random.Random(8)
    base: dict[str, Any] = {
        "a": {"b": [1, {"c": 2, "d": [3, 4]}, None], "e": None},
        "f": [[0, 1], {"g": "h"}],
        "i": "j",
    }
    paths = ["a.b.0", "a.b.1.c", "a.b.1.d.1", "a.e.x", "a.e", "f.0.1", "f.1.g", "f.1.k", "i", "a"]
    for _ in range(300):
        chosen = rng.sample(paths, rng.randint(1, 4))
        overrides = {p: rng.choice([0, "v", [9, {"w": 1}], {"d": [5, 6]}]) for p in chosen}
        frozen = copy.deepcopy(base)
        expected: Any = copy.deepcopy(base)
        try:
            for path, value in overrides.items():
                set_path(expected, path, value)
        except ValueError as exc:
            expected = type(exc)
        try:
            got: Any = with_overrides(base, overrides)
        except ValueError as exc:
            got = type(exc)
        assert (got == expected) if not isinstance(expected, type) else isinstance(got, type)
        assert base == frozen, f"{overrides} modified the base"


def _examples() -> list[dict[str, Any]]:
    specs: list[dict[str, Any]] = []
    for kind, study in sorted(studies().items()):
        specs.append({"problem": {"kind": kind}})
        specs.append({"problem": {"kind": kind}, "budget": {"evaluations": 3000}})
        specs.append({"problem": {"kind": kind}, "budget": {"wall_time_s": 60, "ftol": 1e-3}})
        robot = catalog.get(study.default_robot)
        inline = getattr(robot, "spec", None)
        if inline is not None:
            specs.append({"problem": {"kind": kind}, "robot": inline.model_dump(mode="json")})
    return specs


@pytest.mark.parametrize("spec", _examples(), ids=lambda s: json.dumps(s)[:60])
def test_cached_prepare_matches_legcore_prepare(spec: dict[str, Any], tmp_path: Path) -> None:
    """``check_job_spec`` (robot built once, problem reused) sizes every job exactly as the
    worker's ``legcore.runner.prepare`` does."""
    settings = Settings.from_env(env={}, data_dir=tmp_path)
    prepared = prepare(copy.deepcopy(spec))
    expected = job_size(prepared)
    cache: dict[str, Any] = {}
    for _ in range(2):  # the second time from the cache
        checked = check_job_spec(spec, settings=settings, lookup=lambda _ref: None, cache=cache)
        assert checked.size == expected
        total = prepared.total_generations
        assert checked.total_generations == (total if total is not None else expected.generations)
