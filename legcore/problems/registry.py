"""The study kinds, by name: ``get_study("swing_energy")`` → a :class:`Study` descriptor."""

from __future__ import annotations

import importlib
from functools import cache

from legcore.problems.study import Study

__all__ = ["STUDY_MODULES", "get_study", "studies"]

#: kind -> module defining ``STUDY`` (DESIGN.md §2 "Problems", one per seed paper).
STUDY_MODULES: dict[str, str] = {
    "swing_energy": "legcore.problems.swing_energy",
    "path_placement": "legcore.problems.path_placement",
    "hexapod_workspace": "legcore.problems.hexapod_workspace",
    "quadruped_gait": "legcore.problems.quadruped_gait",
    "path_tracking": "legcore.problems.path_tracking",
}


@cache
def studies() -> dict[str, Study]:
    """All study descriptors, keyed by kind (modules are imported on first call)."""
    out: dict[str, Study] = {}
    for kind, module in STUDY_MODULES.items():
        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError as exc:  # a study still being written (development only)
            if exc.name != module:
                raise
            continue
        study: Study = mod.STUDY
        if study.kind != kind:
            raise RuntimeError(f"{module}: STUDY.kind is {study.kind!r}, expected {kind!r}")
        out[kind] = study
    return out


def get_study(kind: str) -> Study:
    """The study descriptor of ``kind``; ``ValueError`` naming the known kinds otherwise."""
    known = studies()
    if kind not in known:
        raise ValueError(f"kind: unknown study {kind!r}; expected one of {sorted(known)}")
    return known[kind]
