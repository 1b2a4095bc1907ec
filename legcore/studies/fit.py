"""One answer to "does study X fit robot R?" for every place that asks (DESIGN §5).

``legopt studies``, ``GET /studies``, ``legopt robots show``, the dashboard's robot page and
``POST /jobs`` all answer from :meth:`legcore.studies.study.Study.fit` — the function the
submission's ``Study.build`` calls — so a robot × study pair is accepted in a listing exactly
when a job with the default task is accepted:

    >>> from legcore.robots import catalog
    >>> from legcore.studies.fit import fit
    >>> fit(catalog.get("puma560"), "swing_energy").message
    'robot: swing_energy needs 2–6 actuated joints; robot puma560 has 6 …'  # doctest: +SKIP

:func:`fit` caches the default-task verdict per robot model and kind (robots are immutable; a
verdict costs one pre-flight check, up to a few hundred ms for an arm's path).
"""

from __future__ import annotations

import hashlib
import threading
from typing import Any

from legcore.studies.registry import get_study, studies
from legcore.studies.task import Fit

__all__ = ["fit", "fit_all"]

_CACHE: dict[tuple[str, str], Fit] = {}
_LOCK = threading.Lock()
_MAX = 512


def _robot_key(robot: Any) -> str:
    spec: Any = getattr(robot, "spec", None)
    dump = getattr(spec, "model_dump_json", None)
    text = dump() if callable(dump) else repr(spec)
    return hashlib.blake2b(f"{getattr(robot, 'name', '')}\0{text}".encode(),
                           digest_size=16).hexdigest()


def fit(robot: Any, kind: str) -> Fit:
    """Whether study ``kind`` fits ``robot`` with its default task (cached per robot model)."""
    key = (kind, _robot_key(robot))
    with _LOCK:
        hit = _CACHE.get(key)
    if hit is not None:
        return hit
    verdict = get_study(kind).fit(robot)
    with _LOCK:
        if len(_CACHE) >= _MAX:
            _CACHE.clear()
        _CACHE[key] = verdict
    return verdict


def fit_all(robot: Any) -> dict[str, Fit]:
    """The verdict of every study kind on ``robot``, by kind."""
    return {kind: fit(robot, kind) for kind in studies()}
