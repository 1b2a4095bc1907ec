"""Security suite: the attacks of the review, on real processes where they need a worker.

``stack`` is the integration fixture (API + 2 workers on the embedded stack and, when
PostgreSQL and redis-server are present, on PostgreSQL + Redis), shared per module.
"""

from __future__ import annotations

from tests.integration.conftest import stack

__all__ = ["stack"]
