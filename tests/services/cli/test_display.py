"""What the CLI prints about a result (services/cli/display.py, legcore/studies/metric_names.py,
examples/papers/paper_numbers.yaml): 4 significant digits, maximised quantities positive, no
repeated metric, readable names, the paper's numbers beside ours."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from rich.console import Console

from legcore.studies.metric_names import (
    METRICS,
    display_objective,
    joint_row_name,
    metric_name,
)
from services.cli.display import full_tables, summary_block
from services.cli.objectives import best_text
from services.cli.result_view import ResultView, fmt
from services.paper_numbers import paper_entry

ROOT = Path(__file__).resolve().parents[3]


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


@pytest.mark.parametrize("width", [80, 100, 120])
def test_summary_block_keeps_our_numbers_on_a_normal_terminal(width: int) -> None:
    """Issue 21: at 80-120 columns the block keeps start → optimum and the change of every
    row whole (the names and the paper's column wrap instead), and cuts nothing."""
    view = _swing_view()
    spec = yaml.safe_load((ROOT / "examples" / "000_swing_energy_flat.yaml").read_text())
    console = Console(width=width, record=True, color_system=None)
    console.print(summary_block(view, title="000 flat", spec=spec))
    text = console.export_text()
    for ours, change in (("1.514 → 9.681", "+539 %"), ("0.243 → 0.001169", "-99.5 %"),
                         ("2.399 → 0.6508", "-72.9 %"), ("0.2087 → 0.1546", "-25.9 %")):
        row = next(ln for ln in text.splitlines() if ours in ln)
        assert change in row, (width, row)
    assert "0.078 → 0.0003" in text and "(-99.6%)" in text
    assert "…" not in text
    assert max(len(ln) for ln in text.splitlines()) <= width


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


# ------------------------------------------------------------------ feasibility (issue 25)
#: A quadruped_gait result asked for a 20 mm static margin the robot cannot give: the optimum
#: and the default step both violate it (values of a real run, rounded).
GAIT_VIOLATIONS = [
    {"constraint": "stability_margin_mm", "amount": 17.64, "unit": "mm",
     "text": "static stability margin 2.36 mm, 17.6 mm short of the required 20 mm"},
    {"constraint": "joint_speed", "amount": 0.0546, "unit": "", "text": ""},
]  # fmt: skip


def _gait(feasible: bool, start_feasible: bool, *, task: bool = True) -> ResultView:
    metrics = {"energy_per_metre": 2.5, "step_length_m": 0.1, "step_height_m": 0.03,
               "duty": 0.8, "min_stability_margin_m": 0.00236}  # fmt: skip
    start = {"energy_per_metre": 3.1, "step_length_m": 0.08, "step_height_m": 0.03,
             "duty": 0.8, "min_stability_margin_m": 0.0006}  # fmt: skip
    return ResultView.from_api("quadruped_gait", {
        "objective_names": ["energy_per_metre"],
        "objectives": {"names": ["energy_per_metre"], "values": {"energy_per_metre": 2.5}},
        "metrics": metrics,
        "feasible": feasible,
        "violations": [] if feasible else GAIT_VIOLATIONS,
        "task": {"params": {"depth": 0.18}, "preset": None,
                 "rules": {"depth": "0.75 × leg length (0.24 m) = 0.18 m below the hip",
                           "speed": "Froude 0.05 at leg length 0.24 m = 0.077 m/s"}}
        if task else None,
        "summary": {"optimizer": {"kind": "hka", "n_gen": 2}},
        "baselines": [{"name": "default_step", "feasible": start_feasible,
                       "violations": [] if start_feasible else GAIT_VIOLATIONS[:1],
                       "metrics": {"x": [0.08, 0.03, 0.8], "metrics": start}}],
    })  # fmt: skip


def test_an_infeasible_optimum_is_announced_with_each_violation() -> None:
    from services.cli.display_verdict import verdict_line

    view = _gait(feasible=False, start_feasible=True)
    text = _text(summary_block(view, title="walk", spec={"problem": {"kind": "quadruped_gait"}}))
    lines = text.splitlines()
    assert lines[1].strip() == (
        "INFEASIBLE: stability_margin_mm over its limit by 17.64 mm — static stability margin "
        "2.36 mm, 17.6 mm short of the required 20 mm; joint_speed over its limit by 0.0546"
    )  # right under the title, before any number
    line = verdict_line(view.verdict)
    assert line is not None and str(line.style) == "bold red"
    # no change in % towards an answer that breaks the constraints
    assert "%" not in text and "change: — because the optimum is infeasible" in text
    full = _text(*full_tables(view, title="walk"))  # (printed before the summary block)
    row = next(ln for ln in full.splitlines() if "meets every constraint" in ln)
    assert row.split()[-2:] == ["NO", "yes"]  # the optimum, the default step

    ok = _gait(feasible=True, start_feasible=True)
    text = _text(summary_block(ok, title="walk", spec={"problem": {"kind": "quadruped_gait"}}))
    assert "INFEASIBLE" not in text and "feasible: the optimum meets every constraint" in text
    assert "-19.4 %" in text  # 3.1 → 2.5 J/m, both feasible: the change is shown
    assert str(verdict_line(ok.verdict).style) == "green"  # type: ignore[union-attr]
    unchecked = _swing_view()  # a result stored before the verdict existed: no claim either way
    assert verdict_line(unchecked.verdict) is None
    assert "feasible: the" not in _text(summary_block(unchecked, title="t"))
    assert "meets every constraint" not in _text(*full_tables(unchecked, title="t"))


def test_no_change_in_percent_against_an_infeasible_start() -> None:
    view = _gait(feasible=True, start_feasible=False)
    text = _text(summary_block(view, title="walk", spec={"problem": {"kind": "quadruped_gait"}}))
    row = next(ln for ln in text.splitlines() if "energy per metre" in ln.lower())
    assert "3.1 → 2.5" in row and row.rstrip().endswith("—") and "%" not in row
    assert ("change: — because the start (" in text and ") is infeasible: stability_margin_mm "
            "over its limit by 17.64 mm" in text)  # fmt: skip


def test_the_task_rules_are_one_line() -> None:
    text = _text(summary_block(_gait(True, True), title="walk"))
    (line,) = [ln for ln in text.splitlines() if ln.strip().startswith("task ")]
    assert line.strip() == (
        "task derived from the robot: depth: 0.75 × leg length (0.24 m) = 0.18 m below the hip; "
        "speed: Froude 0.05 at leg length 0.24 m = 0.077 m/s"
    )
    assert not [ln for ln in _text(summary_block(_gait(True, True, task=False), title="w"))
                .splitlines() if ln.strip().startswith("task ")]  # fmt: skip
    # a long rule stays one line in the summary (cut at the console's width)...
    view = _gait(True, True)
    view.task = {"params": {}, "preset": "seed 003, Table 2",
                 "rules": {"q_ref": "standing postures " + "with the feet 0.16 m below " * 20}}
    lines = [ln for ln in _text(summary_block(view, title="w")).splitlines() if "task" in ln]
    assert len(lines) == 1 and lines[0].rstrip().endswith("…")
    # ...and whole, with the paper's preset, in the full tables
    full = _text(*full_tables(view, title="w"))
    assert "task: what the spec leaves out is the paper's — seed 003, Table 2" in full
    assert "    q_ref: standing postures with the feet" in full


def test_paper_numbers_only_on_the_papers_robot() -> None:
    """The PUMA paper's 18.56 → 8.59 J is not printed beside a Z1 arm, nor Calderón's numbers
    beside another leg: the robot must be the paper's (by name, or the study's default)."""
    pan = yaml.safe_load((ROOT / "examples" / "001_path_placement_pan.yaml").read_text())
    assert paper_entry(pan) is not None and paper_entry({**pan, "robot": None}) is not None
    for robot in ("articulated_5dof", {"kind": "urdf", "name": "z1", "urdf": "<robot/>"},
                  "z1-stored-under-this-name"):  # fmt: skip
        assert paper_entry({**pan, "robot": robot}) is None, robot
    flat = yaml.safe_load((ROOT / "examples" / "000_swing_energy_flat.yaml").read_text())
    other = {**flat, "robot": {"kind": "urdf", "name": "solo12_leg", "urdf": "<robot/>"}}
    ours = _text(summary_block(_swing_view(), title="000 flat", spec=flat))
    theirs = _text(summary_block(_swing_view(), title="flat on a Solo12 leg", spec=other))
    assert "0.078 → 0.0003" in ours and "Calderón et al. 2015" in ours
    assert "0.078" not in theirs and "Calderón et al. 2015" not in theirs
    assert "(paper: F)" in theirs  # the symbol of our quantity stays: it names the formula
    # the paper's robot, but not the paper's settings: a 20 mm margin instead of its 1 mm
    walk = yaml.safe_load((ROOT / "examples" / "003_quadruped_gait.yaml").read_text())
    assert paper_entry(walk) is not None
    assert paper_entry({**walk, "problem": {**walk["problem"], "stability_margin": 0.001}})
    assert paper_entry({**walk, "problem": {**walk["problem"], "stability_margin": 0.02}}) is None
    # when the task a job ran is known (stored with its result), its values decide
    ran = {"kind": "quadruped_gait", "depth": 0.1648, "stability_margin": 0.001}
    assert paper_entry(walk, {"params": ran}) is not None
    assert paper_entry(walk, {"params": {**ran, "depth": 0.2}}) is None


def test_status_marks_an_infeasible_job_in_red(monkeypatch: pytest.MonkeyPatch) -> None:
    from services.cli import objectives
    from services.cli.views import job_block, jobs_table, status_text

    def never(_spec: object) -> None:
        raise AssertionError("the objective names come from the job's stored facts")

    monkeypatch.setattr(objectives, "objective_names_for", never)
    facts = {"kind": "quadruped_gait", "robot": "calderon_quadruped", "optimizer": "ga",
             "objectives": ["energy_per_metre"], "n_var": 3}  # fmt: skip
    job = {"id": "2253abcd-0000", "kind": "quadruped_gait", "status": "succeeded",
           "feasible": False, "violations": GAIT_VIOLATIONS, "generation": 2,
           "total_generations": 2, "progress": 1.0, "attempts": 1, "spec": {},
           "facts": facts, "best_objective": [1.5]}  # fmt: skip
    assert str(status_text(job)) == "succeeded (infeasible)"
    assert str(status_text(job).style) == "bold red"
    assert str(status_text({**job, "feasible": True}).style) == "green"
    assert str(status_text({**job, "feasible": None})) == "succeeded"  # not checked: no claim
    assert str(status_text({**job, "status": "failed", "feasible": None})) == "failed"
    table = _text(jobs_table({"items": [job], "total": 1}))
    assert "succeeded (infeasible)" in table
    block = _text(job_block(job))
    assert "succeeded (infeasible), attempt 1" in block
    assert "INFEASIBLE: stability_margin_mm over its limit by 17.64 mm" in block


def test_the_gap_to_the_physical_minimum_is_a_line_of_the_block() -> None:
    """Issue 19: a single-objective result states how far it is from the best its problem
    allows (path_tracking: TOPP-RA), or why it has no such reference."""
    from services.cli.display_verdict import gap_line

    gap = {"objective": "time", "value": 3.3914, "reference": 3.3602,
           "kind": "physical minimum", "method": "TOPP-RA on 2000 intervals", "pct": 0.9286}
    view = _gait(feasible=True, start_feasible=True)
    view.gap = gap
    text = _text(summary_block(view, title="t", spec={"problem": {"kind": "quadruped_gait"}}))
    line = next(ln for ln in text.splitlines() if "gap" in ln).strip()
    assert line == ("gap to the physical minimum: +0.929 % (3.3914 s vs 3.3602 s, TOPP-RA on "
                    "2000 intervals)")
    none = gap_line({"objective": "energy_per_metre", "reference": None, "reason": "no exact"})
    assert none is not None and none.plain.strip() == "no optimality gap: no exact"
    assert gap_line({"reference": None, "reason": "several objectives"}) is None
    assert gap_line(None) is None
    # from the API's result (GET /jobs/{id}/result: gap) and from result.json alike
    api = ResultView.from_api("path_tracking", {"objective_names": ["time"], "gap": gap,
                                                "objectives": {"names": ["time"],
                                                               "values": {"time": 3.3914}}})
    assert api.gap == gap


def test_the_demo_finds_the_example_specs() -> None:
    """The demo's examples folder is the repository's (a module move once broke this)."""
    from services.cli import demo

    assert (demo.EXAMPLES / "000_swing_energy_flat.yaml").is_file()
