"""Display downsampling: which samples of a long signal a recording keeps."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from legcore.recording.model import DEFAULT_MAX_SAMPLES, FloatArray, IntArray

if TYPE_CHECKING:
    pass

# ---------------------------------------------------------------------------------------------
# downsampling
# ---------------------------------------------------------------------------------------------


def stride_indices(K: int, max_samples: int = DEFAULT_MAX_SAMPLES) -> IntArray:
    """Indices of a uniform-stride subsample of ``K`` samples: all of them when
    ``K <= max_samples``, else ``round(linspace(0, K-1, max_samples))`` (exactly
    ``max_samples`` distinct indices, first and last included)."""
    if max_samples < 2:
        raise ValueError(f"max_samples: must be >= 2, got {max_samples}")
    if K <= max_samples:
        return np.arange(K, dtype=np.int64)
    return np.unique(np.round(np.linspace(0, K - 1, max_samples)).astype(np.int64))


def minmax_indices(y: FloatArray, max_samples: int = DEFAULT_MAX_SAMPLES) -> IntArray:
    """Indices of a min/max decimation of the signal ``y`` (K,): all of them when
    ``K <= max_samples``; else the first and last sample plus, in each of
    ``(max_samples - 2) // 2`` equal buckets of the interior, the samples of the bucket's
    minimum and maximum (NaN ignored). At most ``max_samples`` sorted distinct indices."""
    y = np.asarray(y, dtype=float)
    return minmax_columns(y[:, None], max_samples)[0]


def shared_minmax_indices(Y: FloatArray, max_samples: int = DEFAULT_MAX_SAMPLES) -> IntArray:
    """One set of indices for all columns of ``Y`` (K, n) (the joints of one signal, logged as
    one entity): all of them when ``K <= max_samples``; else the union over columns of each
    column's :func:`minmax_columns` at the largest per-column cap (at least 4) whose union has
    at most ``max_samples`` sorted distinct indices — every column keeps its bucket minima and
    maxima, every kept value is an original sample."""
    Y = np.asarray(Y, dtype=float)
    K, n = Y.shape
    if K <= max_samples:
        return np.arange(K, dtype=np.int64)
    per = max_samples
    while True:  # joints often peak together: shrink the per-joint cap only as far as needed
        idx = np.unique(np.concatenate(minmax_columns(Y, per)))
        if idx.size <= max_samples or per <= 4:
            return idx
        per = max(4, min(per - 2, int(per * max_samples / idx.size)))


def minmax_columns(Y: FloatArray, max_samples: int = DEFAULT_MAX_SAMPLES) -> list[IntArray]:
    """:func:`minmax_indices` of every column of ``Y`` (K, n) in one vectorised pass."""
    Y = np.asarray(Y, dtype=float)
    K, n = Y.shape
    if max_samples < 4:
        return [stride_indices(K, max(2, max_samples))] * n
    if K <= max_samples:
        return [np.arange(K, dtype=np.int64)] * n
    n_buckets = (max_samples - 2) // 2
    edges = np.linspace(1, K - 1, n_buckets + 1).astype(np.int64)  # interior 1 .. K-2
    starts, stops = edges[:-1], edges[1:]
    width = int(np.max(stops - starts))
    # gather each bucket into a (n_buckets, width) window, padding with the bucket's first sample
    idx = starts[:, None] + np.arange(width)[None, :]
    idx = np.where(idx < stops[:, None], idx, starts[:, None])
    win = Y[idx]  # (n_buckets, width, n)
    finite = np.isfinite(win)
    rows = np.arange(n_buckets)[:, None]
    imin = idx[rows, np.argmin(np.where(finite, win, np.inf), axis=1)]  # (n_buckets, n)
    imax = idx[rows, np.argmax(np.where(finite, win, -np.inf), axis=1)]
    ends = np.array([0, K - 1], dtype=np.int64)
    return [np.unique(np.concatenate((ends, imin[:, j], imax[:, j]))) for j in range(n)]
