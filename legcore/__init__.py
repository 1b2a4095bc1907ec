"""LegOpt core: kinematics, dynamics, trajectories, problems and optimisers (pure library).

    >>> import legcore
    >>> result = legcore.run({"problem": {"kind": "swing_energy"}, "seed": 1})  # doctest: +SKIP

``legcore.run(spec) -> RunResult`` runs one job in-process; see :mod:`legcore.runner`.
"""

from __future__ import annotations

from typing import Any

from legcore.kernel_cache import check_kernel_cache

__all__ = ["run"]

check_kernel_cache()  # cached numba kernels of an older source are stale: drop them first


def __getattr__(name: str) -> Any:
    if name == "run":  # lazy: importing legcore stays cheap
        from legcore.runner import run

        return run
    raise AttributeError(f"module 'legcore' has no attribute {name!r}")
