"""The ask/tell `Algorithm` interface and the serialisation of its checkpointable state.

Protocol (one generation = one ask/tell; the first generation is the initial population)::

    algo = get_algorithm("moead", n_subproblems=300)
    algo.setup(problem, seed=1)
    while not algo.done:                 # plus any Termination of your own
        X = algo.ask()                   # (B, n_var), one batch per generation
        F, G = problem.evaluate(X)       # the whole batch in ONE call
        algo.tell(X, F, G)
        state = algo.state_dict()        # checkpoint whenever you like

    fresh = get_algorithm("moead", n_subproblems=300)
    fresh.setup(problem, seed=1)
    fresh.load_state_dict(state)         # continues bit-identically

``ask`` is idempotent until ``tell``: asking twice returns the same batch, and a checkpoint taken
between ``ask`` and ``tell`` re-asks that batch after a restore, so a worker killed mid-evaluation
resumes without changing the run.

State format (``state_dict()``): a plain dict of python scalars, strings, nested dicts/lists and
numpy arrays, plus the RNG ``bit_generator.state``. ``to_jsonable`` turns it into strict JSON
(arrays as base64 of their bytes, so floats round-trip bit-exactly; non-finite floats tagged);
``from_jsonable`` reverses it. Top-level keys::

    format="legcore.algorithm", version=1, kind, params, problem={n_var, n_obj, n_constr},
    generation, n_evals, rng, pending (array or None), stop_reason, incumbent, data

``data`` holds the algorithm's own arrays (population, archive, Gaussian parameters, ...).
"""

from __future__ import annotations

import base64
import math
from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np

from legcore.metrics import knee_point
from legcore.problems.base import Problem, constraint_violation

__all__ = ["Algorithm", "SeedLike", "make_rng", "to_jsonable", "from_jsonable"]

SeedLike = int | np.integer | np.random.Generator | None

STATE_FORMAT = "legcore.algorithm"
STATE_VERSION = 1
_BIT_GENERATORS = ("PCG64", "PCG64DXSM", "Philox", "SFC64", "MT19937")


def make_rng(seed: SeedLike) -> np.random.Generator:
    """``np.random.default_rng(seed)``; a Generator is used as is (not copied)."""
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int | np.integer)):
        raise ValueError(f"seed: expected an integer, a numpy Generator or None, got {seed!r}")
    if seed is not None and seed < 0:
        raise ValueError(f"seed: must be >= 0, got {seed}")
    return np.random.default_rng(seed)


def _rng_from_state(state: dict[str, Any]) -> np.random.Generator:
    name = state.get("bit_generator") if isinstance(state, dict) else None
    if name not in _BIT_GENERATORS:
        raise ValueError(f"rng: unsupported bit generator {name!r}")
    bitgen = getattr(np.random, name)()
    bitgen.state = state
    return np.random.Generator(bitgen)


# ---------------------------------------------------------------------------- JSON round trip
def to_jsonable(obj: Any) -> Any:
    """Convert a state (dicts, lists, scalars, numpy arrays) to strict-JSON-able python objects.

    Arrays become ``{"__ndarray__": base64 bytes, "dtype": ..., "shape": [...]}`` (bit-exact);
    numpy scalars become python scalars; non-finite floats become ``{"__float__": "nan"|...}``.
    """
    if isinstance(obj, np.ndarray):
        arr = np.ascontiguousarray(obj)
        if arr.dtype.kind not in "biuf":
            raise ValueError(f"state: cannot serialise arrays of dtype {arr.dtype}")
        return {
            "__ndarray__": base64.b64encode(arr.tobytes()).decode("ascii"),
            "dtype": arr.dtype.str,
            "shape": list(arr.shape),
        }
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return {"__float__": repr(obj)}
    if obj is None or isinstance(obj, bool | int | float | str):
        return obj
    raise ValueError(f"state: cannot serialise {type(obj).__name__}")


def from_jsonable(obj: Any) -> Any:
    """Inverse of `to_jsonable` (already-decoded values pass through unchanged)."""
    if isinstance(obj, dict):
        if "__ndarray__" in obj:
            raw = base64.b64decode(obj["__ndarray__"])
            arr = np.frombuffer(raw, dtype=np.dtype(obj["dtype"]))
            return arr.reshape([int(s) for s in obj["shape"]]).copy()
        if "__float__" in obj and len(obj) == 1:
            return float(obj["__float__"])
        return {k: from_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [from_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.copy()
    return obj


def _normalise_params(params: dict[str, Any]) -> Any:
    return from_jsonable(to_jsonable(params))


# ---------------------------------------------------------------------------- the interface
class Algorithm(ABC):
    """Base class of the ask/tell optimisers (GA, HKA, MOEA/D, NSGA-II).

    Subclasses validate their parameters in ``__init__`` (storing them in ``self._params``) and
    implement ``_setup``, ``_ask``, ``_tell``, ``_get_state`` and ``_set_state``; multi-objective
    ones also ``_front``. The base class keeps the problem, the RNG, the generation and
    evaluation counters, the pending batch and the best solution seen (the "incumbent": least
    constraint violation first, then lowest objective sum).
    """

    kind: ClassVar[str] = ""
    #: accepted numbers of objectives: (min, max); max None = unbounded.
    n_obj_range: ClassVar[tuple[int, int | None]] = (1, 1)

    def __init__(self) -> None:
        self._params: dict[str, Any] = {}
        self._problem: Problem | None = None
        self._rng: np.random.Generator = np.random.default_rng(0)
        self._generation = 0
        self._n_evals = 0
        self._pending: np.ndarray | None = None
        self._stop_reason: str | None = None
        self._inc: tuple[np.ndarray, np.ndarray, float] | None = None
        # the current front, computed once per generation (best() and front() both need it)
        self._front_memo: tuple[np.ndarray, np.ndarray] | None = None

    # ------------------------------------------------------------------ public API
    @property
    def params(self) -> dict[str, Any]:
        """The validated parameters (a copy)."""
        return dict(self._params)

    @property
    def problem(self) -> Problem:
        """The problem given to ``setup``."""
        if self._problem is None:
            raise RuntimeError(f"{self.kind}: call setup(problem, seed) first")
        return self._problem

    @property
    def rng(self) -> np.random.Generator:
        """The algorithm's random generator (all its randomness comes from here)."""
        return self._rng

    @property
    def generation(self) -> int:
        """Completed generations (ask/tell cycles)."""
        return self._generation

    @property
    def n_evals(self) -> int:
        """Evaluations told so far."""
        return self._n_evals

    @property
    def done(self) -> bool:
        """True when the algorithm's own stopping rule has fired (e.g. HKA's spread)."""
        return self._stop_reason is not None

    @property
    def stop_reason(self) -> str | None:
        """Why the algorithm stopped itself, or ``None``."""
        return self._stop_reason

    def setup(self, problem: Problem, seed: SeedLike = None) -> Algorithm:
        """Attach a problem and a random generator and reset the run. Returns ``self``."""
        for attr in ("n_var", "n_obj", "n_constr", "xl", "xu", "evaluate", "check_output"):
            if not hasattr(problem, attr):
                raise ValueError(f"problem: expected a legcore Problem, missing {attr!r}")
        lo, hi = self.n_obj_range
        if problem.n_obj < lo or (hi is not None and problem.n_obj > hi):
            allowed = f"{lo}" if lo == hi else f"{lo} or more" if hi is None else f"{lo}..{hi}"
            raise ValueError(f"problem: {self.kind} handles {allowed} objective(s), "
                             f"got {problem.n_obj}")
        self._problem = problem
        self._rng = make_rng(seed)
        self._generation = 0
        self._n_evals = 0
        self._pending = None
        self._stop_reason = None
        self._inc = None
        self._front_memo = None
        self._setup()
        return self

    def ask(self) -> np.ndarray:
        """The next batch to evaluate, ``(B, n_var)`` (the same batch until it is told)."""
        problem = self.problem
        if self._stop_reason is not None:
            raise RuntimeError(f"ask: {self.kind} has stopped ({self._stop_reason})")
        if self._pending is None:
            X = np.asarray(self._ask(), dtype=float)
            if X.ndim != 2 or X.shape[1] != problem.n_var or X.shape[0] == 0:
                raise RuntimeError(f"{self.kind}: produced a batch of shape {X.shape}")
            self._pending = X
        return self._pending.copy()

    def tell(self, X: np.ndarray, F: np.ndarray, G: np.ndarray | None = None) -> None:
        """Report the evaluation of the asked batch: ``F (B, n_obj)``, ``G (B, n_constr)``."""
        problem = self.problem
        if self._pending is None:
            raise RuntimeError("tell: no batch is pending; call ask() first")
        X = np.asarray(X, dtype=float)
        if X.shape != self._pending.shape or not np.array_equal(X, self._pending):
            raise ValueError("X: must be the batch returned by ask()")
        F, G = problem.check_output(X.shape[0], F, G)
        cv = constraint_violation(G)
        self._pending = None
        self._generation += 1
        self._n_evals += X.shape[0]
        self._update_incumbent(X, F, cv)
        self._tell(X, F, cv)
        self._front_memo = None

    def best(self) -> tuple[np.ndarray, np.ndarray, float]:
        """``(x, f, cv)`` of the best solution so far.

        One objective: the incumbent (least violation, then lowest ``f``). Several objectives:
        the knee point of the current front, or the incumbent while the front is empty.
        """
        self.problem  # noqa: B018 - raises if not set up
        if self._inc is None:
            raise RuntimeError("best: nothing has been evaluated yet")
        if self.problem.n_obj > 1:
            FX, FF = self.front()
            if FF.shape[0]:
                k = knee_point(FF)
                return FX[k].copy(), FF[k].copy(), 0.0
        x, f, cv = self._inc
        return x.copy(), f.copy(), cv

    def front(self) -> tuple[np.ndarray, np.ndarray]:
        """``(X, F)`` of the current non-dominated feasible set (empty arrays if none).

        For one objective: the incumbent if it is feasible.
        """
        problem = self.problem
        if problem.n_obj > 1:
            if self._front_memo is None:
                self._front_memo = self._front()
            X, F = self._front_memo
            return X.copy(), F.copy()
        if self._inc is not None and self._inc[2] <= 0.0:
            return self._inc[0][None, :].copy(), self._inc[1][None, :].copy()
        return np.zeros((0, problem.n_var)), np.zeros((0, problem.n_obj))

    # ------------------------------------------------------------------ checkpoint
    def state_dict(self) -> dict[str, Any]:
        """Everything needed to continue this run bit-identically (see module docstring)."""
        problem = self.problem
        inc = None
        if self._inc is not None:
            inc = {"x": self._inc[0].copy(), "f": self._inc[1].copy(), "cv": float(self._inc[2])}
        return {
            "format": STATE_FORMAT,
            "version": STATE_VERSION,
            "kind": self.kind,
            "params": self.params,
            "problem": {"n_var": problem.n_var, "n_obj": problem.n_obj,
                        "n_constr": problem.n_constr},
            "generation": self._generation,
            "n_evals": self._n_evals,
            "rng": _copy_state(self._rng.bit_generator.state),
            "pending": None if self._pending is None else self._pending.copy(),
            "stop_reason": self._stop_reason,
            "incumbent": inc,
            "data": _copy_state(self._get_state()),
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore a state from ``state_dict()`` (or its ``to_jsonable`` form) after ``setup``.

        Raises:
            ValueError: if the state is malformed or belongs to another algorithm kind,
                other parameters, or a problem of other dimensions.
        """
        problem = self.problem
        state = from_jsonable(state)
        if not isinstance(state, dict) or state.get("format") != STATE_FORMAT:
            raise ValueError("state: not a legcore algorithm state")
        if state.get("version") != STATE_VERSION:
            raise ValueError(f"state: unsupported version {state.get('version')!r}")
        if state.get("kind") != self.kind:
            raise ValueError(f"state: belongs to {state.get('kind')!r}, not {self.kind!r}")
        saved, mine = _normalise_params(state["params"]), _normalise_params(self.params)
        for key in sorted(set(saved) | set(mine)):
            if saved.get(key) != mine.get(key):
                raise ValueError(f"state: parameter {key!r} differs "
                                 f"(saved {saved.get(key)!r}, here {mine.get(key)!r})")
        dims = state["problem"]
        for key in ("n_var", "n_obj", "n_constr"):
            if int(dims[key]) != getattr(problem, key):
                raise ValueError(f"state: problem {key} differs "
                                 f"(saved {dims[key]}, here {getattr(problem, key)})")
        self._rng = _rng_from_state(state["rng"])
        self._front_memo = None
        self._generation = int(state["generation"])
        self._n_evals = int(state["n_evals"])
        pending = state["pending"]
        self._pending = None if pending is None else np.asarray(pending, dtype=float).copy()
        self._stop_reason = state["stop_reason"]
        inc = state["incumbent"]
        self._inc = None if inc is None else (
            np.asarray(inc["x"], dtype=float).copy(),
            np.asarray(inc["f"], dtype=float).copy(),
            float(inc["cv"]),
        )
        self._set_state(state["data"])

    # ------------------------------------------------------------------ subclass hooks
    def default_termination(self) -> Any:
        """The termination used when ``minimize`` gets none (100 generations by default)."""
        from legcore.optimizers.termination import MaxGenerations

        return MaxGenerations(100)

    @abstractmethod
    def _setup(self) -> None:
        """Prepare for a new run on ``self.problem`` (no evaluation)."""

    @abstractmethod
    def _ask(self) -> np.ndarray:
        """Produce the next batch."""

    @abstractmethod
    def _tell(self, X: np.ndarray, F: np.ndarray, cv: np.ndarray) -> None:
        """Consume an evaluated batch (``cv`` = constraint violation per row)."""

    @abstractmethod
    def _get_state(self) -> dict[str, Any]:
        """The algorithm's own state (arrays and python scalars)."""

    @abstractmethod
    def _set_state(self, data: dict[str, Any]) -> None:
        """Inverse of ``_get_state``."""

    def _front(self) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    # ------------------------------------------------------------------ helpers
    def _update_incumbent(self, X: np.ndarray, F: np.ndarray, cv: np.ndarray) -> None:
        key = F.sum(axis=1)
        i = int(np.lexsort((key, cv))[0])
        if self._inc is None:
            better = True
        else:
            _, f0, cv0 = self._inc
            better = cv[i] < cv0 or (cv[i] == cv0 and key[i] < f0.sum())
        if better:
            self._inc = (X[i].copy(), F[i].copy(), float(cv[i]))

    def _initial_population(self, n: int) -> np.ndarray:
        """The first population: ``n`` random points (:meth:`_random_population`), the first
        of them replaced by the problem's ``initial_points`` (inside the box, on its grid)."""
        X = self._random_population(n)
        p = self.problem
        start = self._initial_points()
        if start is not None and n > 0:
            S = np.atleast_2d(np.asarray(start, dtype=float))[:n]
            X[: S.shape[0]] = p.snap(np.clip(S, p.xl, p.xu))
        return X

    def _initial_points(self) -> np.ndarray | None:
        """The problem's ``initial_points()`` (a duck-typed problem may have none)."""
        get = getattr(self.problem, "initial_points", None)
        return None if get is None else get()

    def _random_population(self, n: int) -> np.ndarray:
        """``n`` uniform random points in the box (on the grid for an integer-coded problem)."""
        p = self.problem
        if p.resolution is not None:
            k_lo, k_hi = p.gene_bounds()
            return self._rng.integers(k_lo, k_hi + 1, size=(n, p.n_var)) * p.resolution
        return p.xl + self._rng.random((n, p.n_var)) * (p.xu - p.xl)

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self._params.items())
        return f"{type(self).__name__}({args})"


def _copy_state(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.copy()
    if isinstance(obj, dict):
        return {k: _copy_state(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_copy_state(v) for v in obj]
    return obj
