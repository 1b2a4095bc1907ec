"""Per-API-key request rate limit: a token bucket per key, in each API process.

A key may make ``burst`` requests at once and ``rate_per_s`` per second sustained; beyond that
the API answers 429 with ``Retry-After``. A request takes one token plus one per full
``COST_BYTES`` of its body (:func:`request_cost`): large uploads count for what they weigh.
Buckets live in the process (each uvicorn worker process limits on its own, so the
cluster-wide limit is at most processes × rate), which is enough to stop one key from
monopolising the API without a shared store.
"""

from __future__ import annotations

import math
import threading
import time
from collections import OrderedDict


class RateLimiter:
    """Token buckets keyed by API key id (least recently used ones forgotten past ``max_keys``)."""

    def __init__(self, rate_per_s: float, burst: int, *, max_keys: int = 10_000) -> None:
        if rate_per_s <= 0 or burst <= 0:
            raise ValueError("rate_per_s and burst must be > 0")
        self.rate_per_s, self.burst, self.max_keys = float(rate_per_s), int(burst), max_keys
        self._buckets: OrderedDict[str, tuple[float, float]] = OrderedDict()
        self._lock = threading.Lock()

    def acquire(self, key_id: str, now: float | None = None, *, cost: int = 1) -> float:
        """Take ``cost`` tokens (at most ``burst``) for ``key_id``: 0.0 if allowed, else seconds
        until they are available."""
        now = time.monotonic() if now is None else now
        need = float(min(max(1, cost), self.burst))
        with self._lock:
            tokens, last = self._buckets.pop(key_id, (float(self.burst), now))
            tokens = min(float(self.burst), tokens + (now - last) * self.rate_per_s)
            wait = 0.0
            if tokens >= need:
                tokens -= need
            else:
                wait = (need - tokens) / self.rate_per_s
            self._buckets[key_id] = (tokens, now)
            while len(self._buckets) > self.max_keys:
                self._buckets.popitem(last=False)
            return wait


#: Body bytes one rate-limit token pays for, beyond the request's own token.
COST_BYTES = 256 * 1024


def request_cost(content_length: str | None) -> int:
    """Tokens a request takes: 1, plus 1 per full ``COST_BYTES`` of its declared body."""
    try:
        size = max(0, int(content_length or 0))
    except ValueError:
        size = 0
    return 1 + size // COST_BYTES


def retry_after_header(wait_s: float) -> str:
    """The ``Retry-After`` value (whole seconds, at least 1) for a wait of ``wait_s``."""
    return str(max(1, math.ceil(wait_s)))


__all__ = ["COST_BYTES", "RateLimiter", "request_cost", "retry_after_header"]
