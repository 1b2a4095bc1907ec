"""Rule 6's protocol allowance (``paced_resends``), on hand-made event timelines: a re-send a
lease after the previous one is allowed, a storm of re-sends closer than a lease is not."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta
from typing import Any

from tests.chaos.invariants import paced_resends

T0 = datetime(2026, 1, 1, tzinfo=UTC)


def _events(*rows: tuple[float, str]) -> list[dict[str, Any]]:
    return [{"job_id": "j", "kind": k, "at": T0 + timedelta(seconds=t)} for t, k in rows]


def test_a_resend_a_lease_after_the_previous_is_allowed() -> None:
    ev = _events((0, "submitted"), (0.1, "dispatched"), (5.7, "dispatched"), (6.0, "claimed"))
    assert paced_resends(ev, lease_s=4.0)["j"] == 1


def test_resends_closer_than_a_lease_are_not() -> None:
    ev = _events((0, "submitted"), (0.1, "dispatched"), (1.1, "dispatched"), (2.1, "dispatched"))
    assert paced_resends(ev, lease_s=4.0)["j"] == 0


def test_a_claim_starts_a_new_stretch() -> None:
    ev = _events(
        (0, "submitted"), (0.1, "dispatched"), (1.0, "claimed"), (9.0, "requeued"),
        (9.5, "dispatched"),
    )  # fmt: skip
    assert paced_resends(ev, lease_s=4.0)["j"] == 0
