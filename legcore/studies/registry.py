"""The study kinds, by name: ``get_study("swing_energy")`` → a :class:`Study` descriptor.

Two sources:

- the built-in kinds (:data:`STUDY_MODULES`, one package per task, ``legcore/studies/<kind>/``,
  each defining ``STUDY``);
- **plug-ins**: any installed distribution that declares an entry point in the group
  ``legopt.studies`` (:data:`ENTRY_POINT_GROUP`), whose value is a :class:`Study` object or a
  module defining ``STUDY``::

      # the lab's pyproject.toml
      [project.entry-points."legopt.studies"]
      bending_fatigue = "mylab_studies.bending:STUDY"

  The entry point's name must equal ``STUDY.kind``; a plug-in may not replace a built-in kind.
  A plug-in that fails to load is left out and its error kept in :func:`plugin_errors` (so the
  API and the workers still start); see docs/plugins.md.

Every :class:`Study`'s ``build`` checks the robot's capabilities first
(:meth:`Study.refusal`): a robot the study cannot use is refused with
``ValueError("robot: <kind> needs …")`` before the study's own code runs.
"""

from __future__ import annotations

import dataclasses
import importlib
import importlib.metadata
import logging
import types
from functools import cache
from typing import Any

from legcore.studies.study import Study, StudyParams

__all__ = [
    "ENTRY_POINT_GROUP",
    "STUDY_MODULES",
    "get_study",
    "needs_text",
    "plugin_errors",
    "studies",
]

log = logging.getLogger("legcore.studies")

#: kind -> module defining ``STUDY`` (DESIGN.md §2 "Problems").
STUDY_MODULES: dict[str, str] = {
    "swing_energy": "legcore.studies.swing_energy",
    "path_placement": "legcore.studies.path_placement",
    "hexapod_workspace": "legcore.studies.hexapod_workspace",
    "quadruped_gait": "legcore.studies.quadruped_gait",
    "path_tracking": "legcore.studies.path_tracking",
}

#: The entry-point group a package registers its study kinds in.
ENTRY_POINT_GROUP = "legopt.studies"

_plugin_errors: dict[str, str] = {}


def _validate(study: Any, name: str, where: str) -> Study:
    if not isinstance(study, Study):
        raise TypeError(f"{where}: expected a legcore Study, got {type(study).__name__}")
    if study.kind != name:
        raise ValueError(f"{where}: STUDY.kind is {study.kind!r}, expected {name!r}")
    if not (isinstance(study.params, type) and issubclass(study.params, StudyParams)):
        raise TypeError(f"{where}: params must be a StudyParams subclass")
    kind_field = study.params.model_fields.get("kind")
    if kind_field is None or kind_field.default != name:
        raise ValueError(f"{where}: params.kind must be Literal[{name!r}] with that default")
    return study


def _plugins(builtin: set[str]) -> dict[str, Study]:
    """The study kinds of installed plug-ins (entry-point group ``legopt.studies``)."""
    out: dict[str, Study] = {}
    for ep in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP):
        dist = ep.dist.name if ep.dist is not None else "?"
        where = f"plug-in {ep.name!r} ({dist}: {ep.value})"
        try:
            if ep.name in builtin or ep.name in out:
                raise ValueError(f"{where}: the study kind {ep.name!r} is already registered")
            obj = ep.load()
            if isinstance(obj, types.ModuleType):
                obj = obj.STUDY
            study = _validate(obj, ep.name, where)
        except Exception as exc:  # a broken plug-in must not stop the service
            _plugin_errors[ep.name] = f"{type(exc).__name__}: {exc}"
            log.warning("study plug-in not loaded: %s", _plugin_errors[ep.name])
            continue
        out[ep.name] = dataclasses.replace(study, plugin=dist)
    return out


@cache
def studies() -> dict[str, Study]:
    """All study descriptors, keyed by kind: the built-in ones, then the plug-ins' (modules
    are imported on first call; the result is fixed for the life of the process)."""
    out: dict[str, Study] = {}
    for kind, module in STUDY_MODULES.items():
        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError as exc:  # a study still being written (development only)
            if exc.name != module:
                raise
            continue
        out[kind] = _validate(mod.STUDY, kind, module)
    out.update(_plugins(set(STUDY_MODULES)))
    return out


def plugin_errors() -> dict[str, str]:
    """Entry points of the group that could not be loaded: name -> error message."""
    studies()
    return dict(_plugin_errors)


def get_study(kind: str) -> Study:
    """The study descriptor of ``kind``; ``ValueError`` naming the known kinds otherwise."""
    known = studies()
    if kind not in known:
        raise ValueError(f"kind: unknown study {kind!r}; expected one of {sorted(known)}")
    return known[kind]


def _span(lo: int | None, hi: int | None) -> str:
    if lo is not None and hi is not None:
        return f"{lo}" if lo == hi else f"{lo}–{hi}"
    return f"≥ {lo}" if lo is not None else f"≤ {hi}"


def needs_text(study: Study) -> list[str]:
    """What ``study`` needs from a robot, in words: one line per alternative (empty: any robot
    of its kinds), e.g. ``"a legged robot: 4 legs, each of 2–3 joints; revolute joints only"``."""
    out = []
    for n in study.needs:
        parts = []
        if n.serial:
            joints = (f" of {_span(n.min_joints, n.max_joints)} actuated joints"
                      if n.min_joints is not None or n.max_joints is not None else "")
            parts.append(f"a serial chain{joints}")
        if n.legged:
            legs = ("" if n.n_legs is None
                    else " or ".join(str(k) for k in n.n_legs) + " legs")
            each = ("" if n.leg_joints is None
                    else f"each of {_span(*n.leg_joints)} joints")
            detail = ", ".join(x for x in (legs, each) if x)
            parts.append("a legged robot" + (f": {detail}" if detail else ""))
        if n.electrical:
            parts.append("motor data (Kt, Ke, R) on every joint")
        if n.torque_limits:
            parts.append("a torque limit on every joint")
        if n.revolute:
            parts.append("revolute joints only")
        out.append("; ".join(parts))
    return out
