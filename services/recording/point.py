"""One solution of a finished job, decoded again from its stored decision vector: the motion a
front point (or a baseline) stands for, as plot data and as a Rerun recording.

Decoding is deterministic: the job's stored spec builds the same problem as the worker did
(``legcore.runner.prepare``) and ``problem.solution(x)`` decodes ``x`` exactly as
``legcore.runner.finalize`` decoded the optimum, so a point's motion needs no storage until
someone asks for it. The recording is the job's recording with that solution as its motion:
the same baselines, the stored history and per-generation fronts, named after the point.

    decoded = decode_point(spec, x)                       # DecodedPoint(prepared, solution)
    motion_payload(decoded.solution.motion)               # JSON for the page's joint plot
    write_point_recording(decoded, path, pareto=..., history=..., fronts=..., title=...)
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from legcore.recording import SIGNALS, stride_indices
from legcore.runner import Prepared, RunResult, prepare
from legcore.studies.study import Motion, Solution
from services.lru import BuiltCache

__all__ = [
    "DecodedPoint",
    "PointError",
    "decode_baseline",
    "decode_point",
    "motion_payload",
    "prepare_cached",
    "write_point_recording",
]

#: Samples per signal in :func:`motion_payload` (the page's plot, not the recording).
PLOT_SAMPLES = 400


class PointError(ValueError):
    """A stored point that cannot be decoded with its job's spec (a message for the user)."""


@dataclass(frozen=True, eq=False)
class DecodedPoint:
    """A job's prepared problem and one solution decoded on it."""

    prepared: Prepared
    solution: Solution


_prepared: BuiltCache[Prepared] = BuiltCache(4)


def prepare_cached(spec: Any) -> Prepared:
    """``legcore.runner.prepare(spec)``, the last few distinct specs of this process kept
    built (building a problem can take seconds; decoding a point takes milliseconds). A
    prepared problem is not modified by decoding, so sharing it is safe."""
    return _prepared.get_or_build(
        json.dumps(spec, sort_keys=True, default=str), lambda: prepare(spec)
    )


def decode_point(spec: Any, x: Sequence[float]) -> DecodedPoint:
    """Decode the decision vector ``x`` with the problem of the job spec ``spec``.

    Raises :class:`PointError` when the spec cannot be prepared any more or ``x`` does not fit
    its problem (wrong length, non-finite values)."""
    try:
        prepared = prepare_cached(spec)
    except ValueError as exc:  # pydantic's ValidationError is a ValueError
        raise PointError(f"the job's spec cannot be prepared again: {exc}") from None
    vector = np.asarray(x, dtype=float).ravel()
    n_var = int(prepared.problem.n_var)
    if vector.shape != (n_var,):
        raise PointError(
            f"the stored point has {vector.size} decision variables, the job's problem "
            f"{n_var}: it cannot be decoded"
        )
    if not np.all(np.isfinite(vector)):
        raise PointError("the stored point has non-finite decision variables")
    try:
        solution = prepared.problem.solution(vector)
    except (ValueError, ArithmeticError) as exc:
        raise PointError(f"the point could not be decoded: {exc}") from None
    return DecodedPoint(prepared, solution)


def decode_baseline(spec: Any, name: str) -> DecodedPoint:
    """The baseline ``name`` of the job spec's problem (the paper's reference solution)."""
    try:
        prepared = prepare_cached(spec)
    except ValueError as exc:
        raise PointError(f"the job's spec cannot be prepared again: {exc}") from None
    baselines = prepared.problem.baseline_solutions()
    if name not in baselines:
        known = ", ".join(sorted(baselines)) or "none"
        raise PointError(f"no baseline {name!r} in this job (baselines: {known})")
    return DecodedPoint(prepared, baselines[name])


def _rows(a: np.ndarray, idx: np.ndarray) -> list[list[float | None]]:
    """Columns of ``a[idx]`` (K, n) as lists, non-finite values as None (strict JSON)."""
    sub = np.asarray(a, dtype=float)[idx]
    return [[float(v) if np.isfinite(v) else None for v in sub[:, j]] for j in range(sub.shape[1])]


def motion_payload(motion: Motion | None, max_samples: int = PLOT_SAMPLES) -> dict[str, Any]:
    """The joint signals of a motion for a plot: ``t`` (s), one entry per signal with its unit
    and one series per joint, the cumulative energy (J); at most ``max_samples`` samples
    (uniform stride, first and last kept). ``{"t": [], "signals": []}`` without a motion."""
    if motion is None:
        return {"t": [], "joint_names": [], "signals": [], "energy": None}
    idx = stride_indices(motion.n_samples, max_samples)
    signals = []
    for attr, unit, label in SIGNALS:
        a = getattr(motion, attr)
        if a is None:
            continue
        signals.append({"name": attr, "label": label, "unit": unit, "values": _rows(a, idx)})
    energy = None
    if motion.energy is not None:
        energy = [float(v) if np.isfinite(v) else None for v in motion.energy[idx]]
    return {
        "t": [float(v) for v in motion.t[idx]],
        "joint_names": list(motion.joint_names),
        "signals": signals,
        "energy": energy,
        "power_kind": motion.power_kind,
        "source_samples": motion.n_samples,
    }


def write_point_recording(
    decoded: DecodedPoint,
    path: Path,
    *,
    title: str,
    recording_id: str | None = None,
    pareto: Sequence[Mapping[str, Any]] = (),
    history: Sequence[Mapping[str, Any]] = (),
    fronts: Mapping[int, Any] | None = None,
) -> list[str]:
    """Write the recording of one decoded solution to ``path`` (``.rrd``): its motion, the
    job's baselines, ``history`` (the stored per-generation rows) and ``fronts`` (per-generation
    objective vectors) or the final front ``pareto`` (``[{x, objectives}]``); ``title`` names
    it. Returns the writer's notes (what it could not draw)."""
    from services.recording.writer import write_recording
    from services.store.settings import get_settings

    prepared = decoded.prepared
    problem = prepared.problem
    result = RunResult(
        spec=prepared.spec.model_copy(update={"name": title[:200]}),
        status="succeeded",
        best=decoded.solution,
        pareto=[dict(p) for p in pareto],
        baselines=problem.baseline_solutions(),
        history=[dict(h) for h in history],
        study_extras=dict,
        optimizer={},
        objective_names=tuple(problem.objective_names),
    )
    return write_recording(
        result, path, recording_id=recording_id, fronts=fronts,
        mesh_roots=get_settings().mesh_root_dirs,
    )  # fmt: skip
