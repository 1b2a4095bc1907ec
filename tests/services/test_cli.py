"""`legopt run`: progress, result table, DIR/result.json and DIR/recording.rrd; exit 2 naming the
field on bad input."""

from __future__ import annotations

import json
from pathlib import Path

import yaml
from typer.testing import CliRunner

from services.cli import app

ROOT = Path(__file__).resolve().parents[2]
runner = CliRunner()


def _spec(tmp_path: Path, example: str, **over: object) -> Path:
    spec = yaml.safe_load((ROOT / "examples" / example).read_text())
    spec["budget"] = {"generations": 3}
    spec.update(over)
    path = tmp_path / "spec.yaml"
    path.write_text(yaml.safe_dump(spec))
    return path


def test_run_writes_result_json_and_recording(tmp_path: Path) -> None:
    out = tmp_path / "out"
    res = runner.invoke(app, ["run", str(_spec(tmp_path, "002_hexapod_workspace.yaml")),
                              "--out", str(out), "--quiet"])  # fmt: skip
    assert res.exit_code == 0, res.output
    doc = json.loads((out / "result.json").read_text())
    for key in ("spec", "status", "best", "pareto", "baselines", "history"):
        assert key in doc
    assert doc["status"] == "succeeded"
    assert set(doc["best"]) >= {"x", "objectives", "metrics"}
    assert len(doc["history"]) == 3
    assert doc["pareto"] and set(doc["pareto"][0]) == {"x", "objectives"}
    assert (out / "recording.rrd").read_bytes()[:4] == b"RRF2"
    assert "best vs baselines" in res.output


def test_run_without_recording(tmp_path: Path) -> None:
    out = tmp_path / "out"
    spec = _spec(tmp_path, "003_quadruped_gait.yaml", record=False)
    res = runner.invoke(app, ["run", str(spec), "--out", str(out), "--quiet"])
    assert res.exit_code == 0, res.output
    assert (out / "result.json").exists() and not (out / "recording.rrd").exists()


def test_bad_specs_exit_2_naming_the_field(tmp_path: Path) -> None:
    spec = _spec(tmp_path, "003_quadruped_gait.yaml", colour="red")
    res = runner.invoke(app, ["run", str(spec), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2
    assert "colour: Extra inputs are not permitted" in res.output
    spec = _spec(tmp_path, "003_quadruped_gait.yaml", problem={"kind": "quadruped_gait", "stpe": 1})
    res = runner.invoke(app, ["run", str(spec), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2 and "problem.stpe: Extra inputs are not permitted" in res.output
    spec = _spec(tmp_path, "003_quadruped_gait.yaml", robot="r2d2")
    res = runner.invoke(app, ["run", str(spec), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2 and "robot" in res.output and "r2d2" in res.output
    res = runner.invoke(app, ["run", str(tmp_path / "missing.yaml")])
    assert res.exit_code == 2 and "cannot read" in res.output
    (tmp_path / "list.yaml").write_text("- 1\n- 2\n")
    res = runner.invoke(app, ["run", str(tmp_path / "list.yaml")])
    assert res.exit_code == 2 and "must contain a mapping" in res.output
    assert not (tmp_path / "o").exists()  # nothing written for a rejected spec
