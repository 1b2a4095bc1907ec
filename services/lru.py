"""A small thread-safe cache of the last few built objects, keyed by a content string."""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import Generic, TypeVar

V = TypeVar("V")


class BuiltCache(Generic[V]):
    """The last ``size`` distinct values by key, least recently used dropped first. ``build``
    runs outside the lock (it may take seconds), so two threads missing the same key may both
    build it; the values must not be modified after they are built (they are shared)."""

    def __init__(self, size: int) -> None:
        self.size = size
        self._items: OrderedDict[str, V] = OrderedDict()
        self._lock = threading.Lock()

    def get_or_build(self, key: str, build: Callable[[], V]) -> V:
        """The value cached under ``key``, else ``build()`` (then cached)."""
        with self._lock:
            hit = self._items.get(key)
            if hit is not None:
                self._items.move_to_end(key)
                return hit
        value = build()
        with self._lock:
            self._items[key] = value
            while len(self._items) > self.size:
                self._items.popitem(last=False)
        return value
