"""Sweeps: pure expansion, a 2x3 grid -> 6 jobs and 6 enqueues, the aggregated table, robot
parameter sweeps, validation of every generated spec before anything is stored, limits."""

from __future__ import annotations

import copy
from typing import Any

import pytest
from api_helpers import finish_like_a_worker, locs, row_counts
from fastapi.testclient import TestClient

from legcore.robots import Robot, catalog
from legcore.studies.registry import studies
from services.api.app import create_app
from services.api.deps import ApiContext
from services.api.sweeps import SweepError, count_points, expand
from services.store.spec_paths import get_path, set_path

API = "/api/v1"
KINDS = sorted(studies())


def study_with_param(name: str) -> tuple[str, dict[str, Any]]:
    """A study whose default optimizer has the parameter ``name``, and that optimizer."""
    for kind in KINDS:
        opt = studies()[kind].default_optimizer
        if name in opt["params"]:
            return kind, opt
    raise AssertionError(f"no study's optimizer has {name!r}")


def serial_study() -> tuple[str, dict[str, Any]]:
    for kind in KINDS:
        robot = catalog.get(studies()[kind].default_robot)
        if isinstance(robot, Robot):
            return kind, robot.spec.model_dump(mode="json")
    raise AssertionError("no study with a serial default robot")


# --------------------------------------------------------------------------- pure expansion


def test_expand_grid_list_seeds_in_order() -> None:
    base = {"problem": {"kind": "k"}, "optimizer": {"kind": "ga", "params": {"pop_size": 10}}}
    points = expand(
        base,
        grid={"optimizer.params.mutation_rate": [0.01, 0.03], "problem.w": [1, 2]},
        entries=[{"budget.generations": 5}, {"budget.generations": 7}],
        seeds=[1, 2, 3],
    )
    assert (
        len(points)
        == 2 * 2 * 2 * 3
        == count_points({"a": [0, 1], "b": [0, 1]}, [{}, {}], [1, 2, 3])
    )
    first, last = points[0], points[-1]
    assert first.overrides == {
        "optimizer.params.mutation_rate": 0.01,
        "problem.w": 1,
        "budget.generations": 5,
        "seed": 1,
    }
    assert first.spec["optimizer"]["params"] == {"pop_size": 10, "mutation_rate": 0.01}
    assert first.spec["budget"] == {"generations": 5} and first.spec["seed"] == 1
    assert last.overrides["seed"] == 3 and last.spec["problem"]["w"] == 2
    assert base == {
        "problem": {"kind": "k"},
        "optimizer": {"kind": "ga", "params": {"pop_size": 10}},
    }
    assert [p.index for p in points] == list(range(len(points)))
    assert first.source_of(["optimizer", "params", "mutation_rate"]) == (
        "grid",
        "optimizer.params.mutation_rate",
        0,
    )
    assert last.source_of(["seed"]) == ("seeds", 2)
    assert first.source_of(["robot"]) is None


def test_expand_without_axes_is_one_job() -> None:
    (point,) = expand({"seed": 4})
    assert point.spec == {"seed": 4} and point.overrides == {}


def test_paths_into_lists_and_errors() -> None:
    doc: dict[str, Any] = {"robot": {"joints": [{"mass": 1.0}, {"mass": 2.0}]}}
    set_path(doc, "robot.joints.1.mass", 5.0)
    assert get_path(doc, "robot.joints.1.mass") == 5.0
    assert get_path(doc, "robot.joints.7.mass", "missing") == "missing"
    with pytest.raises(ValueError, match="no index '2'"):
        set_path(doc, "robot.joints.2.mass", 1.0)
    with pytest.raises(ValueError, match="catalog name"):
        set_path({"robot": "puma560"}, "robot.joints.1.mass", 1.0)
    with pytest.raises(SweepError) as info:
        expand({}, grid={"seed": []})
    assert info.value.loc == ("grid", "seed")
    with pytest.raises(SweepError) as info:
        expand({}, grid={"a..b": [1]})
    assert info.value.loc == ("grid", "a..b")
    with pytest.raises(SweepError) as info:
        expand({}, grid={"seed": [1]}, seeds=[1])
    assert info.value.loc == ("seeds",)
    with pytest.raises(SweepError, match="limit is 10"):
        expand({}, grid={"a": list(range(4))}, seeds=[1, 2, 3], max_jobs=10)


# --------------------------------------------------------------------------- API


def test_sweep_2x3_grid(
    client: TestClient, ctx: ApiContext, alice: dict[str, str], sent: list[str]
) -> None:
    kind, opt = study_with_param("mutation_rate")
    body = {
        "base": {"problem": {"kind": kind}, "optimizer": opt},
        "grid": {"optimizer.params.mutation_rate": [0.01, 0.03], "seed": [1, 2, 3]},
    }
    r = client.post(f"{API}/sweeps", json=body, headers=alice)
    assert r.status_code == 202, r.text
    created = r.json()
    sid = created["id"]
    assert r.headers["location"] == f"{API}/sweeps/{sid}"
    assert created["n_jobs"] == 6 and created["counts"]["queued"] == 6
    assert sent == created["job_ids"] and len(set(sent)) == 6

    jobs = client.get(f"{API}/jobs?sweep_id={sid}", headers=alice).json()
    assert jobs["total"] == 6 and {j["sweep_id"] for j in jobs["items"]} == {sid}

    finish_like_a_worker(ctx, sent[0], n_pareto=3)
    finish_like_a_worker(ctx, sent[4], n_pareto=3)
    client.post(f"{API}/jobs/{sent[5]}/cancel", headers=alice)

    sweep = client.get(f"{API}/sweeps/{sid}", headers=alice).json()
    assert sweep["columns"] == ["optimizer.params.mutation_rate", "seed"]
    assert sweep["counts"] == {
        "queued": 3,
        "running": 0,
        "succeeded": 2,
        "failed": 0,
        "cancelled": 1,
    }
    assert sweep["state"] == "running" and sweep["n_jobs"] == 6
    assert sweep["objective_names"] == ["energy", "time"]
    rows = sweep["table"]["items"]
    assert [row["job_id"] for row in rows] == sent
    assert [row["overrides"] for row in rows] == [
        {"optimizer.params.mutation_rate": m, "seed": s} for m in (0.01, 0.03) for s in (1, 2, 3)
    ]
    assert rows[0]["status"] == "succeeded" and rows[0]["objectives"] == {
        "energy": 1.5,
        "time": 2.0,
    }
    assert rows[0]["metrics"]["energy_J"] == 1.5
    assert rows[1]["objectives"] is None and rows[5]["status"] == "cancelled"

    page = client.get(f"{API}/sweeps/{sid}?limit=4&offset=4", headers=alice).json()["table"]
    assert [row["job_id"] for row in page["items"]] == sent[4:]
    assert (page["total"], page["limit"], page["offset"]) == (6, 4, 4)

    listing = client.get(f"{API}/sweeps", headers=alice).json()
    assert listing["total"] == 1 and listing["items"][0]["n_jobs"] == 6


def test_sweep_list_and_seeds(client: TestClient, alice: dict[str, str], sent: list[str]) -> None:
    kind = KINDS[0]
    body = {
        "base": {"problem": {"kind": kind}},
        "list": [{"budget.generations": 2}, {"budget.generations": 3, "name": "three"}],
        "seeds": [7, 8],
    }
    r = client.post(f"{API}/sweeps", json=body, headers=alice)
    assert r.status_code == 202, r.text
    assert r.json()["n_jobs"] == 4 and len(sent) == 4
    jobs = [client.get(f"{API}/jobs/{j}", headers=alice).json() for j in sent]
    assert [(j["spec"]["budget"]["generations"], j["spec"]["seed"]) for j in jobs] == [
        (2, 7),
        (2, 8),
        (3, 7),
        (3, 8),
    ]
    assert [j["total_generations"] for j in jobs] == [2, 2, 3, 3]
    assert jobs[2]["name"] == "three"


def test_sweep_of_robot_parameters(
    client: TestClient, alice: dict[str, str], sent: list[str]
) -> None:
    kind, spec = serial_study()
    body = {
        "base": {"problem": {"kind": kind}, "robot": spec},
        "grid": {"robot.joints.1.mass": [0.5, 1.0, 2.0]},
    }
    r = client.post(f"{API}/sweeps", json=body, headers=alice)
    assert r.status_code == 202, r.text
    masses = [
        client.get(f"{API}/jobs/{j}", headers=alice).json()["spec"]["robot"]["joints"][1]["mass"]
        for j in sent
    ]
    assert masses == [0.5, 1.0, 2.0]
    # a stored robot can be swept too (its spec is substituted first)
    rid = client.post(f"{API}/robots", json={"name": "r", "spec": spec}, headers=alice).json()["id"]
    body = {
        "base": {"problem": {"kind": kind}, "robot": rid},
        "grid": {"robot.joints.0.mass": [1.5]},
    }
    r = client.post(f"{API}/sweeps", json=body, headers=alice)
    assert r.status_code == 202, r.text
    job = client.get(f"{API}/jobs/{sent[-1]}", headers=alice).json()
    assert job["spec"]["robot"]["joints"][0]["mass"] == 1.5


def test_bad_sweeps_store_nothing(
    client: TestClient, ctx: ApiContext, alice: dict[str, str], sent: list[str]
) -> None:
    kind, spec = serial_study()
    base = {"problem": {"kind": kind}, "robot": spec}
    bad_inertia = [[1.0, 0, 0], [0, -1.0, 0], [0, 0, 1.0]]
    cases: list[tuple[dict[str, Any], list[Any]]] = [
        # one bad value among good ones: located at the grid value that caused it
        (
            {"base": base, "grid": {"robot.joints.1.mass": [1.0, -1.0]}},
            ["body", "grid", "robot.joints.1.mass", 1],
        ),
        (
            {"base": base, "grid": {"robot.joints.1.inertia": [bad_inertia]}},
            ["body", "grid", "robot.joints.1.inertia", 0],
        ),
        ({"base": base, "list": [{"seed": 1}, {"seed": -5}]}, ["body", "list", 1, "seed"]),
        ({"base": base, "seeds": [1, -2]}, ["body", "seeds", 1]),
        (
            {"base": base, "grid": {"budget.generations": [10, 90_000]}},
            ["body", "grid", "budget.generations", 1],
        ),
        # the base itself is wrong
        ({"base": {**base, "bogus": 1}, "seeds": [1, 2]}, ["body", "base", "bogus"]),
        ({"base": {"problem": {"kind": kind}, "robot": "nope"}}, ["body", "base", "robot"]),
        # paths that cannot be set
        (
            {
                "base": {"problem": {"kind": kind}, "robot": studies()[kind].default_robot},
                "grid": {"robot.joints.1.mass": [1.0]},
            },
            ["body", "grid", "robot.joints.1.mass", 0],
        ),
        (
            {"base": base, "grid": {"robot.joints.99.mass": [1.0]}},
            ["body", "grid", "robot.joints.99.mass", 0],
        ),
        ({"base": base, "grid": {"seed": []}}, ["body", "grid", "seed"]),
        ({"base": base, "grid": {"seed": [1]}, "seeds": [2]}, ["body", "seeds"]),
        # too many jobs (MAX_SWEEP_JOBS = 10 000: 101 × 100)
        (
            {
                "base": base,
                "grid": {"budget.generations": list(range(1, 102))},
                "seeds": list(range(100)),
            },
            ["body"],
        ),
        # unknown field of the sweep
        ({"base": base, "axes": {}}, ["body", "axes"]),
    ]
    before = row_counts(ctx)
    for body, loc in cases:
        r = client.post(f"{API}/sweeps", json=body, headers=alice)
        assert loc in locs(r), (body, r.json())
    assert row_counts(ctx) == before and sent == []


def test_sweep_limit_is_configurable(settings: Any, ctx: ApiContext, alice: dict[str, str]) -> None:
    sent: list[str] = []
    with TestClient(create_app(settings, enqueue=sent.append, max_sweep_jobs=3)) as c:
        body = {"base": {"problem": {"kind": KINDS[0]}}, "seeds": [1, 2, 3, 4]}
        r = c.post(f"{API}/sweeps", json=body, headers=alice)
        assert "limit is 3" in r.json()["detail"][0]["msg"]
        body["seeds"] = [1, 2, 3]
        assert c.post(f"{API}/sweeps", json=body, headers=alice).status_code == 202
    assert len(sent) == 3


def test_sweeps_of_another_key_are_404(
    client: TestClient, alice: dict[str, str], bob: dict[str, str]
) -> None:
    body = {"base": {"problem": {"kind": KINDS[0]}}, "seeds": [1, 2]}
    sid = client.post(f"{API}/sweeps", json=body, headers=alice).json()["id"]
    assert client.get(f"{API}/sweeps/{sid}", headers=bob).status_code == 404
    assert client.get(f"{API}/sweeps", headers=bob).json()["total"] == 0
    assert client.get(f"{API}/jobs?sweep_id={sid}", headers=bob).json()["total"] == 0
    assert client.get(f"{API}/sweeps/{sid}", headers=alice).status_code == 200


def test_sweep_does_not_mutate_request_copies() -> None:
    base = {"robot": {"joints": [{"mass": 1.0}]}}
    snapshot = copy.deepcopy(base)
    points = expand(base, grid={"robot.joints.0.mass": [2.0, 3.0]})
    assert base == snapshot
    assert points[0].spec["robot"] is not points[1].spec["robot"]


def test_sweep_over_stored_robots_runs_each_robot(
    client: TestClient, alice: dict[str, str], sent: list[str]
) -> None:
    """A ``robot`` axis of stored robots' names: each job reads back (and a worker runs) the
    robot it names, not the name."""
    kind, spec = serial_study()
    heavy = copy.deepcopy(spec)
    heavy["joints"][0]["mass"] = 9.0
    for name, doc in (("light", spec), ("heavy", heavy)):
        r = client.post(f"{API}/robots", json={"name": name, "spec": doc}, headers=alice)
        assert r.status_code == 201, r.text
    body = {"base": {"problem": {"kind": kind}}, "grid": {"robot": ["light", "heavy"]}}
    r = client.post(f"{API}/sweeps", json=body, headers=alice)
    assert r.status_code == 202, r.text
    robots = [client.get(f"{API}/jobs/{j}", headers=alice).json()["spec"]["robot"] for j in sent]
    assert [r["joints"][0]["mass"] for r in robots] == [spec["joints"][0]["mass"], 9.0]
    table = client.get(f"{API}/sweeps/{r.json()['id']}", headers=alice).json()["table"]["items"]
    shown = [row["overrides"]["robot"] for row in table]
    assert len(set(shown)) == 2 and all(isinstance(v, str) for v in shown), shown
