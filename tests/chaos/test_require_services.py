"""``LEGOPT_REQUIRE_SERVICES=1`` (``.ci/run`` sets it when PostgreSQL and redis-server are up):
a services-stack or PostgreSQL test whose server is missing fails naming what is missing; it is
skipped only where the variable is not set (``tests/integration/stack.py``). No process is
started here: the probes are replaced."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.integration import stack


@pytest.fixture
def nothing_up(monkeypatch: pytest.MonkeyPatch) -> pytest.MonkeyPatch:
    """Neither PostgreSQL nor redis-server is available."""
    monkeypatch.setattr(stack, "postgres_available", lambda: False)
    monkeypatch.setattr(stack, "redis_server_binary", lambda: None)
    return monkeypatch


def test_missing_services_fail_where_required(
    nothing_up: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    nothing_up.setenv(stack.REQUIRE_SERVICES_ENV, "1")
    assert not stack.services_available()
    message = r"LEGOPT_REQUIRE_SERVICES=1 requires .* no PostgreSQL server .* redis-server"
    with pytest.raises(pytest.fail.Exception, match=message):
        stack.require_services()
    with pytest.raises(pytest.fail.Exception, match="no PostgreSQL server"):
        with stack.postgres_database():
            pass
    with pytest.raises(pytest.fail.Exception, match="no PostgreSQL server"):
        with stack.service_database("postgresql", tmp_path):
            pass
    with pytest.raises(pytest.fail.Exception, match="redis-server is not installed"):
        stack.RedisServer(tmp_path).start()
    # the parameters are not skipped: the test runs and its fixture fails as above
    param = stack.when_available("services", stack.services_missing())
    assert not param.marks


def test_missing_services_skip_where_not_required(
    nothing_up: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    nothing_up.delenv(stack.REQUIRE_SERVICES_ENV, raising=False)
    with pytest.raises(pytest.skip.Exception, match="redis-server is not installed"):
        stack.require_services()
    with pytest.raises(pytest.skip.Exception, match="no PostgreSQL server"):
        with stack.service_database("postgresql", tmp_path):
            pass
    (mark,) = stack.when_available("services", stack.services_missing()).marks
    assert mark.name == "skip" and "redis-server" in mark.kwargs["reason"]
    with stack.service_database("sqlite", tmp_path) as url:  # SQLite needs no server
        assert url.startswith("sqlite:///")


def test_kinds_and_databases_follow_the_probes() -> None:
    services = stack.KINDS[1]
    postgresql = stack.DATABASES[1]
    assert services.values == ("services",) and postgresql.values == ("postgresql",)
    assert bool(services.marks) == (
        stack.services_missing() is not None and not stack.services_required()
    )
    assert bool(postgresql.marks) == (
        stack.postgres_missing() is not None and not stack.services_required()
    )
