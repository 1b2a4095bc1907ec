"""BoundedWork: a piece of work that is already over when ``run`` registers its clean-up (it
failed at once, e.g. an artifact that is gone) neither deadlocks nor stays pending."""

from __future__ import annotations

import threading
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

import pytest

from services.api.bounded_work import BoundedWork


class _DoneAtOnce:
    """An executor whose futures are finished before ``submit`` returns."""

    def submit(self, fn: Callable[[], Any]) -> Future[Any]:
        future: Future[Any] = Future()
        try:
            future.set_result(fn())
        except Exception as exc:
            future.set_exception(exc)
        return future


def test_work_over_before_its_callback_is_added() -> None:
    work = BoundedWork("test-done-at-once", workers=1, max_pending=2, wait_s=5)
    work._executor = _DoneAtOnce()  # type: ignore[assignment]
    outcome: list[Any] = []

    def fail() -> None:
        raise FileNotFoundError("gone")

    def requests() -> None:
        with pytest.raises(FileNotFoundError):
            work.run("a", fail, "the failing work")
        outcome.append(work.run("b", lambda: 42, "the quick work"))

    caller = threading.Thread(target=requests, daemon=True)
    caller.start()
    caller.join(timeout=10)
    assert not caller.is_alive(), "BoundedWork.run deadlocked on a finished future"
    assert outcome == [42] and work.pending == 0
