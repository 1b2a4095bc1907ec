"""API key generation and hashing. Only ``hash_api_key(raw)`` is ever stored.

Keys are 256-bit random tokens, so a plain SHA-256 is a sufficient one-way hash (no slow
password hash is needed for non-guessable secrets); lookups are by the hash.
"""

from __future__ import annotations

import hashlib
import secrets

KEY_PREFIX = "lgo_"


def hash_api_key(raw_key: str) -> str:
    """Hex SHA-256 of a raw API key (what the ``api_keys.key_hash`` column holds)."""
    return hashlib.sha256(raw_key.encode("utf-8")).hexdigest()


def generate_api_key() -> tuple[str, str]:
    """A new key as ``(raw_key, key_hash)``; show ``raw_key`` once, store ``key_hash``."""
    raw = KEY_PREFIX + secrets.token_urlsafe(32)
    return raw, hash_api_key(raw)
