"""Shared fixture of the worker tests: settings over a fresh, migrated SQLite store."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from services.store.migrate import upgrade
from services.store.session import reset_engine
from services.store.settings import Settings, get_settings


@pytest.fixture
def settings(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Settings]:
    """The process settings over ``tmp_path`` (SQLite ``legopt.db``, artifacts beside it),
    checkpoint every generation; the engine and settings cache reset before and after."""
    url = f"sqlite:///{tmp_path / 'legopt.db'}"
    monkeypatch.setenv("LEGOPT_DATA_DIR", str(tmp_path))
    monkeypatch.setenv("LEGOPT_DATABASE_URL", url)
    monkeypatch.setenv("LEGOPT_CHECKPOINT_EVERY", "1")
    get_settings.cache_clear()
    reset_engine()
    upgrade(url)
    try:
        yield get_settings()
    finally:
        get_settings.cache_clear()
        reset_engine()
