"""Robots by reference (issue 8, defect 9): a job or sweep's robot document is stored once by
content, the stored spec holds a reference, and every reader gets the whole spec back."""

from __future__ import annotations

import json
from pathlib import Path

from sqlalchemy import Engine, func, select
from sqlalchemy.pool import NullPool
from store_testdb import sqlite_url

from services.store import (
    create_api_key,
    create_job,
    create_sweep,
    get_job,
    hash_api_key,
    migrate,
    session_scope,
)
from services.store.repository import create_jobs, job_spec, sweep_base_spec
from services.store.robot_documents import REF_KEY
from services.store.session import make_engine
from services.store.specs import json_size
from services.store.tables import JOBS, ROBOT_DOCUMENTS

URDF = "<robot name='arm'>" + "<!-- padding -->" * 4000 + "</robot>"  # ~64 KB of file
ROBOT = {"name": "my_arm", "urdf": URDF, "locked_joints": {"finger": 0.0}}


def _spec(seed: int) -> dict:
    return {"problem": {"kind": "path_tracking"}, "robot": ROBOT, "seed": seed}


def _documents(engine: Engine) -> int:
    with session_scope(engine) as s:
        return int(s.execute(select(func.count()).select_from(ROBOT_DOCUMENTS)).scalar_one())


def test_jobs_share_one_robot_document_and_read_back_whole(engine: Engine) -> None:
    with session_scope(engine) as s:
        alice = create_api_key(s, name="alice", key_hash=hash_api_key("a"))
        bob = create_api_key(s, name="bob", key_hash=hash_api_key("b"))
        jobs = [create_job(s, owner_key_id=k.id, spec=_spec(i))
                for i, k in enumerate([alice, alice, bob])]  # fmt: skip
    assert _documents(engine) == 1  # one row per distinct content, whoever submitted it
    with session_scope(engine) as s:
        for i, job in enumerate(jobs):
            raw, size = s.execute(
                select(JOBS.c.spec, JOBS.c.spec_bytes).where(JOBS.c.id == job.id)).one()
            assert set(raw["robot"]) == {REF_KEY, "name"} and raw["robot"]["name"] == "my_arm"
            assert json_size(raw) < 300  # the row holds the reference, not the 64 KB URDF
            assert size > len(URDF)  # the storage quota counts the whole spec
            record = get_job(s, job.id)
            assert record is not None
            assert job_spec(s, record) == _spec(i)


def test_catalog_names_and_robotless_specs_are_stored_as_given(engine: Engine) -> None:
    with session_scope(engine) as s:
        alice = create_api_key(s, name="alice", key_hash=hash_api_key("a"))
        (a, b) = create_jobs(s, owner_key_id=alice.id, total_generations=[1, 1],
                             specs=[{"robot": "puma560"}, {"seed": 3}])  # fmt: skip
        assert get_job(s, a).spec == {"robot": "puma560"}  # type: ignore[union-attr]
        assert get_job(s, b).spec == {"seed": 3}  # type: ignore[union-attr]
    assert _documents(engine) == 0


def test_sweep_base_holds_a_reference_and_its_jobs_read_the_robot(engine: Engine) -> None:
    with session_scope(engine) as s:
        alice = create_api_key(s, name="alice", key_hash=hash_api_key("a"))
        sweep = create_sweep(s, owner_key_id=alice.id, base_spec=_spec(0), axes={})
        assert REF_KEY in sweep.base_spec["robot"]
        ids = create_jobs(s, owner_key_id=alice.id, total_generations=[1, 1], sweep_id=sweep.id,
                          overrides=[{"seed": 1}, {"robot.locked_joints.finger": 0.5}])  # fmt: skip
        assert sweep_base_spec(s, sweep) == _spec(0)
        specs = [job_spec(s, get_job(s, i)) for i in ids]  # type: ignore[arg-type]
    assert specs[0] == _spec(1)
    assert specs[1]["robot"] == {**ROBOT, "locked_joints": {"finger": 0.5}}
    assert _documents(engine) == 1


def test_downgrade_puts_the_documents_back_into_the_specs(tmp_path: Path) -> None:
    url = sqlite_url(tmp_path)
    migrate.upgrade(url)
    engine = make_engine(url, poolclass=NullPool)
    try:
        with session_scope(engine) as s:
            alice = create_api_key(s, name="alice", key_hash=hash_api_key("a"))
            job = create_job(s, owner_key_id=alice.id, spec=_spec(7))
            sweep = create_sweep(s, owner_key_id=alice.id, base_spec=_spec(8), axes={})
    finally:
        engine.dispose()
    migrate.downgrade(url, "0006")
    engine = make_engine(url, poolclass=NullPool)
    try:
        with engine.connect() as conn:
            spec = conn.execute(select(JOBS.c.spec).where(JOBS.c.id == job.id)).scalar_one()
            base = conn.exec_driver_sql(
                "SELECT base_spec FROM sweeps WHERE id = ?", (sweep.id,)).scalar_one()  # fmt: skip
    finally:
        engine.dispose()
    assert spec == _spec(7)
    assert json.loads(base) == _spec(8)


def test_a_second_insert_of_the_same_content_is_ignored(engine: Engine) -> None:
    from services.store.robot_documents import store_document

    with session_scope(engine) as s:
        first = store_document(s, ROBOT)
        assert store_document(s, dict(reversed(list(ROBOT.items())))) == first  # key order
    with session_scope(engine) as s:  # another transaction (a racing writer): no error
        assert store_document(s, ROBOT) == first
    assert _documents(engine) == 1
