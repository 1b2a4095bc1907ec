"""Optimisers behind one ask/tell interface, and the `minimize` driver.

``get_algorithm(kind, **params)`` builds one by name:

- ``"ga"``: seed 000's integer-coded genetic algorithm (`GA`);
- ``"hka"``: seed 001's Heuristic Kalman Algorithm (`HKA`);
- ``"moead"``: seed 002's MOEA/D with Tchebycheff decomposition (`MOEAD`);
- ``"nsga2"``: NSGA-II for comparison (`NSGA2`).

Parameters are validated when the algorithm is built: an unknown name or a bad value is a
``ValueError`` naming the parameter. See docs/optimizers.md.
"""

from __future__ import annotations

import inspect
from typing import Any

from legcore.optimizers.base import Algorithm, from_jsonable, make_rng, to_jsonable
from legcore.optimizers.callback import Callback, GenerationRecord, Progress
from legcore.optimizers.driver import Result, Run, minimize
from legcore.optimizers.ga import GA
from legcore.optimizers.hka import HKA
from legcore.optimizers.moead import MOEAD
from legcore.optimizers.nsga2 import NSGA2
from legcore.optimizers.termination import (
    AllOf,
    AnyOf,
    MaxEvaluations,
    MaxGenerations,
    MaxTime,
    Termination,
    Tolerance,
    termination_from_budget,
)

__all__ = [
    "ALGORITHMS",
    "get_algorithm",
    "algorithm_params",
    "Algorithm",
    "GA",
    "HKA",
    "MOEAD",
    "NSGA2",
    "minimize",
    "Run",
    "Result",
    "Progress",
    "GenerationRecord",
    "Callback",
    "Termination",
    "MaxGenerations",
    "MaxEvaluations",
    "MaxTime",
    "Tolerance",
    "AnyOf",
    "AllOf",
    "termination_from_budget",
    "to_jsonable",
    "from_jsonable",
    "make_rng",
]

ALGORITHMS: dict[str, type[Algorithm]] = {"ga": GA, "hka": HKA, "moead": MOEAD, "nsga2": NSGA2}


def algorithm_params(kind: str) -> dict[str, Any]:
    """The parameters of an algorithm kind with their defaults."""
    cls = _lookup(kind)
    sig = inspect.signature(cls.__init__)
    return {name: p.default for name, p in sig.parameters.items() if name != "self"}


def get_algorithm(kind: str, **params: Any) -> Algorithm:
    """Build an algorithm by kind (``"ga"``, ``"hka"``, ``"moead"``, ``"nsga2"``).

    Raises:
        ValueError: unknown kind, unknown parameter, or invalid value (naming the parameter).
    """
    cls = _lookup(kind)
    allowed = algorithm_params(kind)
    for name in params:
        if name not in allowed:
            raise ValueError(f"{name}: unknown parameter for {kind!r}; "
                             f"expected one of {sorted(allowed)}")
    return cls(**params)


def _lookup(kind: str) -> type[Algorithm]:
    try:
        return ALGORITHMS[kind]
    except (KeyError, TypeError):
        raise ValueError(f"kind: unknown algorithm {kind!r}; "
                         f"expected one of {sorted(ALGORITHMS)}") from None
