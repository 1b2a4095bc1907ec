"""Heavy work an API request starts, bounded: a few threads, a short queue, shared results.

Some requests make something expensive on demand (a front point's recording, a sweep's merged
recording). Done naively, N parallel requests start N pieces of work and one API key can
exhaust the machine's memory. A :class:`BoundedWork` runs them on at most ``workers`` threads
of the process, with these rules:

- **Shared**: concurrent requests for the same key wait on one piece of work.
- **Queued, then refused**: at most ``max_pending`` distinct keys wait or run at once; beyond
  that a request is refused at once with 429 and ``Retry-After`` (nothing started).
- **Answered in time**: a request waits at most ``wait_s`` seconds; then it gets 503 with
  ``Retry-After`` while the work finishes in the background, so the retry finds its result
  (each caller keeps finished results where it keeps them: the artifact store, a cache).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable
from concurrent.futures import Future, ThreadPoolExecutor
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Any, TypeVar

from fastapi import HTTPException, status

T = TypeVar("T")

__all__ = ["BoundedWork"]


class BoundedWork:
    """``workers`` threads (created on first use), ``max_pending`` distinct keys at once,
    ``wait_s`` seconds per request, ``retry_after_s`` seconds advised (see the module
    docstring); ``name``: the threads' name prefix."""

    def __init__(
        self,
        name: str,
        *,
        workers: int = 1,
        max_pending: int | None = None,
        wait_s: float = 30.0,
        retry_after_s: int = 5,
    ) -> None:
        if workers < 1 or (max_pending is not None and max_pending < workers):
            raise ValueError("need workers >= 1 and max_pending >= workers")
        self.name, self.workers, self.max_pending = name, workers, max_pending
        self.wait_s, self.retry_after_s = wait_s, retry_after_s
        self._executor: ThreadPoolExecutor | None = None
        self._pending: dict[Hashable, Future[Any]] = {}
        # re-entrant: a work that is already done when its callback is added (it failed at
        # once) runs ``_forget`` in this thread, inside ``run``'s locked block
        self._lock = threading.RLock()

    @property
    def pending(self) -> int:
        """Distinct keys waiting or running now."""
        with self._lock:
            return len(self._pending)

    def run(self, key: Hashable, work: Callable[[], T], what: str) -> T:
        """``work()``'s result, shared by every concurrent request for ``key``; ``what``
        names it in the 429/503 messages. Exceptions of ``work`` reach every waiter."""
        with self._lock:
            future = self._pending.get(key)
            if future is None:
                if self.max_pending is not None and len(self._pending) >= self.max_pending:
                    raise HTTPException(
                        status.HTTP_429_TOO_MANY_REQUESTS,
                        f"{what}: {len(self._pending)} pieces of such work are already queued "
                        f"or running in this API process (at most {self.max_pending}); retry "
                        "in a few seconds",
                        headers={"Retry-After": str(self.retry_after_s)},
                    )
                if self._executor is None:
                    self._executor = ThreadPoolExecutor(
                        max_workers=self.workers, thread_name_prefix=self.name
                    )
                future = self._executor.submit(work)
                self._pending[key] = future
                future.add_done_callback(lambda _f: self._forget(key))
        try:
            return future.result(timeout=self.wait_s)
        except FutureTimeout:
            raise HTTPException(
                status.HTTP_503_SERVICE_UNAVAILABLE,
                f"{what} is still being made ({self.workers} at a time per API process); "
                "retry in a few seconds",
                headers={"Retry-After": str(self.retry_after_s)},
            ) from None

    def _forget(self, key: Hashable) -> None:
        with self._lock:
            self._pending.pop(key, None)
