"""Per-request memo of job spec validation, so a sweep costs O(size of the request).

A sweep of N points over a base of size S used to cost O(N × S): every point deep-copied the
base, rebuilt its inline robot (a 1.7 MB URDF: ~1 s each, twice per point), re-validated the
whole spec and serialized it to compute a cache key. With copy-on-write expansion
(``services.api.sweeps.with_overrides``) the points share every untouched subtree with the base
by identity; this module keys those subtrees by content without re-reading them:

- ``content_key(value, memo)``: a Merkle digest of a JSON value, memoized by object identity, so
  a shared subtree (the robot, a 1 MB path CSV) is digested once per request and a point costs
  only the containers its overrides copied;
- ``SpecCache``: what ``services.api.validation.check_job_spec`` remembers per key: built robots
  (one build per distinct robot document), validated sub-models (``problem``, ``optimizer``:
  pydantic does not re-validate a model instance, so later points validate only their top-level
  fields), built study problems per (robot, problem), job sizes per (robot, problem, optimizer,
  budget), and failures of each of these, so N points sharing a bad part fail N times for the
  price of one.

``problem_builder`` hands ``legcore.runner.prepare`` the study problems a request built
already (its ``build_problem``). Validation is also bounded: the builds of one request may
parse at most ``MAX_BUILD_CHARS`` characters of URDF / path CSV text (a few CPU seconds).

A ``SpecCache`` lives in the ``cache`` mapping the caller passes to ``check_job_spec`` (one per
request); nothing here outlives the request or is shared between API keys.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, MutableMapping
from dataclasses import dataclass, field
from typing import Any

from legcore.robots import LeggedRobot, Robot, build_any_robot
from legcore.runner import JobSize
from legcore.studies.study import Study, StudyProblem
from services.api.errors import invalid
from services.lru import BuiltCache

#: Strings longer than this are digested instead of quoted in a key (characters).
_INLINE_STRING = 64

#: Robot and study-problem builds one request may cause, in characters of the URDF / path CSV
#: text they parse (plus ``BUILD_OVERHEAD_CHARS`` each). Building costs ~0.6 µs per character
#: (a 1.7 MB URDF: ~1 s), so this bounds a request's validation at a few CPU seconds: a sweep
#: may vary the parameters of a large inline robot or path in a few jobs only. One job never
#: reaches it (a URDF has at most 2,000,000 characters, a CSV 1,000,000).
MAX_BUILD_CHARS = 8_000_000
BUILD_OVERHEAD_CHARS = 1_000

Errors = list[dict[str, Any]]


def _digest(text: str) -> str:
    return hashlib.blake2b(text.encode("utf-8", "surrogatepass"), digest_size=16).hexdigest()


def content_key(value: Any, memo: dict[int, tuple[Any, str]]) -> str:
    """A digest of the JSON value ``value`` (equal iff equal as JSON, object key order aside).

    Containers and strings are memoized in ``memo`` by identity (the memo keeps them alive, so
    an id is never reused while it is in there): a subtree shared by many documents is read once.
    """
    if not isinstance(value, dict | list | str):
        return json.dumps(value, default=repr)  # null, true, 1 and 1.0 stay distinct
    hit = memo.get(id(value))
    if hit is not None and hit[0] is value:
        return hit[1]
    if isinstance(value, dict):
        items = sorted((str(k), content_key(v, memo)) for k, v in value.items())
        key = "d" + _digest(json.dumps(items))
    elif isinstance(value, list):
        key = "l" + _digest(json.dumps([content_key(v, memo) for v in value]))
    elif len(value) > _INLINE_STRING:
        key = "s" + _digest(value)
    else:
        key = json.dumps(value)
    memo[id(value)] = (value, key)
    return key


@dataclass(frozen=True)
class BuiltRobot:
    """An inline robot spec validated and built once: the document to store and the model."""

    document: dict[str, Any]
    robot: Robot | LeggedRobot


@dataclass
class SpecCache:
    """What validating one request's job specs remembers (see the module docstring)."""

    memo: dict[int, tuple[Any, str]] = field(default_factory=dict)
    lookups: dict[str, Any] = field(default_factory=dict)
    robots: dict[str, BuiltRobot | Errors] = field(default_factory=dict)
    models: dict[tuple[str, str], Any] = field(default_factory=dict)
    failures: dict[tuple[str, str], Errors] = field(default_factory=dict)
    problems: dict[tuple[str, str], Any] = field(default_factory=dict)
    sizes: dict[tuple[str, ...], tuple[int, JobSize, dict[str, Any]] | Errors] = field(
        default_factory=dict
    )
    stats: dict[str, int] = field(default_factory=dict)

    def charge(self, text_chars: int, loc: tuple[str | int, ...]) -> None:
        """Count one robot or study-problem build (its URDF / CSV text plus a fixed overhead)
        against ``MAX_BUILD_CHARS``; a 422 at ``loc`` once the request has spent it."""
        spent = self.stats.get("build_chars", 0) + text_chars + BUILD_OVERHEAD_CHARS
        if spent > MAX_BUILD_CHARS:
            raise invalid(
                loc,
                f"this request builds too many distinct robots or paths: more than "
                f"{MAX_BUILD_CHARS} characters of URDF/CSV text in all (a build costs its text "
                f"plus {BUILD_OVERHEAD_CHARS}); sweep fewer variants of a large inline robot or "
                "path, or split the sweep",
                "too_much_work",
            )
        self.stats["build_chars"] = spent

    def key(self, value: Any) -> str:
        """``content_key`` of ``value`` with this request's memo."""
        return content_key(value, self.memo)

    def count(self, what: str) -> None:
        """Count an expensive step (robot builds, prepares) for tests and logs."""
        self.stats[what] = self.stats.get(what, 0) + 1

    def memo_lookup(
        self, lookup: Callable[[str], str | dict[str, Any] | None]
    ) -> Callable[[str], str | dict[str, Any] | None]:
        """``lookup`` answering each reference once per request (the same document object
        each time, so its content key is computed once)."""

        def cached(reference: str) -> str | dict[str, Any] | None:
            if reference not in self.lookups:
                self.lookups[reference] = lookup(reference)
            found: str | dict[str, Any] | None = self.lookups[reference]
            return found

        return cached

    @classmethod
    def attach(cls, cache: MutableMapping[str, Any], scope: str) -> SpecCache:
        """The ``SpecCache`` stored in the caller's ``cache`` mapping for ``scope`` (the error
        location prefix: cached errors are located under it), created on first use."""
        name = f"spec-cache:{scope}"
        found = cache.get(name)
        if not isinstance(found, SpecCache):
            found = cache[name] = cls()
        return found


def problem_builder(
    problems: dict[tuple[str, str], Any], problem_key: tuple[str, str]
) -> Callable[[Study, Robot | LeggedRobot, Any], StudyProblem]:
    """``build_problem`` for ``legcore.runner.prepare``: the study problem of ``problem_key``
    from ``problems`` when this request built it already, else built and kept there."""

    def build(study: Study, robot: Robot | LeggedRobot, problem_spec: Any) -> StudyProblem:
        found = problems.get(problem_key)
        if found is None:
            found = problems[problem_key] = study.build(robot, problem_spec)
        return found

    return build


#: Robots ``build_robot_cached`` keeps (a 1.7 MB URDF model is a few MB in memory).
_robots: BuiltCache[Robot | LeggedRobot] = BuiltCache(8)


def build_robot_cached(spec: dict[str, Any]) -> Robot | LeggedRobot:
    """``legcore.robots.build_any_robot(spec)`` for a stored inline robot document, shared by the
    requests of this process: the last few distinct documents (by content) stay built, so
    reading a stored 1.7 MB URDF robot costs a digest (~5 ms), not a build (~0.5 s).
    Robots are never modified after they are built, so sharing them is safe."""
    return _robots.get_or_build(content_key(spec, {}), lambda: build_any_robot(spec))


def robot_kind(robot: Robot | LeggedRobot) -> str:
    """``"legged"`` or ``"serial"`` (what a study's ``robot_kinds`` lists)."""
    return "legged" if isinstance(robot, LeggedRobot) else "serial"


__all__ = [
    "BUILD_OVERHEAD_CHARS",
    "MAX_BUILD_CHARS",
    "BuiltRobot",
    "SpecCache",
    "build_robot_cached",
    "content_key",
    "problem_builder",
    "robot_kind",
]
