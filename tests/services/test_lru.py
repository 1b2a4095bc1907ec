"""services.lru.BuiltCache: built once per key, least recently used dropped first."""

from __future__ import annotations

from services.lru import BuiltCache


def test_built_once_per_key_and_oldest_dropped() -> None:
    built: list[str] = []
    cache: BuiltCache[str] = BuiltCache(2)

    def get(key: str) -> str:
        return cache.get_or_build(key, lambda: built.append(key) or key.upper())

    assert [get("a"), get("b"), get("a")] == ["A", "B", "A"]
    assert built == ["a", "b"]
    get("c")  # drops b, the least recently used
    get("a")
    get("b")
    assert built == ["a", "b", "c", "b"]
