"""docs/studies.md's summary headlines against a fresh run (issue 11: no headline claims more
than was earned, and none drifts from what the code computes).

For every single-objective example whose headline is in the summary table of docs/studies.md,
the number is parsed from the doc text (never written twice), the shipped example is run with
``legcore.run`` at the seed the doc quotes, and the two must agree:

* a single-run number the doc quotes ("seed 1: 3.878 s") to the digits it prints (relative
  1e-3 for 4 significant digits, half a unit of the last digit for a rounded percentage);
* that fresh run must also lie inside the doc's 10-seed mean ± 3 sd (plus the rounding of the
  printed sd), so a stale 10-seed headline is caught too;
* a construction's value (the paper's law, the default step, the shortest foot path) to the
  digits printed.

The pattern is `tests/legcore/test_earned.py::test_readme_headline_of_seed_000_matches_a_fresh_run`
(regex on the text, ``legcore.run`` on the example, ``pytest.approx``). Runtime: the six shipped
examples at their full budgets, ≈ 15-20 s on an idle 2-core machine with warm numba caches.
"""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path
from typing import Any

import pytest
import yaml

from legcore.runner import run

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "studies.md"
NUM = r"(-?\d+(?:\.\d+)?)"  # a number as the doc prints it (after − → -)


def _summary_row(seed: str) -> str:
    """The summary table's row of ``seed`` ("000" … "004"), Unicode minus as ASCII."""
    text = DOC.read_text().replace("−", "-")
    table = text[: text.index("\n<a id=\"seed-000\"></a>")]
    rows = [ln for ln in table.splitlines() if ln.startswith(f"| {seed} |")]
    assert len(rows) == 1, f"docs/studies.md: no single summary row for seed {seed}"
    return rows[0]


class _Num(float):
    """A number parsed from the doc, remembering how many decimals it was printed with."""

    decimals: int

    def __new__(cls, text: str) -> _Num:
        obj = super().__new__(cls, float(text))
        obj.decimals = len(text.split(".")[1]) if "." in text else 0
        return obj

    @property
    def rounding(self) -> float:
        """Half a unit of the last printed digit."""
        return 0.5 * 10.0 ** -self.decimals


def _parse(pattern: str, row: str) -> tuple[_Num, ...]:
    m = re.search(pattern.replace("NUM", NUM), row)
    assert m, f"docs/studies.md summary: {pattern!r} not found in {row[:120]!r}…"
    return tuple(_Num(g) for g in m.groups())


@cache
def _fresh(example: str, seed: int) -> dict[str, Any]:
    """``result.json`` of the shipped example at ``seed`` (its own budget and settings)."""
    with open(ROOT / "examples" / example) as fh:
        spec = yaml.safe_load(fh)
    spec["seed"] = seed
    spec["record"] = False
    return run(spec).to_dict()


def _within_spread(value: float, mean: _Num, sd: _Num) -> None:
    """``value`` inside the doc's 10-seed mean ± 3 sd, allowing for the printed rounding."""
    slack = 3.0 * (sd + sd.rounding) + mean.rounding
    assert abs(value - mean) <= slack, (value, float(mean), float(sd))


def test_000_headlines_match_fresh_runs() -> None:
    """Flat: the −99.5 % vs the parabolic swing (the coordinated motion our coding gives free).
    Box: "seed 1 alone: −68 %" vs the shortest foot path, whose energy the row also prints."""
    row = _summary_row("000")
    (flat_pct,) = _parse(r"the -NUM % energy vs the parabolic swing", row)
    seed, box_pct = _parse(r"seed NUM alone: -NUM %", row)
    (shortest,) = _parse(r"the shortest foot path's NUM J", row)
    flat = _fresh("000_swing_energy_flat.yaml", 1)
    e_best = flat["best"]["metrics"]["energy_total"]
    e_par = flat["baselines"]["calderon2008_parabolic"]["metrics"]["energy_total"]
    assert 100.0 * (1.0 - e_best / e_par) == pytest.approx(flat_pct, abs=0.05)
    box = _fresh("000_swing_energy_obstacle.yaml", int(seed))
    e_best = box["best"]["metrics"]["energy_total"]
    e_short = box["baselines"]["shankar_kaur2011_min_distance"]["metrics"]["energy_total"]
    assert 100.0 * (1.0 - e_best / e_short) == pytest.approx(box_pct, abs=0.5)
    assert e_short == pytest.approx(shortest, abs=0.0005)


@pytest.mark.parametrize("path, index", [("pan", 0), ("jar", 1)])
def test_001_energy_and_manipulability_headlines_match_fresh_runs(path: str, index: int) -> None:
    """"electrical energy −44.0 ± 0.1 % / −41.2 ± 1.0 % … seed 1: −44.06 % / −42.25 %",
    "mean manipulability ×3.705 ± 0.001 / ×5.28 ± 0.01" (pan / jar) against the original
    placement."""
    row = _summary_row("001")
    energy = _parse(r"electrical energy NUM ± NUM % / NUM ± NUM %", row)
    one = _parse(r"seed NUM: NUM % / NUM %", row)
    manip = _parse(r"mean manipulability ×NUM ± NUM / ×NUM ± NUM", row)
    doc = _fresh(f"001_path_placement_{path}.yaml", int(one[0]))
    best, orig = doc["best"]["metrics"], doc["baselines"]["original"]["metrics"]
    change = best["energy_change_pct"]
    assert change == pytest.approx(100.0 * (best["energy_J"] / orig["energy_J"] - 1.0), rel=1e-9)
    assert change == pytest.approx(one[1 + index], rel=1e-3)
    _within_spread(change, energy[2 * index], energy[2 * index + 1])
    ratio = best["mean_manipulability"] / orig["mean_manipulability"]
    _within_spread(ratio, manip[2 * index], manip[2 * index + 1])
    assert best["feasible"] == 1.0


def test_003_energy_per_metre_headline_matches_a_fresh_run() -> None:
    """"optimised step 0.7759 ± 0.0019 J/m (10 seeds; seed 1: 0.7757 J/m) vs the default
    step's 1.2071 J/m"."""
    row = _summary_row("003")
    mean, sd, seed, one, default = _parse(
        r"optimised step NUM ± NUM J/m \(10 seeds; seed NUM: NUM J/m\) vs the default step's "
        r"NUM J/m", row)
    doc = _fresh("003_quadruped_gait.yaml", int(seed))
    best = doc["best"]["metrics"]
    value = best["energy_per_metre_J_per_m"]
    assert value == pytest.approx(one, rel=1e-3)
    _within_spread(value, mean, sd)
    assert best["feasible"] == 1.0 and best["min_stability_margin_m"] >= 0.001 - 1e-9
    base = doc["baselines"]["default_step"]["metrics"]["energy_per_metre_J_per_m"]
    assert base == pytest.approx(default, rel=1e-4)


def test_004_minimum_time_headline_matches_a_fresh_run() -> None:
    """"minimum-time capsule 3.895 ± 0.036 s (10 seeds; seed 1: 3.878 s) vs the paper's law's
    17.28 s", within the joint limits (acceleration limit on)."""
    row = _summary_row("004")
    mean, sd, seed, one, paper = _parse(
        r"minimum-time capsule NUM ± NUM s \(10 seeds; seed NUM: NUM s\) vs the paper's law's "
        r"NUM s", row)
    doc = _fresh("004_path_tracking.yaml", int(seed))
    best = doc["best"]["metrics"]
    assert best["time"] == pytest.approx(one, rel=1e-3)
    _within_spread(best["time"], mean, sd)
    assert best["feasible"] == 1.0
    assert max(best["qd_use_max"], best["qdd_use_max"], best["tau_use_max"]) <= 1.0 + 1e-9
    assert doc["baselines"]["seed"]["objectives"]["time"] == pytest.approx(paper, abs=0.005)


def test_004_physical_minimum_and_speed_profile_match_fresh_runs() -> None:
    """Issue 19: "TOPP-RA's physical minimum of the same path under the same limits is
    3.3602 s … `speeds: profile` reaches 3.3747 ± 0.0001 s (10 seeds; seed 1: 3.3747 s)"."""
    row = _summary_row("004")
    (physical,) = _parse(r"physical minimum of the same path under the same limits is NUM s", row)
    mean, sd, seed, one = _parse(
        r"`speeds: profile` reaches NUM ± NUM s \(10 seeds; seed NUM: NUM s", row)
    doc = _fresh("004_path_tracking.yaml", int(seed))
    assert doc["baselines"]["time_optimal"]["objectives"]["time"] == pytest.approx(
        physical, abs=physical.rounding)
    with open(ROOT / "examples" / "004_path_tracking.yaml") as fh:
        spec = yaml.safe_load(fh)
    spec["problem"]["speeds"] = "profile"
    prof = run({**spec, "seed": int(seed), "record": False}).to_dict()
    assert prof["feasible"] is True
    assert prof["best"]["objectives"]["time"] == pytest.approx(one, abs=one.rounding)
    _within_spread(prof["best"]["objectives"]["time"], mean, sd)
    assert prof["gap"]["reference"] == pytest.approx(physical, abs=physical.rounding)


def test_004_energy_time_front_range_matches_a_fresh_run() -> None:
    """"front of example 2, seed 1: from 4.305 s / 14.47 J to 41.56 s / 14.13 J"."""
    text = DOC.read_text()
    t0, e0, t1, e1 = _parse(
        r"front of example 2, seed 1: from NUM s / NUM J to NUM s / NUM J", text)
    doc = _fresh("004_path_tracking_energy_time.yaml", 1)
    front = sorted(p["objectives"] for p in doc["pareto"])
    assert front[0][0] == pytest.approx(t0, abs=t0.rounding)
    assert front[0][1] == pytest.approx(e0, abs=e0.rounding)
    assert front[-1][0] == pytest.approx(t1, abs=t1.rounding)
    assert front[-1][1] == pytest.approx(e1, abs=e1.rounding)
