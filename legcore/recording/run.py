"""One run (a RunResult) as a recording: optimisation series, fronts, baselines."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from legcore.recording.helpers import unique_parts
from legcore.recording.model import (
    BASELINE_SIGNALS,
    C_BASELINE,
    C_BEST,
    C_FRONT,
    DEFAULT_MAX_SAMPLES,
    FloatArray,
    FrontTrack,
    MeshRoots,
    MotionRecording,
    RunRecording,
    Series,
)
from legcore.recording.motion import record_motion
from legcore.recording.sampling import minmax_indices, shared_minmax_indices, stride_indices
from legcore.recording.size import (
    DEFAULT_MAX_BYTES,
    MIN_SAMPLES,
    _baselines_bytes,
    _front_bytes,
    _motion_bytes,
    estimate_bytes,
)

if TYPE_CHECKING:
    from legcore.robots.legged import LeggedRobot
    from legcore.robots.model import Robot
    from legcore.runner import RunResult
    from legcore.studies.study import Solution

# ---------------------------------------------------------------------------------------------
# one run
# ---------------------------------------------------------------------------------------------


def _objective_names(result: RunResult, m: int) -> tuple[str, ...]:
    names = tuple(getattr(result, "objective_names", ()) or ())
    if len(names) != m:
        names = tuple(f"f{i + 1}" for i in range(m))
    return names


def _history_arrays(history: Sequence[Mapping[str, Any]], key: str, m: int) -> FloatArray:
    rows = []
    for h in history:
        v = h.get(key)
        if v is None:
            rows.append([math.nan] * m)
        elif isinstance(v, list | tuple | np.ndarray):
            rows.append(
                [math.nan if x is None else float(x) for x in v][:m] + [math.nan] * (m - len(v))
            )
        else:
            rows.append([float(v)] + [math.nan] * (m - 1))
    return np.asarray(rows, dtype=float).reshape(len(history), m)


def _optimization_series(result: RunResult, max_samples: int) -> tuple[list[Series], int]:
    history = list(getattr(result, "history", []) or [])
    if not history:
        return [], 0
    first = history[0].get("best_f")
    m = len(first) if isinstance(first, list | tuple) else 1
    names = _objective_names(result, m)
    parts = unique_parts(names)
    gen = np.array([float(h.get("generation", i + 1)) for i, h in enumerate(history)])
    G = gen.shape[0]
    out: list[Series] = []

    def add(path: str, y: FloatArray, label: str) -> None:
        idx = minmax_indices(y, max_samples)
        out.append(Series(path, "generation", gen[idx], y[idx], label, "", G))

    def add_objectives(kind: str, Y: FloatArray) -> None:
        """One series per objective; several share their samples and one entity (``group``
        ``optimization/<kind>``, like the joints of a signal)."""
        if m == 1:
            add(f"optimization/{kind}/{parts[0]}", Y[:, 0], f"{kind} {names[0]}")
            return
        idx = shared_minmax_indices(Y, max_samples)
        for j, part in enumerate(parts):
            path, label = f"optimization/{kind}/{part}", f"{kind} {names[j]}"
            group = f"optimization/{kind}"
            out.append(Series(path, "generation", gen[idx], Y[idx, j], label, "", G, group))

    add_objectives("best", _history_arrays(history, "best_f", m))
    if m > 1:
        add_objectives("ideal", _history_arrays(history, "ideal", m))
        add_objectives("nadir", _history_arrays(history, "nadir", m))
    add(
        "optimization/front_size",
        np.array([float(h.get("front_size", 0) or 0) for h in history]),
        "front size",
    )
    cv = np.array([float(h.get("best_cv") or 0.0) for h in history])
    if np.any(cv != 0):
        add("optimization/constraint_violation", cv, "constraint violation of the best")
    return out, m


def _cap_front(F: FloatArray, cap: int) -> FloatArray:
    if F.shape[0] <= cap:
        return F
    order = np.lexsort(F.T[::-1])
    return F[order[stride_indices(F.shape[0], cap)]]


def _front_track(
    path: str,
    fronts: Sequence[tuple[int, FloatArray]],
    names: tuple[str, ...],
    source: str,
    cap: int,
    radius: float,
    color: tuple[int, int, int],
) -> FrontTrack | None:
    gens, pts, sizes = [], [], []
    for g, F in fronts:
        F = np.asarray(F, dtype=float)
        if F.ndim != 2 or F.shape[1] < 2:
            return None
        F = F[np.all(np.isfinite(F[:, :3]), axis=1), :3]
        gens.append(int(g))
        sizes.append(int(F.shape[0]))
        pts.append(_cap_front(F, cap))
    if not gens:
        return None
    return FrontTrack(
        path, np.asarray(gens, dtype=np.int64), pts, names[:3], source, sizes, radius, color
    )


def _front_scale(fronts: Sequence[tuple[int, FloatArray]]) -> float:
    allF = [np.asarray(F, dtype=float)[:, :3] for _, F in fronts if np.asarray(F).size]
    if not allF:
        return 1.0
    A = np.concatenate(allF)
    A = A[np.all(np.isfinite(A), axis=1)]
    if A.size == 0:
        return 1.0
    span = float(np.max(np.ptp(A, axis=0)))
    return span if span > 0 else max(1.0, float(np.max(np.abs(A))))


def record_run(
    result: RunResult,
    *,
    robot: Robot | LeggedRobot | None = None,
    fronts: Mapping[int, Any] | Sequence[tuple[int, Any]] | None = None,
    max_samples: int = DEFAULT_MAX_SAMPLES,
    max_front_points: int | None = None,
    max_bytes: int | None = DEFAULT_MAX_BYTES,
    mesh_roots: MeshRoots = (),
    baseline_signals: Sequence[str] | None = BASELINE_SIGNALS,
) -> RunRecording:
    """Everything to log for a finished job.

    ``robot``: the robot to draw (default: the job's robot, resolved from ``result.spec`` as
    the runner does, or the catalog robot named by the motion). ``fronts``: optional Pareto
    front per generation ``{generation: F (k, m)}`` (see the module docstring); default the
    final ``result.pareto`` at the last generation. ``max_samples`` caps every displayed signal
    and pose track, ``max_front_points`` (default ``max_samples``) each generation's front.

    Size budget: when the :func:`estimate_bytes` of the result exceeds ``max_bytes`` (None: no
    budget), the caps are lowered in proportion to the excess — the baselines' first, then the
    best motion's (never below ``MIN_SAMPLES``), then the front's (never below
    ``MIN_SAMPLES // 4`` points) — until it fits; ``properties`` and ``notes`` say so.

    ``mesh_roots``: the only directories a URDF ``<mesh filename=…>`` may be read from
    (``package://<pkg>/<rel>`` or a relative name, confined by :mod:`legcore.resource_paths`).
    The default, none, opens no file at all — what every robot submitted over the API gets
    (DESIGN §5); a mesh not read becomes a note and its link is drawn as a capsule.

    ``baseline_signals``: the signals kept for each baseline (``"q"``, ``"energy/total"``, any
    kind of :data:`SIGNALS`, ``"energy"``); default :data:`BASELINE_SIGNALS`, what the
    blueprint shows; None: all of them, like the best motion.
    """
    notes: list[str] = []
    if robot is None:
        robot = _resolve_robot(result, notes)
    optimization, m = _optimization_series(result, max_samples)
    initial = {
        "best": max_samples,
        "baselines": max_samples,
        "front": max_front_points or max_samples,
    }
    caps = dict(initial)
    best = _record_best(result, robot, caps["best"], mesh_roots)
    baselines = _record_baselines(result, robot, caps["baselines"], baseline_signals)
    front, best_point = _record_fronts(result, fronts, m, caps["front"], max_samples, notes)

    def assemble() -> RunRecording:
        return _assemble(
            result, robot, best, baselines, optimization, front, best_point, notes, max_samples
        )

    rec = assemble()
    floors = {"best": MIN_SAMPLES, "baselines": MIN_SAMPLES, "front": MIN_SAMPLES // 4}
    for key in ("baselines", "best", "front"):
        est = estimate_bytes(rec)
        if max_bytes is None or est <= max_bytes:
            break
        if key == "baselines":
            var = _baselines_bytes(list(baselines.values()))[1]
            used = max((s.n_samples for b in baselines.values() for s in b.series), default=0)
        elif key == "best":
            var = _motion_bytes(best)[1] if best is not None else 0
            used = max((s.n_samples for s in best.series), default=0) if best is not None else 0
        else:
            var = _front_bytes(front)[1]
            used = max((p.shape[0] for p in front.points), default=0) if front is not None else 0
        if var <= 0 or used <= floors[key]:
            continue
        ratio = max(0.0, (var - (est - max_bytes)) / var)
        new_cap = max(floors[key], int(used * ratio * 0.95))
        if new_cap >= used:
            continue
        caps[key] = new_cap
        if key == "baselines":
            baselines = _record_baselines(result, robot, new_cap, baseline_signals)
        elif key == "best":
            best = _record_best(result, robot, new_cap, mesh_roots)
        else:
            front, best_point = _record_fronts(result, fronts, m, new_cap, max_samples, [])
        rec = assemble()
    est = estimate_bytes(rec)
    if caps != initial:
        rec.notes.append(
            f"display caps lowered to {caps} samples to keep the recording under "
            f"{(max_bytes or 0) / 1e6:.0f} MB (estimated {est / 1e6:.1f} MB)"
        )
    if max_bytes is not None and est > max_bytes:
        rec.notes.append(
            f"estimated size {est / 1e6:.1f} MB is over the {max_bytes / 1e6:.0f} MB budget"
        )
    rec.properties.update(
        {
            "max_samples_best": caps["best"],
            "max_samples_baselines": caps["baselines"],
            "max_front_points": caps["front"],
            "estimated_bytes": est,
        }
    )
    return rec


def _record_best(
    result: RunResult, robot: Robot | LeggedRobot | None, cap: int, mesh_roots: MeshRoots = ()
) -> MotionRecording | None:
    best_sol: Solution | None = getattr(result, "best", None)
    if best_sol is None or best_sol.motion is None:
        return None
    return record_motion(best_sol.motion, robot, max_samples=cap, mesh_roots=mesh_roots)


def _record_baselines(
    result: RunResult,
    robot: Robot | LeggedRobot | None,
    cap: int,
    signals: Sequence[str] | None = BASELINE_SIGNALS,
) -> dict[str, MotionRecording]:
    out: dict[str, MotionRecording] = {}
    names = list((getattr(result, "baselines", None) or {}).keys())
    for name, part in zip(names, unique_parts(names), strict=True):
        sol = result.baselines[name]
        if sol is None or sol.motion is None:
            continue
        out[name] = record_motion(
            sol.motion,
            robot,
            name=name,
            signals_prefix=f"baselines/{part}/signals",
            world_prefix=f"world/baselines/{part}",
            max_samples=cap,
            animate=False,
            scene=False,
            path_color=C_BASELINE,
        )
        if signals is not None:
            prefix = f"baselines/{part}/signals/"
            out[name].series[:] = [
                s
                for s in out[name].series
                if any(
                    (rel := s.path[len(prefix) :]) == k or rel.startswith(k + "/") for k in signals
                )
            ]
    return out


def _record_fronts(
    result: RunResult,
    fronts: Mapping[int, Any] | Sequence[tuple[int, Any]] | None,
    m: int,
    cap: int,
    max_samples: int,
    notes: list[str],
) -> tuple[FrontTrack | None, FrontTrack | None]:
    pareto = list(getattr(result, "pareto", []) or [])
    if m == 0 and pareto:
        m = len(pareto[0].get("objectives", []))
    if m < 2:
        return None, None
    obj_names = _objective_names(result, m)
    history = list(getattr(result, "history", []) or [])
    last_gen = int(history[-1].get("generation", len(history))) if history else 0
    if fronts is not None:
        pairs = fronts.items() if isinstance(fronts, Mapping) else fronts
        items = sorted((int(g), np.asarray(F, dtype=float)) for g, F in pairs)
        source = "per_generation"
    else:
        F_final = np.array([p["objectives"] for p in pareto], dtype=float).reshape(-1, m)
        items = [(last_gen, F_final)] if F_final.size else []
        source = "final_only"
        notes.append(
            "per-generation fronts were not given: the final front is logged at the last generation"
        )
    scale = _front_scale(items)
    front = _front_track(
        "optimization/front", items, obj_names, source, cap, 0.006 * scale, C_FRONT
    )
    best_point = None
    if history:
        bf = _history_arrays(history, "best_f", m)
        gens = [int(h.get("generation", i + 1)) for i, h in enumerate(history)]
        sel = stride_indices(len(gens), max_samples)
        best_point = _front_track(
            "optimization/best_point",
            [(gens[i], bf[i : i + 1]) for i in sel],
            obj_names,
            "history",
            1,
            0.012 * scale,
            C_BEST,
        )
    return front, best_point


def _assemble(
    result: RunResult,
    robot: Robot | LeggedRobot | None,
    best: MotionRecording | None,
    baselines: dict[str, MotionRecording],
    optimization: list[Series],
    front: FrontTrack | None,
    best_point: FrontTrack | None,
    run_notes: list[str],
    max_samples: int,
) -> RunRecording:
    notes = list(run_notes)
    spec = getattr(result, "spec", None)
    kind = getattr(getattr(spec, "problem", None), "kind", "") if spec is not None else ""
    title = (
        (getattr(spec, "name", None) or kind or "legopt run") if spec is not None else "legopt run"
    )
    motion = getattr(getattr(result, "best", None), "motion", None)
    props: dict[str, Any] = {
        "study": kind,
        "robot": getattr(robot, "name", "")
        if robot is not None
        else (motion.robot if motion else ""),
        "seed": int(getattr(spec, "seed", 0) or 0) if spec is not None else 0,
        "optimizer": str((getattr(result, "optimizer", None) or {}).get("kind", "")),
        "objectives": ", ".join(getattr(result, "objective_names", ()) or ()),
        "status": str(getattr(result, "status", "")),
        "front_source": front.source if front is not None else "none",
        "max_samples": int(max_samples),
    }
    for mrec in ([best] if best else []) + list(baselines.values()):
        notes.extend(f"{mrec.name}: {n}" for n in mrec.notes)
    return RunRecording(title, best, dict(baselines), optimization, front, best_point, props, notes)


def _resolve_robot(result: RunResult, notes: list[str]) -> Robot | LeggedRobot | None:
    spec = getattr(result, "spec", None)
    if spec is not None:
        try:
            from legcore.runner import resolve_robot
            from legcore.studies.registry import get_study

            return resolve_robot(spec, get_study(spec.problem.kind))
        except Exception as exc:  # noqa: BLE001 - drawing falls back to the motion's robot name
            notes.append(f"robot of the spec not resolved ({type(exc).__name__}: {exc})")
    motion = getattr(getattr(result, "best", None), "motion", None)
    if motion is not None and motion.robot:
        from legcore.robots import catalog

        try:
            return catalog.get(motion.robot)
        except KeyError:
            notes.append(f"robot {motion.robot!r} is not in the catalog: not drawn")
    return None
