"""What the CLI prints about a result (services/display.py, legcore/studies/metric_names.py,
examples/papers/paper_numbers.yaml): 4 significant digits, maximised quantities positive, no
repeated metric, readable names, the paper's numbers beside ours."""

from __future__ import annotations

from pathlib import Path

import yaml
from rich.console import Console

from legcore.studies.metric_names import (
    METRICS,
    display_objective,
    joint_row_name,
    metric_name,
)
from services.display import ResultView, best_text, fmt, full_tables, summary_block
from services.paper_numbers import paper_entry

ROOT = Path(__file__).resolve().parents[2]


def _text(*renderables: object) -> str:
    console = Console(width=200, record=True, color_system=None)
    for r in renderables:
        console.print(r)
    return console.export_text()


def _swing_view() -> ResultView:
    """A swing_energy result as the API stores it (values of a real run, rounded)."""
    metrics = {"score": 9.680989, "f_d": 0.936198, "f_a": 1.0, "theta_total": 0.650809,
               "path_length": 0.154601, "energy_total": 0.00116927, "tau_sq_total": 0.11601,
               "criterion": -9.680989, "feasible": 1.0, "on_grid": 1.0}  # fmt: skip
    parabolic = {"score": 1.5142, "theta_total": 2.39919, "path_length": 0.20867,
                 "energy_total": 0.243006, "criterion": -1.5142, "feasible": 1.0}  # fmt: skip
    return ResultView.from_api("swing_energy", {
        "objective_names": ["neg_score"],
        "objectives": {"names": ["neg_score"], "values": {"score": 9.680989}},
        "metrics": metrics,
        "summary": {"optimizer": {"kind": "ga", "n_gen": 100, "n_evals": 9802, "elapsed_s": 0.6}},
        "baselines": [{"name": "calderon2008_parabolic",
                       "metrics": {"x": [0.1], "metrics": parabolic}}],
    })  # fmt: skip


def test_numbers_have_4_significant_digits() -> None:
    assert fmt(9.680989539007347) == "9.681"
    assert fmt(0.00116927) == "0.001169"
    assert fmt(4.204082461956027e-05) == "4.204e-05"
    assert fmt(16642.8) == "1.664e+04"
    assert fmt(None) == "—" and fmt(float("nan")) == "—" and fmt(3) == "3"
    assert fmt(1.0, metric_name("feasible")) == "yes"


def test_a_maximised_objective_is_shown_positive() -> None:
    assert display_objective("neg_score", -9.68) == ("score", 9.68)
    assert display_objective("time", 2.97) == ("time", 2.97)
    assert best_text(["neg_score"], [-9.680989]) == "score 9.681"
    assert best_text(["time", "energy"], [6.5555, 14.2559]) == "time 6.556, energy 14.26"
    assert best_text(None, [0.5]) == "best 0.5"


def test_names_and_units_of_the_papers_symbols() -> None:
    cuad = metric_name("tau_sq_total", "swing_energy")
    assert (cuad.label, cuad.unit, cuad.paper) == ("squared-torque integral ∫τ²dt", "N²·m²·s",
                                                   "T_cuad")  # fmt: skip
    assert metric_name("path_length", "swing_energy").paper == "D_PFE"
    assert metric_name("T_3", "path_tracking").label == "time on segment 3"
    assert metric_name("peak_thing_W").unit == "W"  # unknown keys: unit from the suffix
    assert joint_row_name("T_cuad") == "squared-torque integral ∫τ²dt (T_cuad)"
    assert joint_row_name("D_PFE") == "foot path length (D_PFE)" and joint_row_name("x") == "x"
    for kind, table in METRICS.items():
        for key, m in table.items():
            assert m.same_as is None or m.same_as != key, (kind, key)


def test_summary_block_one_row_per_quantity_with_the_paper_beside() -> None:
    view = _swing_view()
    spec = yaml.safe_load((ROOT / "examples" / "000_swing_energy_flat.yaml").read_text())
    text = _text(summary_block(view, title="000 flat", spec=spec))
    assert "start = parabolic swing (Calderón 2008)" in text
    assert "score F = w1·f_d + w2·f_a (best 10) — maximised (paper: F)" in text
    assert "1.514 → 9.681" in text and "-9.681" not in text
    assert "swing energy ∫|τ·ω|dt (J) (paper: E_T)" in text and "0.078 → 0.0003" in text
    assert "0.243 → 0.001169" in text and "-99.5 %" in text
    assert text.count("score F") == 1 and "the GA's criterion" not in text


def test_full_tables_hide_repeats_and_show_every_baseline() -> None:
    view = _swing_view()
    text = _text(*full_tables(view, title="t"))
    assert "parabolic swing (Calderón 2008)" in text
    assert "the GA's criterion" not in text and text.count("score F") == 1
    assert "squared-torque integral ∫τ²dt (N²·m²·s)" in text


def test_paper_numbers_match_each_example_once() -> None:
    for path in sorted((ROOT / "examples").glob("*.yaml")):
        spec = yaml.safe_load(path.read_text())
        entry = paper_entry(spec)
        assert entry is not None, path.name
        keys = {k for k in METRICS.get(spec["problem"]["kind"], {})} | {"time", "energy"}
        for row in entry.rows:
            assert row.metric in keys, (path.name, row.metric)
    flat = paper_entry({"problem": {"kind": "swing_energy"}})  # the paper's defaults: case 1
    box = paper_entry({"problem": {"kind": "swing_energy", "obstacle": {"height": 0.02}}})
    assert flat is not None and "Table 3" in flat.source
    assert box is not None and "Table 5" in box.source
    assert paper_entry({"problem": {"kind": "no_such_study"}}) is None
