"""Fixtures: a running stack (API + 2 workers) per backend kind, shared by a test module."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.integration.stack import KINDS, RedisServer, Stack, postgres_database


@pytest.fixture(scope="module", params=KINDS)
def stack(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[Stack]:
    kind = request.param
    tmp: Path = tmp_path_factory.mktemp(f"stack-{kind}")
    if kind == "embedded":
        st = Stack(kind, tmp, f"sqlite:///{tmp / 'data' / 'legopt.db'}", "filesystem://")
        (tmp / "data").mkdir(parents=True, exist_ok=True)
        yield from _run(st)
        return
    redis = RedisServer(tmp)
    redis.start()
    try:
        with postgres_database() as url:
            st = Stack(kind, tmp, url, redis.url)
            st.redis = redis  # type: ignore[attr-defined]
            yield from _run(st)
    finally:
        redis.stop()


def _run(st: Stack) -> Iterator[Stack]:
    st.migrate_and_key()
    st.start_api()
    st.start_worker()
    st.start_worker()
    try:
        yield st
    finally:
        st.stop()
