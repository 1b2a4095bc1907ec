"""Repository: create/get/list of API keys, robots, sweeps and jobs; frozen records; JSON."""

from __future__ import annotations

import dataclasses
from datetime import UTC, datetime, timedelta, timezone

import numpy as np
import pytest
from sqlalchemy import Engine, select

from services.store import (
    ApiKeyRecord,
    ConflictError,
    JobRecord,
    JobStatus,
    RobotSource,
    count_jobs_by_status,
    create_api_key,
    create_job,
    create_robot,
    create_sweep,
    delete_api_key,
    delete_robot,
    generate_api_key,
    get_api_key,
    get_api_key_by_hash,
    get_job,
    get_robot,
    get_robot_by_name,
    get_sweep,
    hash_api_key,
    list_api_keys,
    list_jobs,
    list_robots,
    list_sweeps,
    repository,
    session_scope,
)
from services.store.tables import JOBS

T0 = datetime(2026, 1, 1, 12, 0, tzinfo=UTC)


def _key(engine: Engine, name: str = "alice") -> ApiKeyRecord:
    with session_scope(engine) as s:
        return create_api_key(s, name=name, key_hash=hash_api_key(f"raw-{name}"))


def test_api_keys_are_stored_by_hash(engine: Engine) -> None:
    raw, key_hash = generate_api_key()
    assert raw.startswith("lgo_") and key_hash == hash_api_key(raw) and raw not in key_hash
    with session_scope(engine) as s:
        key = create_api_key(s, name="ci", key_hash=key_hash)
    with session_scope(engine) as s:
        assert get_api_key_by_hash(s, hash_api_key(raw)) == key
        assert get_api_key_by_hash(s, hash_api_key("wrong")) is None
        assert get_api_key(s, key.id) == key
        with pytest.raises(ConflictError):
            create_api_key(s, name="again", key_hash=key_hash)
        # the conflict rolled back only its savepoint: the session is still usable
        other = create_api_key(s, name="other", key_hash=hash_api_key("x"))
    with session_scope(engine) as s:
        page = list_api_keys(s)
        assert {k.id for k in page.items} == {key.id, other.id} and page.total == 2
    assert not hasattr(key, "key_hash")
    assert key.created_at.tzinfo is not None and key.created_at.utcoffset() == timedelta(0)


def test_robots_unique_per_owner_and_owner_scoped(engine: Engine) -> None:
    alice, bob = _key(engine, "alice"), _key(engine, "bob")
    spec = {"dh": [{"a": 0.1, "alpha": 0.0, "d": 0.0}], "units": "SI"}
    with session_scope(engine) as s:
        robot = create_robot(s, owner_key_id=alice.id, name="leg", source_kind="dh", spec=spec)
        create_robot(s, owner_key_id=bob.id, name="leg", source_kind=RobotSource.URDF, spec={})
    with session_scope(engine) as s:
        with pytest.raises(ConflictError, match="leg"):
            create_robot(s, owner_key_id=alice.id, name="leg", source_kind="dh", spec={})
        assert robot.source_kind is RobotSource.DH
        assert get_robot(s, robot.id) == robot
        assert get_robot(s, robot.id, owner_key_id=bob.id) is None
        assert get_robot_by_name(s, owner_key_id=alice.id, name="leg") == robot
        assert list_robots(s, owner_key_id=alice.id).items == (robot,)
        assert list_robots(s).total == 2
        assert not delete_robot(s, robot.id, owner_key_id=bob.id)
        assert delete_robot(s, robot.id, owner_key_id=alice.id)
        assert get_robot(s, robot.id) is None
    with pytest.raises(ValueError):
        with session_scope(engine) as s:
            create_robot(s, owner_key_id=alice.id, name="x", source_kind="step", spec={})


def test_jobs_create_get_list_paginate(engine: Engine) -> None:
    alice, bob = _key(engine, "alice"), _key(engine, "bob")
    spec = {"robot": "puma560", "problem": {"kind": "path_placement"}, "seed": 1}
    with session_scope(engine) as s:
        sweep = create_sweep(s, owner_key_id=alice.id, base_spec=spec, axes={"seed": [1, 2]})
        jobs = [
            create_job(
                s,
                owner_key_id=alice.id,
                spec={**spec, "seed": i},
                total_generations=50,
                sweep_id=sweep.id if i < 2 else None,
                now=T0 + timedelta(seconds=i),
            )
            for i in range(5)
        ]
        create_job(s, owner_key_id=bob.id, spec=spec, warnings=["robot is near a singularity"])
    job = jobs[0]
    assert job.status is JobStatus.QUEUED and job.attempt_count == 0
    assert (job.progress_generation, job.total_generations, job.progress) == (0, 50, 0.0)
    assert job.created_at == T0 and job.started_at is None and job.lease_owner is None
    assert job.warnings == [] and job.cancel_requested is False and job.best_objective is None
    with session_scope(engine) as s:
        assert get_job(s, job.id) == job
        assert get_job(s, job.id, owner_key_id=bob.id) is None
        page = list_jobs(s, owner_key_id=alice.id, limit=2, offset=1)
        assert [j.id for j in page.items] == [jobs[3].id, jobs[2].id]  # newest first
        assert (page.total, page.limit, page.offset) == (5, 2, 1)
        assert list_jobs(s, sweep_id=sweep.id).total == 2
        assert list_jobs(s, status="queued").total == 6
        assert list_jobs(s, status=[JobStatus.RUNNING, JobStatus.FAILED]).total == 0
        assert count_jobs_by_status(s, sweep_id=sweep.id)[JobStatus.QUEUED] == 2
        assert count_jobs_by_status(s)[JobStatus.SUCCEEDED] == 0
        assert get_sweep(s, sweep.id) == sweep
        assert get_sweep(s, sweep.id, owner_key_id=bob.id) is None
        assert list_sweeps(s, owner_key_id=alice.id).items == (sweep,)
        assert list_jobs(s, owner_key_id=bob.id).items[0].warnings == [
            "robot is near a singularity"
        ]
        # the total is counted up to COUNT_CAP + 1 ("more than"), not over every row
        assert list_jobs(s, owner_key_id=alice.id, limit=1).total == 5
    with session_scope(engine) as s, pytest.MonkeyPatch.context() as mp:
        mp.setattr(repository, "COUNT_CAP", 3)
        page = list_jobs(s, owner_key_id=alice.id, limit=2)
        assert page.total == 4 and len(page.items) == 2  # 4 = COUNT_CAP + 1: more than 3
        assert list_jobs(s, owner_key_id=alice.id, limit=2, offset=4).items == (jobs[0],)
    with session_scope(engine) as s:
        with pytest.raises(ValueError):
            list_jobs(s, limit=0)
        with pytest.raises(ValueError):
            list_jobs(s, offset=-1)


def test_records_are_frozen_snapshots(engine: Engine) -> None:
    alice = _key(engine)
    with session_scope(engine) as s:
        job = create_job(s, owner_key_id=alice.id, spec={"budget": {"generations": 3}})
    with pytest.raises(dataclasses.FrozenInstanceError):
        job.status = JobStatus.RUNNING  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        alice.name = "mallory"  # type: ignore[misc]
    job.spec["budget"]["generations"] = 1000  # a copy: the store is unaffected
    with session_scope(engine) as s:
        again = get_job(s, job.id)
    assert isinstance(again, JobRecord)
    assert again.spec == {"budget": {"generations": 3}}


def test_json_values_are_made_plain_and_finite(engine: Engine) -> None:
    alice = _key(engine)
    spec = {"w": np.array([0.25, 0.5]), "n": np.int64(3), "bad": float("nan"), "t": (1, 2)}
    with session_scope(engine) as s:
        job = create_job(s, owner_key_id=alice.id, spec=spec)
    assert job.spec == {"w": [0.25, 0.5], "n": 3, "bad": None, "t": [1, 2]}
    with pytest.raises(Exception, match="not JSON-serialisable"):
        with session_scope(engine) as s:
            create_job(s, owner_key_id=alice.id, spec={"x": object()})


def test_naive_datetimes_are_refused_and_aware_ones_stored_as_utc(engine: Engine) -> None:
    alice = _key(engine)
    plus2 = datetime(2026, 1, 1, 14, 0, tzinfo=timezone(timedelta(hours=2)))
    with session_scope(engine) as s:
        job = create_job(s, owner_key_id=alice.id, spec={}, now=plus2)
        raw = s.execute(select(JOBS.c.created_at).where(JOBS.c.id == job.id)).scalar_one()
    assert job.created_at == datetime(2026, 1, 1, 12, 0, tzinfo=UTC)
    assert job.created_at.tzinfo is UTC and raw.utcoffset() == timedelta(0)
    with pytest.raises(ValueError, match="naive"):
        with session_scope(engine) as s:
            create_job(s, owner_key_id=alice.id, spec={}, now=datetime(2026, 1, 1))


def test_deleting_a_key_cascades_to_its_rows(engine: Engine) -> None:
    alice = _key(engine)
    with session_scope(engine) as s:
        job = create_job(s, owner_key_id=alice.id, spec={})
        create_robot(s, owner_key_id=alice.id, name="r", source_kind="catalog", spec={})
    with session_scope(engine) as s:
        assert delete_api_key(s, alice.id)
    with session_scope(engine) as s:
        assert get_job(s, job.id) is None and list_robots(s).total == 0


def test_session_scope_rolls_back_on_error(engine: Engine) -> None:
    alice = _key(engine)
    with pytest.raises(RuntimeError):
        with session_scope(engine) as s:
            create_job(s, owner_key_id=alice.id, spec={})
            raise RuntimeError("boom")
    with session_scope(engine) as s:
        assert list_jobs(s).total == 0


def test_foreign_keys_are_enforced(engine: Engine) -> None:
    with pytest.raises(Exception, match="(?i)foreign key"):
        with session_scope(engine) as s:
            create_job(s, owner_key_id="no-such-key", spec={})
