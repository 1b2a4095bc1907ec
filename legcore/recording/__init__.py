"""A run → the plain time series its Rerun recording shows (pure: numpy only, no Rerun here).

:func:`record_run` turns a :class:`~legcore.runner.RunResult` (and :func:`record_motion` a single
:class:`~legcore.studies.study.Motion`) into a :class:`RunRecording`: a flat list of items, each
with its entity path, its timeline and its numbers. ``services.recording.writer`` — the only
module that imports Rerun — logs them one archetype per item; nothing here knows about Rerun.

Entity paths (``docs/recording.md`` has the full table). Items are named per joint, frame and
link here; ``services.recording.writer`` logs several of them as one entity:

- ``signals/<q|qd|qdd|jerk|tau|power>/<joint>`` — one scalar series per joint on the ``time``
  timeline (s); ``signals/energy/<joint>`` the cumulative ``∫|P_i| dt`` of that joint (J) and
  ``signals/energy/total`` the motion's own cumulative energy (``Motion.energy``). The joints
  of one signal share their samples and are logged as one entity, ``signals/<kind>``
  (``Series.group``).
- ``world/robot[/<leg>]/frames/<k>`` — link frame ``k`` (0 = base) in the world over time
  (``legcore.kinematics.frames``, one batched call for all displayed samples);
  ``.../frames/<k>/link`` — the link drawn as a capsule from frame origin ``k-1`` to frame
  origin ``k``, posed relative to frame ``k`` (static there for DH chains), and
  ``.../frames/<n>/tool_link`` from the last frame's origin to the tool point when they differ;
  ``world/robot/body`` the body box of a legged robot. A robot drawn without meshes is logged
  as **one entity** ``world/robot/links``: per sample 3 arrows (x / y / z) per drawn frame —
  every frame of a serial robot, a legged robot's joint frames between each leg's base and
  foot frame —, the capsules and the body box posed in the world. A URDF robot with meshes
  keeps one entity per frame and link.
- ``world/robot/tool`` the moving tool point (serial robots); ``world/path`` the motion's
  tool/foot path (``Motion.tool``); ``world/robot/<leg>/foot_path`` each leg's foot path
  (legged), logged in the ``world/path`` entity (labelled ``path``, ``L1``, …). A pose that
  does not change over the motion is logged once, static.
- ``world/scene/<targets|obstacles|support_polygon|...>`` from ``Motion.scene``.
- ``baselines/<name>/signals/...`` the signals of each baseline — by default only ``q`` and
  ``energy/total`` (:data:`BASELINE_SIGNALS`; ``record_run(baseline_signals=None)`` keeps all)
  —, logged as one entity per signal for all baselines, ``baselines/signals/<kind>``, when they
  share their samples; ``world/baselines/<name>/path`` each baseline's path, logged together
  as ``world/baselines/paths``.
- ``optimization/best/<objective>`` (best objective per generation), ``optimization/front_size``,
  ``optimization/ideal|nadir/<objective>``, ``optimization/constraint_violation`` on the
  ``generation`` timeline (the objectives of best / ideal / nadir: one entity each,
  ``optimization/best`` …, when there are several); ``optimization/front`` the Pareto front
  (points in objective space) per generation and ``optimization/best_point`` the history's best
  (knee) point.

Downsampling (display only; the stored result keeps every sample). A motion of ``K`` samples is
shown with at most ``max_samples`` (default 2000) of them:

- scalar signals use **min/max decimation**: the interior samples are cut into
  ``(max_samples - 2) // 2`` equal buckets and each bucket keeps the samples of its minimum and
  maximum, plus the first and last sample — so peaks (τ_max, jerk spikes) survive; every kept
  value is an original sample at its original time; the joints of one signal keep the union
  of their samples (:func:`shared_minmax_indices`, still at most ``max_samples``);
- poses, the moving tool point, the path and time-varying scene items use a **uniform stride**:
  ``round(linspace(0, K-1, max_samples))``, endpoints included.

Every series records ``source_samples`` (``K``) and ``n_samples`` (what is logged), so the
counts are exact and known. The Pareto front per generation is capped the same way (points
sorted by the first objective, uniform stride) at ``max_front_points``. Size budget: a run's
estimated file size (:func:`estimate_bytes`, constants measured on rerun-sdk 0.41 files) is
kept under ``max_bytes`` (16 MB by default) by lowering the caps in proportion to the excess —
baselines first, then the best motion (never below ``MIN_SAMPLES``), then the front — and
``RunRecording.properties`` records the caps used.

Fronts per generation: a :class:`~legcore.runner.RunResult` carries only the final front
(``pareto``) and a per-generation summary (``history``: best, ideal, nadir, front size). Pass
``fronts={generation: F (k, m)}`` (e.g. collected from each ``Progress.front_F`` in the run's
callback) to log the front of every generation; without it the final front is logged once, at
the last generation, and ``FrontTrack.source`` says ``"final_only"``.
"""

from __future__ import annotations

from legcore.recording.helpers import (
    entity_part,
    link_radius,
    quaternion_xyzw,
    unique_parts,
)
from legcore.recording.model import (
    BASELINE_SIGNALS,
    DEFAULT_MAX_SAMPLES,
    MAX_MESH_BYTES,
    MESH_SUFFIXES,
    SIGNALS,
    BoxSet,
    FrontTrack,
    MeshRoots,
    MotionRecording,
    PointSet,
    PointTrack,
    Polyline,
    PolylineTrack,
    PoseTrack,
    RunRecording,
    Series,
)
from legcore.recording.motion import (
    record_motion,
)
from legcore.recording.run import (
    record_run,
)
from legcore.recording.sampling import (
    minmax_columns,
    minmax_indices,
    shared_minmax_indices,
    stride_indices,
)
from legcore.recording.size import (
    DEFAULT_MAX_BYTES,
    MIN_SAMPLES,
    estimate_bytes,
)

__all__ = [
    "MeshRoots",
    "BASELINE_SIGNALS",
    "DEFAULT_MAX_BYTES",
    "DEFAULT_MAX_SAMPLES",
    "MAX_MESH_BYTES",
    "MESH_SUFFIXES",
    "MIN_SAMPLES",
    "SIGNALS",
    "BoxSet",
    "FrontTrack",
    "MotionRecording",
    "PointSet",
    "PointTrack",
    "Polyline",
    "PolylineTrack",
    "PoseTrack",
    "RunRecording",
    "Series",
    "entity_part",
    "estimate_bytes",
    "link_radius",
    "minmax_columns",
    "minmax_indices",
    "quaternion_xyzw",
    "record_motion",
    "record_run",
    "shared_minmax_indices",
    "stride_indices",
    "unique_parts",
]
