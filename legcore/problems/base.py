"""The `Problem` abstraction every study implements and every optimiser drives.

Conventions (the same as pymoo's):

- **Minimisation** of every objective. A study that maximises a score reports ``-score``.
- **Batch evaluation**: ``evaluate(X)`` takes a whole population ``X`` of shape ``(B, n_var)`` and
  returns ``F`` of shape ``(B, n_obj)`` and ``G`` of shape ``(B, n_constr)`` in one call.
- **Constraints** ``G <= 0`` are feasible; ``G`` has 0 columns for an unconstrained problem. The
  constraint violation of a row is ``CV = sum(max(G, 0))``.
- **Integer coding** (seed 000): with a per-variable ``resolution`` the decision variable is
  ``x = k * resolution`` for an integer gene ``k`` in
  ``[ceil(xl / resolution), floor(xu / resolution)]``, so every value the optimiser proposes is a
  value the controller can reach. ``resolution=None`` means continuous variables.

A subclass calls ``super().__init__(...)`` with its sizes and bounds and implements
``_evaluate(X) -> (F, G)`` (``G`` may be ``None`` when ``n_constr == 0``). The public ``evaluate``
validates shapes, dtypes and finiteness of the input, so ``_evaluate`` can assume a clean batch.
``decode`` and ``baselines`` have defaults a study overrides to return its full trajectory and the
reference solutions of its seed paper.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["Problem", "constraint_violation"]

_ArrayLike = np.ndarray | Sequence[float] | float

# Slack when converting float bounds to integer gene bounds, so that a bound that *is* a multiple
# of the resolution (up to float rounding, e.g. 0.3 / 0.1 = 2.9999999999999996) stays included.
_GRID_SLACK = 1e-9


def constraint_violation(G: np.ndarray) -> np.ndarray:
    """Total constraint violation per row, ``sum_i max(G_i, 0)`` (0 for feasible rows).

    Args:
        G: constraint values ``(B, n_constr)``; ``G <= 0`` is feasible. May have 0 columns.

    Returns:
        ``(B,)`` float array, ``>= 0``.
    """
    G = np.asarray(G, dtype=float)
    if G.ndim != 2:
        raise ValueError(f"G: expected a 2-D array (B, n_constr), got shape {G.shape}")
    if G.shape[1] == 0:
        return np.zeros(G.shape[0])
    return np.maximum(G, 0.0).sum(axis=1)


def _as_bound(name: str, value: _ArrayLike, n_var: int) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        arr = np.full(n_var, float(arr))
    if arr.shape != (n_var,):
        raise ValueError(f"{name}: expected shape ({n_var},), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: bounds must be finite")
    return arr


class Problem(ABC):
    """A vectorised optimisation problem: bounds, objectives ``F`` and constraints ``G <= 0``.

    Args:
        n_var: number of decision variables (>= 1).
        n_obj: number of objectives (>= 1), all minimised.
        n_constr: number of inequality constraints ``G <= 0`` (>= 0).
        xl: lower bounds, scalar or ``(n_var,)``.
        xu: upper bounds, scalar or ``(n_var,)``; ``xu >= xl``.
        resolution: ``None`` for continuous variables, or a positive scalar / ``(n_var,)`` array:
            variable ``j`` then only takes values ``k * resolution[j]`` for integer ``k``.
        name: a short label used in reports.

    Attributes:
        n_var, n_obj, n_constr, xl, xu, resolution, name: as given (arrays are read-only).
    """

    #: Memory budget (bytes) of one ``evaluate`` call; ``None``: :mod:`legcore.memory`'s default.
    eval_budget_bytes: int | None = None

    def __init__(
        self,
        n_var: int,
        n_obj: int = 1,
        n_constr: int = 0,
        *,
        xl: _ArrayLike,
        xu: _ArrayLike,
        resolution: _ArrayLike | None = None,
        name: str | None = None,
    ) -> None:
        sizes = (("n_var", n_var, 1), ("n_obj", n_obj, 1), ("n_constr", n_constr, 0))
        for pname, value, low in sizes:
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
                raise ValueError(f"{pname}: expected an integer >= {low}, got {value!r}")
        self.n_var = int(n_var)
        self.n_obj = int(n_obj)
        self.n_constr = int(n_constr)
        self.xl = _as_bound("xl", xl, self.n_var)
        self.xu = _as_bound("xu", xu, self.n_var)
        bad = np.flatnonzero(self.xl > self.xu)
        if bad.size:
            j = int(bad[0])
            raise ValueError(f"xl/xu: lower bound above upper bound for variable {j} "
                             f"({self.xl[j]} > {self.xu[j]})")
        self.xl.flags.writeable = False
        self.xu.flags.writeable = False
        self.resolution: np.ndarray | None
        if resolution is None:
            self.resolution = None
        else:
            res = _as_bound("resolution", resolution, self.n_var)
            if np.any(res <= 0):
                raise ValueError("resolution: every entry must be > 0")
            self.resolution = res
            self.resolution.flags.writeable = False
            k_lo, k_hi = self.gene_bounds()
            empty = np.flatnonzero(k_lo > k_hi)
            if empty.size:
                j = int(empty[0])
                raise ValueError(f"resolution: no multiple of {res[j]} lies in "
                                 f"[{self.xl[j]}, {self.xu[j]}] for variable {j}")
        self.name = name or type(self).__name__

    # ------------------------------------------------------------------ integer coding
    @property
    def is_integer(self) -> bool:
        """True when the variables are integer-coded at ``resolution``."""
        return self.resolution is not None

    def gene_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Integer gene bounds ``(k_lo, k_hi)`` (int64, ``(n_var,)``) of an integer-coded problem.

        ``x_j = k_j * resolution_j`` stays within ``[xl_j, xu_j]`` for ``k_lo_j <= k_j <= k_hi_j``.
        """
        if self.resolution is None:
            raise ValueError("resolution: this problem has continuous variables (resolution=None)")
        k_lo = np.ceil(self.xl / self.resolution - _GRID_SLACK).astype(np.int64)
        k_hi = np.floor(self.xu / self.resolution + _GRID_SLACK).astype(np.int64)
        return k_lo, k_hi

    def snap(self, X: np.ndarray) -> np.ndarray:
        """Clip ``X`` to the bounds and, for an integer-coded problem, round it onto the grid.

        Returns a new ``(B, n_var)`` array; every row is a valid decision vector.
        """
        X = np.asarray(X, dtype=float)
        if self.resolution is None:
            return np.clip(X, self.xl, self.xu)
        k_lo, k_hi = self.gene_bounds()
        K = np.clip(np.rint(X / self.resolution), k_lo, k_hi)
        return K * self.resolution

    # ------------------------------------------------------------------ evaluation
    def evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Evaluate a whole batch.

        Args:
            X: ``(B, n_var)`` decision vectors (a single ``(n_var,)`` vector is accepted as B = 1).

        A batch larger than :meth:`chunk_rows` is evaluated in consecutive chunks of rows (rows
        are independent, so the result is the same) so that its memory stays within the
        evaluation budget (see :mod:`legcore.memory`).

        Returns:
            ``F`` ``(B, n_obj)`` and ``G`` ``(B, n_constr)``, float arrays.

        Raises:
            ValueError: if ``X`` has the wrong shape or non-finite entries, or ``_evaluate``
                returns arrays of the wrong shape.
        """
        X = np.asarray(X, dtype=float)
        if X.ndim == 1:
            X = X[None, :]
        if X.ndim != 2 or X.shape[1] != self.n_var:
            raise ValueError(f"X: expected shape (B, {self.n_var}), got {X.shape}")
        if not np.all(np.isfinite(X)):
            raise ValueError("X: contains NaN or infinite entries")
        n = X.shape[0]
        rows = self.chunk_rows(X)
        if n <= rows:
            F, G = self._evaluate(X)
            return self.check_output(n, F, G)
        parts = [self.check_output(min(rows, n - i), *self._evaluate(X[i : i + rows]))
                 for i in range(0, n, rows)]
        return (np.concatenate([p[0] for p in parts], axis=0),
                np.concatenate([p[1] for p in parts], axis=0))

    def chunk_rows(self, X: np.ndarray | None = None) -> int:
        """At most this many rows are passed to ``_evaluate`` at once (``evaluate`` splits a
        larger batch ``X`` and concatenates the results): the evaluation budget over the bytes
        one row costs, :func:`legcore.memory.chunk_rows`. Set the ``eval_budget_bytes``
        attribute to change the budget of one problem (bytes; ``None``:
        ``LEGOPT_EVAL_MEMORY_MB`` or 256 MiB)."""
        from legcore.memory import chunk_rows

        return chunk_rows(self, X=X)

    def check_output(self, n: int, F: Any, G: Any) -> tuple[np.ndarray, np.ndarray]:
        """Coerce and validate ``(F, G)`` for a batch of ``n`` rows (used by ``evaluate``)."""
        F = np.asarray(F, dtype=float)
        if F.ndim == 1 and self.n_obj == 1:
            F = F[:, None]
        if F.shape != (n, self.n_obj):
            raise ValueError(f"F: {self.name} returned shape {F.shape}, "
                             f"expected ({n}, {self.n_obj})")
        if np.any(np.isnan(F)):
            raise ValueError(f"F: {self.name} returned NaN objective values")
        if G is None:
            if self.n_constr:
                raise ValueError(f"G: {self.name} has {self.n_constr} constraints "
                                 "but returned None")
            G = np.zeros((n, 0))
        G = np.asarray(G, dtype=float)
        if G.ndim == 1 and self.n_constr == 1:
            G = G[:, None]
        if G.shape != (n, self.n_constr):
            raise ValueError(f"G: {self.name} returned shape {G.shape}, "
                             f"expected ({n}, {self.n_constr})")
        if np.any(np.isnan(G)):
            raise ValueError(f"G: {self.name} returned NaN constraint values")
        return F, G

    @abstractmethod
    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """Compute ``(F, G)`` for a validated ``(B, n_var)`` batch (``G`` may be ``None``)."""

    # ------------------------------------------------------------------ reporting
    def decode(self, x: np.ndarray) -> dict[str, Any]:
        """Turn one decision vector into a readable solution.

        The default returns ``{"x": x}``; a study overrides this to return its full trajectory.
        """
        x = np.asarray(x, dtype=float)
        if x.shape != (self.n_var,):
            raise ValueError(f"x: expected shape ({self.n_var},), got {x.shape}")
        return {"x": x.copy()}

    def baselines(self) -> dict[str, np.ndarray]:
        """Named reference decision vectors to compare an optimum against (default: none)."""
        return {}

    def initial_points(self) -> np.ndarray | None:
        """Decision vectors ``(k, n_var)`` the first population starts with (the rest is
        random), as pymoo's ``sampling=`` array — e.g. a solution an exact method gives for a
        relaxation of the problem; None (the default): a random start only."""
        return None

    def __repr__(self) -> str:
        kind = "integer" if self.is_integer else "continuous"
        return (f"{self.name}(n_var={self.n_var}, n_obj={self.n_obj}, "
                f"n_constr={self.n_constr}, {kind})")
