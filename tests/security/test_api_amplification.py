"""Amplification through the in-process API (issue 8, defect 9: CPU): a sweep of an inline URDF
robot builds it once (not twice per job), points share the base instead of deep-copying it, a
sweep building many distinct large robots is refused, and the API's cached preparation sizes
every job as the worker's does. Hostile bodies (defect 10): ``test_api_inputs.py``.

The API tests run on both databases (``db_settings``: SQLite, and PostgreSQL where it answers).
"""

from __future__ import annotations

import copy
import json
import random
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

import legcore.robots.build as robot_build
from legcore.robots import catalog
from legcore.runner import job_size, prepare
from legcore.studies.registry import studies
from services.api.sweeps import expand
from services.api.validation import check_job_spec
from services.store.settings import Settings
from services.store.spec_paths import set_path
from tests.security.api_inputs_helpers import Api, error_at, in_process_api


@pytest.fixture(scope="module")
def api(db_settings: Settings) -> Iterator[Api]:
    with in_process_api(db_settings) as api:
        yield api


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
