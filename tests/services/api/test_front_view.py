"""The reported optimum's place on the front (issue 24: facts stored once): the worker's stored
index wins; None stored means the optimum is not on the front; only results stored before the
worker kept it fall back to the nearest point."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from services.api.front_view import reported_optimum_index


def _points(*objectives: list[float]) -> list[Any]:
    return [SimpleNamespace(index=i, objectives=f, x=[0.0]) for i, f in enumerate(objectives)]


def _result(summary: dict[str, Any], values: dict[str, float]) -> Any:
    return SimpleNamespace(summary=summary, objectives={"names": list(values), "values": values})


POINTS = _points([1.0, 5.0], [2.0, 3.0], [4.0, 1.0])
NAMES = ["a", "b"]


def test_the_stored_index_wins_over_the_nearest_point() -> None:
    result = _result({"best_index": 2}, {"a": 1.0, "b": 5.0})  # nearest would be point 0
    assert reported_optimum_index(result, POINTS, NAMES) == 2  # type: ignore[arg-type]


def test_an_optimum_off_the_front_has_no_index() -> None:
    result = _result({"best_index": None}, {"a": 1.0, "b": 5.0})
    assert reported_optimum_index(result, POINTS, NAMES) is None  # type: ignore[arg-type]
    stale = _result({"best_index": 7}, {"a": 1.0, "b": 5.0})  # not a point of this front
    assert reported_optimum_index(stale, POINTS, NAMES) is None  # type: ignore[arg-type]


def test_an_older_result_falls_back_to_the_nearest_point() -> None:
    result = _result({}, {"a": 2.1, "b": 2.9})
    assert reported_optimum_index(result, POINTS, NAMES) == 1  # type: ignore[arg-type]
    assert reported_optimum_index(None, POINTS, NAMES) is None
