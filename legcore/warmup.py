"""Compile every numba kernel once, ahead of the first job (issue 12, warm starts).

    python -m legcore.warmup            # e.g. in the image build, with NUMBA_CACHE_DIR set

Runs one small job of every built-in study kind (its default robot and settings, a population
of 8 for 2 generations — the first and a steady-state one: MOEA/D's replacement, for one,
runs from the second on —, seed 000's baseline GAs for 1 generation) through the whole
``legcore.run`` — evaluation, IK of the baselines and placements, decoding — so that every
``@numba.njit(cache=True)`` kernel is compiled with the signatures the jobs use and written to
numba's cache (``NUMBA_CACHE_DIR`` when set, else ``__pycache__`` next to the package). A later
process loads them instead of compiling. Then ``numeric_ik``: the numerical IK that arms without
a closed form use (URDF arms, 7-DOF; none of the study kinds' default robots needs it), whose
kernels take the longest to compile (~2 min on the 2-core development machine). Prints one line
per kind and the total time.
"""

from __future__ import annotations

import sys
import time
from typing import Any

__all__ = ["compiled_during", "warm_up", "warmup_spec"]

#: Per-kind parameters that keep the warm-up job small.
_SMALL: dict[str, dict[str, Any]] = {
    "swing_energy": {"baseline_generations": 1, "baseline_pop_size": 8},
}


def warmup_spec(kind: str, study: Any) -> dict[str, Any]:
    """A tiny job of ``kind``: its default optimiser with population 8 (MOEA/D: as many
    subproblems as neighbours), two generations (MOEA/D's replacement and the GA's elitism
    run from the second on)."""
    params = dict(study.default_optimizer["params"])
    for name in ("pop_size", "n_samples", "n_subproblems"):
        if name in params:
            params[name] = max(8, int(params.get("n_neighbors", 0)))
    return {
        "problem": {"kind": kind, **_SMALL.get(kind, {})},
        "optimizer": {"kind": study.default_optimizer["kind"], "params": params},
        "budget": {"generations": 2},
        "seed": 0,
    }


def warm_numeric_ik() -> None:
    """The numerical IK (its kernels are the same for every robot) on the catalog PUMA 560 with
    its closed form bypassed: pose, tool-axis and position tasks, along a path and per sample
    (8 targets each)."""
    import numpy as np

    from legcore.ik import solve
    from legcore.kinematics import fk
    from legcore.robots import Robot, catalog

    arm = catalog.get("puma560")
    assert isinstance(arm, Robot)
    q = np.array([0.2, 0.5, -2.0, 0.3, 0.8, 0.2]) + 0.1 * np.linspace(0.0, 1.0, 8)[:, None]
    T = fk(arm, q)
    targets = {"pose": T, "axis": np.concatenate([T[:, :3, 3], T[:, :3, 2]], axis=1),
               "position": T[:, :3, 3]}  # fmt: skip
    for task, target in targets.items():
        for path in (True, False):
            solve(arm, target, task, q0=q[0], path=path, method="numeric")


#: Warm-ups beside the study kinds (name -> function), run after them by default.
_EXTRA = {"numeric_ik": warm_numeric_ik}


def warm_up(
    kinds: list[str] | None = None, *, extras: bool = False, verbose: bool = True
) -> dict[str, float]:
    """Run the warm-up job of each kind (default: every built-in kind, then with ``extras`` the
    ``numeric_ik`` warm-up — the command line's default; a worker at start leaves it out: with
    a cold cache it would hold the worker ~2 min); seconds per kind.

    A kind whose job fails is reported (``nan``) and skipped: warming up is best effort.
    """
    from legcore.runner import run
    from legcore.studies.registry import STUDY_MODULES, studies

    found = studies()
    chosen = kinds if kinds is not None else [k for k in found if k in STUDY_MODULES]
    if kinds is None and extras:
        chosen = [*chosen, *_EXTRA]
    out: dict[str, float] = {}
    for kind in chosen:
        t0 = time.perf_counter()
        try:
            if kind in _EXTRA:
                _EXTRA[kind]()
            else:  # the extras too: the API makes them on demand (their kernels with them)
                _ = run(warmup_spec(kind, found[kind])).extras
            out[kind] = time.perf_counter() - t0
        except Exception as exc:  # noqa: BLE001 - best effort, reported
            out[kind] = float("nan")
            if verbose:
                print(f"warmup: {kind}: failed: {type(exc).__name__}: {exc}", flush=True)
            continue
        if verbose:
            print(f"warmup: {kind}: {out[kind]:.1f} s", flush=True)
    return out


def compiled_during(work: Any) -> list[str]:
    """Run ``work()`` and return the kernels numba *compiled* meanwhile (``"name(args)"``);
    kernels loaded from numba's cache are not listed (its ``numba:compile`` event fires only
    on a cache miss). A process started after :func:`warm_up` lists none."""
    from numba.core import event

    compiled: list[str] = []

    class _Compiles(event.Listener):
        def on_start(self, ev: Any) -> None:
            d = ev.data or {}
            name = getattr(d.get("dispatcher"), "__qualname__", None) or str(d.get("dispatcher"))
            compiled.append(f"{name}{tuple(str(a) for a in d.get('args', ()))}")

        def on_end(self, ev: Any) -> None:
            pass

    listener = _Compiles()
    event.register("numba:compile", listener)
    try:
        work()
    finally:
        event.unregister("numba:compile", listener)
    return compiled


def main(argv: list[str]) -> int:
    """``python -m legcore.warmup [KIND ...] [--check]``: warm up (every kind and the
    numerical IK by default); ``--check``: then print the kernels that still had to be
    compiled (none, when the cache was warm) and exit 1 if any did."""
    check = "--check" in argv
    kinds = [a for a in argv if a != "--check"]
    t0 = time.perf_counter()
    if check:
        times: dict[str, float] = {}
        compiled = compiled_during(
            lambda: times.update(warm_up(kinds or None, extras=True, verbose=True))
        )
        print(f"warmup: {len(compiled)} kernels compiled" + "".join(f"\n  {c}" for c in compiled))
        return 1 if compiled or not all(t == t for t in times.values()) else 0
    times = warm_up(kinds or None, extras=True)
    print(f"warmup: {len(times)} kinds in {time.perf_counter() - t0:.1f} s", flush=True)
    return 0 if all(t == t for t in times.values()) else 1


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
