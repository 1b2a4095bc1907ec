"""Fixtures of the chaos suite: one ``ChaosStack`` per backend kind, shared by the whole
package (database, broker and API; each test starts and stops its own workers), and one
``Scenario`` per test.

Kinds as in tests/integration/conftest.py: ``embedded`` (SQLite + filesystem broker) always,
``services`` (a fresh PostgreSQL database + a private Redis) when PostgreSQL answers on
127.0.0.1:5432 and ``redis-server`` is installed; otherwise skipped with the reason — or,
where ``LEGOPT_REQUIRE_SERVICES=1`` (CI), failed with it (``ChaosRedis.start``).
The stack's leases are short (4 s lease, 1 s heartbeat, checkpoint every generation).
Teardown of the stack checks that no process it started (or a descendant) survives it.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.chaos.harness import ChaosRedis, ChaosStack
from tests.chaos.scenario import Scenario
from tests.integration.stack import KINDS, postgres_database
from tests.patience import Patience


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """``@pytest.mark.stacks("embedded")``: the test exists only for those stack kinds (the
    other kinds' instances are deselected, not skipped: there is nothing there to prove)."""
    keep: list[pytest.Item] = []
    drop: list[pytest.Item] = []
    for item in items:
        mark = item.get_closest_marker("stacks")
        callspec = getattr(item, "callspec", None)
        kind = callspec.params.get("chaos_stack") if callspec is not None else None
        (drop if mark is not None and kind is not None and kind not in mark.args else keep).append(
            item
        )
    if drop:
        config.hook.pytest_deselected(items=drop)
        items[:] = keep


@pytest.fixture(scope="package", params=KINDS)
def chaos_stack(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[ChaosStack]:
    kind = request.param
    tmp: Path = tmp_path_factory.mktemp(f"chaos-{kind}")
    (tmp / "data").mkdir(parents=True, exist_ok=True)
    if kind == "embedded":
        st = ChaosStack(kind, tmp, f"sqlite:///{tmp / 'data' / 'legopt.db'}", "filesystem://")
        yield from _run(st)
        return
    redis = ChaosRedis(tmp)
    redis.start()
    try:
        with postgres_database() as url:
            st = ChaosStack(kind, tmp, url, redis.url)
            st.redis = redis
            assert redis.proc is not None
            st.track_tree(redis.proc.pid)
            yield from _run(st)
    finally:
        redis.stop()


def _run(st: ChaosStack) -> Iterator[ChaosStack]:
    st.migrate_and_key()
    st.start_api()
    assert st.api is not None
    st.track_tree(st.api.pid)
    try:
        yield st
    finally:
        st.stop()
        if st.redis is not None:
            st.redis.stop()
        # a child exits when it sees its parent gone (end of file on a pipe): give it a moment
        patience = Patience(10)
        left = st.leftover_processes()
        while left and not patience.expired():
            time.sleep(0.1)
            left = st.leftover_processes()
        st.kill_leftovers()
        assert not left, f"processes left after the {st.kind} stack stopped: {left}"


@pytest.fixture
def scenario(chaos_stack: ChaosStack, request: pytest.FixtureRequest) -> Iterator[Scenario]:
    chaos_stack.ensure_api()
    sc = Scenario(chaos_stack, request.node.name)
    try:
        yield sc
    finally:
        sc.close()
