"""Security suite: the attacks of the review, on real processes where they need a worker, and
in process on both databases where they do not.

``stack`` is the integration fixture (API + 2 workers on the embedded stack and, when
PostgreSQL and redis-server are present, on PostgreSQL + Redis), shared per module.
``db_settings`` is the settings of an in-process API on a migrated database, once per module
and database kind (``tests.security.databases``: SQLite, and PostgreSQL where it answers —
skipped otherwise, failed where ``LEGOPT_REQUIRE_SERVICES=1``).
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from services.store.settings import Settings
from tests.integration.conftest import stack
from tests.security.databases import DATABASES, migrated_settings

__all__ = ["db_settings", "stack"]


@pytest.fixture(scope="module", params=DATABASES)
def db_settings(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[Settings]:
    """Settings on a fresh migrated database of each kind, shared by a test module."""
    kind: str = request.param
    with migrated_settings(kind, tmp_path_factory.mktemp(f"db-{kind}")) as settings:
        yield settings
