"""Reading ``.rrd`` files back with the Rerun SDK's own reader, for the recording tests."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import numpy as np
import pyarrow as pa
from rerun.chunk import RrdReader


def read_back(path: Path) -> dict[str, list[pa.RecordBatch]]:
    """Entity path (no leading /) → record batches of its chunks, via rerun.chunk.RrdReader."""
    out: dict[str, list[pa.RecordBatch]] = defaultdict(list)
    for chunk in RrdReader(path).stream():
        out[chunk.entity_path.lstrip("/")].append(chunk.to_record_batch())
    return dict(out)


def column(batches: list[pa.RecordBatch], name: str, index: str) -> tuple[np.ndarray, list]:
    """(index values — s for a duration timeline —, component values) of the rows of
    ``batches`` that carry ``name``, sorted by index."""
    idx: list[np.ndarray] = []
    vals: list = []
    for b in batches:
        if name in b.schema.names and index in b.schema.names:
            col = b.column(index)
            scale = 1e-9 if pa.types.is_duration(col.type) else 1.0
            idx.append(col.cast(pa.int64()).to_numpy() * scale)
            vals.extend(b.column(name).to_pylist())
    i = np.concatenate(idx) if idx else np.zeros(0)
    order = np.argsort(i, kind="stable")
    return i[order], [vals[k] for k in order]


def signal(batches: list[pa.RecordBatch], j: int, index: str = "time") -> tuple[np.ndarray, list]:
    """(index, [[value]] rows) of joint ``j`` of a signal logged as one entity (a ``Scalars``
    batch of one value per joint at each sample)."""
    t, vals = column(batches, "Scalars:scalars", index)
    return t, [[v[j]] for v in vals]
