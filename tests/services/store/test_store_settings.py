"""The settings object: defaults, environment, overrides, validation, caching."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pydantic
import pytest

from services.store.settings import Settings, get_settings


def test_defaults_are_embedded_and_relative() -> None:
    s = Settings.from_env(env={})
    assert s.data_dir == Path("legopt-data")
    assert s.database_url == "sqlite:///legopt-data/legopt.db"
    assert s.artifact_dir == Path("legopt-data/artifacts")
    assert s.broker_url == "filesystem://"
    assert s.broker_dir == Path("legopt-data/broker")
    assert s.result_backend is None
    assert s.is_sqlite
    assert not Path(s.database_url.removeprefix("sqlite:///")).is_absolute()
    assert 0 < s.heartbeat_seconds < s.lease_seconds


def test_environment_variables_are_read() -> None:
    env = {
        "LEGOPT_DATA_DIR": "somewhere",
        "LEGOPT_DATABASE_URL": "postgresql+psycopg://u@db/legopt",
        "LEGOPT_BROKER_URL": "redis://redis:6379/0",
        "LEGOPT_RESULT_BACKEND": "redis://redis:6379/1",
        "LEGOPT_LEASE_SECONDS": "120",
        "LEGOPT_HEARTBEAT_SECONDS": "20",
        "LEGOPT_MAX_POPULATION": "50",
        "LEGOPT_UNRELATED": "ignored",
    }
    s = Settings.from_env(env=env)
    assert s.database_url == "postgresql+psycopg://u@db/legopt"
    assert s.broker_url == "redis://redis:6379/0"
    assert s.result_backend == "redis://redis:6379/1"
    assert s.artifact_dir == Path("somewhere/artifacts")  # derived from the data dir
    assert (s.lease_seconds, s.heartbeat_seconds, s.max_population) == (120.0, 20.0, 50)
    assert not s.is_sqlite


def test_data_dir_moves_the_derived_defaults() -> None:
    s = Settings.from_env(env={"LEGOPT_DATA_DIR": "d"})
    assert s.database_url == "sqlite:///d/legopt.db"
    assert s.artifact_dir == Path("d/artifacts")


def test_overrides_win_and_settings_are_frozen() -> None:
    s = Settings.from_env(env={"LEGOPT_MAX_WORK": "10"}, max_work=99)
    assert s.max_work == 99
    with pytest.raises(pydantic.ValidationError):
        s.max_work = 5  # type: ignore[misc]
    t = s.with_overrides(lease_seconds=30.0, heartbeat_seconds=5.0)
    assert (t.lease_seconds, s.lease_seconds) == (30.0, 60.0)
    assert not dataclasses.is_dataclass(t)


def test_invalid_values_are_rejected() -> None:
    with pytest.raises(pydantic.ValidationError, match="heartbeat_seconds"):
        Settings.from_env(env={}, lease_seconds=10, heartbeat_seconds=10)
    with pytest.raises(pydantic.ValidationError):
        Settings.from_env(env={"LEGOPT_MAX_POPULATION": "many"})
    with pytest.raises(pydantic.ValidationError):
        Settings(unknown_field=1)  # type: ignore[call-arg]


def test_job_size_limits() -> None:
    s = Settings.from_env(
        env={}, max_population=100, max_generations=100, max_samples=1000, max_work=10**6
    )
    assert s.check_job_size(100, 100, 100) is None
    assert "population" in (s.check_job_size(101, 1) or "")
    assert "generations" in (s.check_job_size(1, 101) or "")
    assert "samples" in (s.check_job_size(1, 1, 1001) or "")
    assert "exceeds the limit 1000000" in (s.check_job_size(100, 100, 101) or "")


def test_get_settings_is_cached_and_reads_the_environment(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    get_settings.cache_clear()
    monkeypatch.setenv("LEGOPT_DATABASE_URL", "sqlite:///elsewhere.db")
    try:
        first = get_settings()
        monkeypatch.setenv("LEGOPT_DATABASE_URL", "sqlite:///changed.db")
        assert get_settings() is first
        assert first.database_url == "sqlite:///elsewhere.db"
    finally:
        get_settings.cache_clear()
