"""The databases of the in-process security tests: SQLite always, PostgreSQL where it answers.

Each is made by ``tests.integration.stack.service_database`` (a SQLite file, or a fresh
PostgreSQL database dropped afterwards) and migrated to head with the service's own migrations,
as ``legopt db upgrade`` does. The PostgreSQL variant is skipped where no server answers on
``LEGOPT_TEST_POSTGRES_URL`` — and fails instead where ``LEGOPT_REQUIRE_SERVICES=1`` (CI).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from services.store import migrate
from services.store.settings import Settings
from tests.integration.stack import DATABASES, service_database

__all__ = ["DATABASES", "migrated_settings"]


@contextmanager
def migrated_settings(kind: str, directory: Path, **overrides: Any) -> Iterator[Settings]:
    """Settings of the API on a fresh database of ``kind`` (``sqlite`` or ``postgresql``),
    migrated to head; data and artifacts under ``directory``."""
    directory.mkdir(parents=True, exist_ok=True)
    with service_database(kind, directory) as url:
        migrate.upgrade(url)
        yield Settings.from_env(env={}, data_dir=directory, database_url=url, **overrides)
