"""What the optimiser earned (issue 11): a result's start block is what was computed, and the
seed 000 deviation coding's optimum is credited to the coding, not to the GA."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from legcore.earned import change_pct, earned_summary
from legcore.runner import run


def test_change_pct_is_the_improvement_of_a_minimised_value() -> None:
    assert change_pct(2.0, 1.0) == pytest.approx(50.0)
    assert change_pct(-1.0, -3.0) == pytest.approx(200.0)  # a maximised score shown negated
    assert change_pct(0.0, 1.0) is None and change_pct(float("nan"), 1.0) is None


def test_earned_summary_names_what_the_search_added() -> None:
    s = earned_summary(
        ("f",), np.array([1.0]), 0.0, (np.array([4.0]), 0.0), ("zero", np.array([1.0]), 0.0)
    )
    row = s["objectives"][0]
    assert row["earned_pct"] == pytest.approx(75.0) and row["earned_over_free_pct"] == 0.0
    assert "nothing over zero" in s["verdict"]
    s = earned_summary(("f",), np.array([1.0]), 0.0, None, ("zero", np.array([2.0]), 0.5))
    assert "violates the constraints" in s["verdict"]


def _spec(path: str, generations: int) -> dict:
    with open(path) as fh:
        spec = yaml.safe_load(fh)
    spec["budget"] = {"generations": generations}
    return spec


def test_seed_000_result_reports_its_start_and_the_free_coordinated_motion() -> None:
    """The start block is computed, not claimed: the initial best is generation 1's best, the
    free solution is the all-zero genes' score, and the shipped optimum is no better than it."""
    result = run(_spec("examples/000_swing_energy_flat.yaml", 3))
    doc = result.to_dict()
    st = doc["start"]
    row = st["objectives"][0]
    assert row["initial"] == pytest.approx(doc["history"][0]["best_f"][0])
    assert row["optimum"] == pytest.approx(doc["history"][-1]["best_f"][0])
    assert row["free"] == pytest.approx(-9.680989539, abs=1e-6)  # the coordinated motion
    assert row["optimum"] >= row["free"] - 1e-9  # the GA never beats what the coding gives free
    assert st["free"]["what"].startswith("the coordinated motion")


def test_literal_coding_has_no_free_start() -> None:
    spec = _spec("examples/000_swing_energy_flat.yaml", 2)
    spec["problem"]["encoding"] = "absolute"
    st = run(spec).to_dict()["start"]
    assert st["free"] is None and "over the initial population" in st["verdict"]


def test_readme_headline_of_seed_000_matches_a_fresh_run() -> None:
    """The README's demo block prints seed 000's start → optimum; a fresh run of the shipped
    example (seed 1, the full budget) must give those numbers (4 significant digits), and the
    optimiser-earned line must say the optimum is the coding's free solution."""
    import re
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    score = re.search(r"\(paper: F\)\s+([\d.]+) → ([\d.]+)", readme)
    energy = re.search(r"\(paper: E_T\)\s+([\d.]+) → ([\d.]+)", readme)
    assert score and energy, "README: the demo block of seed 000 is missing"
    with open("examples/000_swing_energy_flat.yaml") as fh:
        doc = run(yaml.safe_load(fh)).to_dict()
    best, parabolic = doc["best"]["metrics"], doc["baselines"]["calderon2008_parabolic"]["metrics"]
    assert float(score.group(1)) == pytest.approx(parabolic["score"], rel=1e-3)
    assert float(score.group(2)) == pytest.approx(best["score"], rel=1e-3)
    assert float(energy.group(1)) == pytest.approx(parabolic["energy_total"], rel=1e-3)
    assert float(energy.group(2)) == pytest.approx(best["energy_total"], rel=1e-3)
    assert "the optimum is that solution" in readme
    row = doc["start"]["objectives"][0]
    assert row["free"] == pytest.approx(row["optimum"], abs=1e-9)
