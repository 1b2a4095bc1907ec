"""The job spec and `legcore.run`: validation naming fields, budgets, determinism, JSON."""

from __future__ import annotations

import json

import pytest
from pydantic import ValidationError

import legcore
from legcore.jobspec import parse_job_spec
from legcore.runner import job_size, prepare
from legcore.studies.registry import studies

QUICK = {"problem": {"kind": "quadruped_gait"}, "budget": {"generations": 3}, "record": False}


def _locs(data: dict) -> list[str]:
    with pytest.raises(ValidationError) as info:
        parse_job_spec(data)
    return [".".join(str(p) for p in e["loc"]) + ": " + e["msg"] for e in info.value.errors()]


def test_every_study_kind_is_registered_with_the_seed_defaults() -> None:
    assert set(studies()) == {
        "swing_energy", "path_placement", "hexapod_workspace", "quadruped_gait", "path_tracking",
    }  # fmt: skip
    for kind, study in studies().items():
        spec = parse_job_spec({"problem": {"kind": kind}})
        assert spec.problem.kind == kind
        assert study.default_generations >= 1


def test_bad_specs_name_the_field() -> None:
    assert any(s.startswith("colour:") for s in _locs({**QUICK, "colour": 1}))
    assert any(s.startswith("problem:") for s in _locs({"problem": {"kind": "teleport"}}))
    assert any(
        s.startswith("budget.generations:") for s in _locs({**QUICK, "budget": {"generations": 0}})
    )
    bad_opt = {**QUICK, "optimizer": {"kind": "ga", "params": {"pop_size": 1}}}
    assert any(s.startswith("optimizer") and "pop_size" in s for s in _locs(bad_opt))
    with pytest.raises(ValueError, match="robot: unknown catalog robot 'r2d2'"):
        prepare({**QUICK, "robot": "r2d2"})
    with pytest.raises(ValueError, match="robot: quadruped_gait needs a legged robot"):
        prepare({**QUICK, "robot": "puma560"})


def test_same_seed_same_result_and_strict_json() -> None:
    a, b = legcore.run({**QUICK, "seed": 4}), legcore.run({**QUICK, "seed": 4})
    assert a.to_dict()["best"] == b.to_dict()["best"]
    doc = json.loads(json.dumps(a.to_dict(), allow_nan=False))
    assert {"spec", "status", "best", "pareto", "baselines", "history"} <= set(doc)
    assert len(doc["history"]) == 3


def test_budget_tolerance_stops_early_and_sizes_are_estimated() -> None:
    r = legcore.run({**QUICK, "budget": {"generations": 500, "ftol": 1e-9, "window": 5}})
    assert r.optimizer["n_gen"] < 500 and "1e-09" in r.optimizer["reason"]
    size = job_size(prepare({**QUICK, "budget": {"ftol": 1e-3}}))  # no limit: the seed's budget
    assert size.generations == studies()["quadruped_gait"].default_generations
    assert size.work == size.population * size.generations * size.samples


@pytest.mark.parametrize("optimizer", ["ga", "nsga2"])
def test_the_optimum_knows_its_place_on_the_front(optimizer: str) -> None:
    """``best_index`` is the front point that is the reported optimum (stored by the worker,
    so the dashboard never guesses it by distance)."""
    r = legcore.run({**QUICK, "optimizer": {"kind": optimizer}, "seed": 2})
    doc = r.to_dict()
    assert doc["best_index"] is not None
    assert doc["pareto"][doc["best_index"]]["x"] == pytest.approx(doc["best"]["x"])
