"""Compact binary form of a per-generation Pareto front (``generations.front_packed``).

A front is a (k, m) array of objective vectors, stored for display only (the recording's
generation timeline, a front point's recording): little-endian float64 after an 8-byte header
``<II`` (k, m) — 24 bytes per point of three objectives instead of ~60 bytes of JSON, with the
exact values (the stored hypervolume of a generation is that of its stored front). Non-finite
values are stored as NaN and read back as ``None``, as the JSON column did.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np

_HEADER = struct.Struct("<II")


def encode_front(front: Any) -> bytes | None:
    """``front`` (k, m) array-like (``None`` entries allowed) as bytes; None for no front."""
    if front is None:
        return None
    F = np.asarray(front, dtype=float)
    if F.ndim != 2 or F.size == 0:
        return None
    F = np.where(np.isfinite(F), F, np.nan).astype("<f8")
    return _HEADER.pack(*F.shape) + F.tobytes()


def decode_front_array(blob: bytes) -> np.ndarray:
    """The (k, m) float64 array of ``encode_front``'s bytes (NaN where not finite)."""
    k, m = _HEADER.unpack_from(blob)
    data = np.frombuffer(blob, dtype="<f8", count=k * m, offset=_HEADER.size)
    return data.reshape(k, m).astype(float)


def decode_front(blob: bytes) -> list[list[float | None]]:
    """``encode_front``'s bytes as a JSON-like list of rows (``None`` where not finite)."""
    F = decode_front_array(blob)
    rows: list[list[float | None]] = F.tolist()
    if np.isnan(F).any():
        rows = [[None if v != v else v for v in row] for row in rows]
    return rows
