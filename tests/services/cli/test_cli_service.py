"""The `legopt` verbs that talk to a service, against a real embedded stack (API + 1 worker):
id prefixes everywhere (unknown / ambiguous = exit 2 naming it), `status` as a summary line or
block (`--json` the full record), `results` with readable names, `cancel` of a job and of a
sweep, `replay --point` saving a front point's recording, and `export` of the job list, a
front, a history and a sweep's cells."""

from __future__ import annotations

import json
import re
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from services.cli import app
from tests.integration.stack import Stack, embedded_stack
from tests.patience import Patience

ROOT = Path(__file__).resolve().parents[3]
runner = CliRunner()

pytestmark = pytest.mark.integration


@pytest.fixture(scope="module")
def stack(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Stack]:
    tmp = tmp_path_factory.mktemp("cli-stack")
    with embedded_stack(tmp) as st:
        yield st


def cli(stack: Stack, *args: str) -> tuple[int, str]:
    res = runner.invoke(app, [*args, "--url", stack.url, "--key", stack.key])
    return res.exit_code, res.output


def _spec(tmp: Path, example: str, generations: int) -> Path:
    spec = yaml.safe_load((ROOT / "examples" / example).read_text())
    spec["budget"] = {"generations": generations}
    path = tmp / f"{Path(example).stem}-{generations}.yaml"
    path.write_text(yaml.safe_dump(spec))
    return path


def test_submit_status_results_by_prefix(stack: Stack, tmp_path: Path) -> None:
    code, out = cli(stack, "submit", str(_spec(tmp_path, "000_swing_energy_flat.yaml", 3)),
                    "--wait")  # fmt: skip
    assert code == 0, out
    job_id = re.search(r"job ([0-9a-f-]{36}) queued", out).group(1)  # type: ignore[union-attr]
    assert "score F = w1·f_d + w2·f_a (best 10) — maximised (paper: F)" in out
    assert "objective score" not in out and "criterion" not in out

    code, out = cli(stack, "status")
    assert code == 0 and job_id[:8] in out and job_id not in out  # one short line per job

    code, out = cli(stack, "status", job_id[:6])
    assert code == 0, out
    for field in ("kind", "swing_energy", "robot", "calderon_leg", "optimiser", "GA",
                  "succeeded", "3/3 generations", "finished"):  # fmt: skip
        assert field in out
    assert re.search(r"best\s+score \d", out) and "mutation_rate" not in out

    code, out = cli(stack, "status", job_id[:6], "--json")
    assert code == 0 and json.loads(out)["spec"]["problem"]["kind"] == "swing_energy"

    code, out = cli(stack, "results", job_id[:5])
    assert code == 0, out
    assert "swing energy ∫|τ·ω|dt (J)" in out and "parabolic swing (Calderón 2008)" in out
    assert "energy_total" not in out
    code, out = cli(stack, "results", job_id[:5], "--json")
    assert code == 0 and json.loads(out)["job_id"] == job_id


def test_unknown_and_ambiguous_prefixes_exit_2(stack: Stack, tmp_path: Path) -> None:
    spec = str(_spec(tmp_path, "004_path_tracking.yaml", 2))
    for _ in range(2):
        assert cli(stack, "submit", spec)[0] == 0
    code, out = cli(stack, "status", "zz")
    assert code == 2 and "ID: no job or sweep id starts with 'zz'" in out
    code, out = cli(stack, "results", "")
    assert code == 2 and "JOB: '' is ambiguous" in out
    code, out = cli(stack, "replay", "zz")
    assert code == 2 and "JOB: no job id starts with 'zz'" in out


def test_cancel_a_job_and_a_sweep_by_prefix(stack: Stack, tmp_path: Path) -> None:
    code, out = cli(stack, "submit", str(_spec(tmp_path, "003_quadruped_gait.yaml", 4000)))
    assert code == 0, out
    job_id = re.search(r"job ([0-9a-f-]{36})", out).group(1)  # type: ignore[union-attr]
    code, out = cli(stack, "cancel", job_id[:8])
    assert code == 0, out
    assert re.search(rf"job {job_id[:8]}: (cancelled|cancel requested)", out)
    stack.wait_for(job_id, lambda j: j["status"] == "cancelled", timeout_s=60)
    code, out = cli(stack, "cancel", job_id[:8])
    assert code == 0 and "already finished (cancelled), nothing to cancel" in out, out
    # a finished job can be deleted, by prefix, once
    code, out = cli(stack, "delete", job_id[:8])
    assert code == 0 and f"job {job_id[:8]}: deleted" in out, out
    code, out = cli(stack, "status", job_id)
    assert code == 2, out

    base = yaml.safe_load((ROOT / "examples" / "003_quadruped_gait.yaml").read_text())
    base["budget"] = {"generations": 4000}
    doc = tmp_path / "sweep.yaml"
    doc.write_text(yaml.safe_dump({"base": base, "seeds": [1, 2]}))
    code, out = cli(stack, "sweep", str(doc))
    assert code == 0, out
    sweep_id = re.search(r"sweep ([0-9a-f-]{36}): 2 jobs", out).group(1)  # type: ignore[union-attr]
    code, out = cli(stack, "status", sweep_id[:8])
    assert code == 0 and f"sweep {sweep_id}" in out and "seed" in out
    code, out = cli(stack, "cancel", sweep_id[:8])
    assert code == 0, out
    said = re.search(  # one request; a running job stops after its current generation
        rf"sweep {sweep_id[:8]}: (\d) cancelled(?:, (\d) stopping after their current "
        r"generation)?, 0 already finished",
        out,
    )
    assert said and int(said.group(1)) + int(said.group(2) or 0) == 2, out
    patience = Patience(60)
    with stack.client() as c:
        while not patience.expired():
            jobs = c.jobs(sweep_id=sweep_id)["items"]
            if all(j["status"] == "cancelled" for j in jobs):
                break
            time.sleep(0.3)
        assert [j["status"] for j in c.jobs(sweep_id=sweep_id)["items"]] == ["cancelled"] * 2


def test_replay_a_front_point_saves_its_recording(stack: Stack, tmp_path: Path) -> None:
    """`legopt replay JOB --point K --save FILE`: the recording of front point K, made on demand
    by the service, saved as a Rerun file (the header a job's own recording starts with)."""
    code, out = cli(stack, "submit", str(_spec(tmp_path, "004_path_tracking_energy_time.yaml", 3)),
                    "--wait", "--quiet")  # fmt: skip
    assert code == 0, out
    job_id = out.strip().splitlines()[-1]
    with stack.client() as c:
        job_rrd = c.recording(job_id)
        k = c.pareto(job_id)["items"][-1]["index"]
    target = tmp_path / "point.rrd"
    code, out = cli(stack, "replay", job_id[:8], "--point", str(k), "--save", str(target))
    assert code == 0, out
    assert f"saved {target}" in out.replace("\n", "")
    data = target.read_bytes()
    assert job_rrd[:4] == b"RRF2" and data[:4] == job_rrd[:4]
    assert data != job_rrd  # that point's recording, not the job's
    code, out = cli(stack, "replay", job_id[:8], "--point", "99999", "--save", str(target))
    assert code == 2 and "no front point 99999" in out


def test_export_jobs_front_history_and_cells(stack: Stack, tmp_path: Path) -> None:
    """`legopt export`: the job list as CSV, a job's front as JSON (with its points' metrics)
    and its history as Parquet (read back with pyarrow), a sweep's cells as CSV, by id
    prefix."""
    import csv

    import pyarrow.parquet as pq

    base = yaml.safe_load((ROOT / "examples" / "004_path_tracking_energy_time.yaml").read_text())
    base.update(budget={"generations": 2}, record=False)
    doc = tmp_path / "sweep.yaml"
    doc.write_text(yaml.safe_dump({"base": base, "seeds": [1, 2],
                                   "grid": {"optimizer.params.pop_size": [12, 16]}}))  # fmt: skip
    code, out = cli(stack, "sweep", str(doc))
    assert code == 0, out
    sweep_id = re.search(r"sweep ([0-9a-f-]{36}): 4 jobs", out).group(1)  # type: ignore[union-attr]
    code, out = cli(stack, "submit", str(_spec(tmp_path, "004_path_tracking_energy_time.yaml", 3)),
                    "--wait", "--quiet")  # fmt: skip
    assert code == 0, out
    job_id = out.strip().splitlines()[-1]
    code, out = cli(stack, "export", "jobs", "--out", str(tmp_path / "jobs.csv"))
    assert code == 0, out
    with open(tmp_path / "jobs.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert job_id in {r["id"] for r in rows}
    code, out = cli(stack, "export", "front", job_id[:8], "--format", "json",
                    "--out", str(tmp_path / "front.json"))  # fmt: skip
    assert code == 0, out
    front = json.loads((tmp_path / "front.json").read_text())
    assert front["rows"], "an empty front"
    assert front["columns"][:3] == ["index", "time", "energy"]
    assert all(isinstance(r["energy"], float) for r in front["rows"])
    assert front["units"]["energy"] == "J" and front["units"]["time"] == "s"
    code, out = cli(stack, "export", "history", job_id[:8], "--format", "parquet",
                    "--out", str(tmp_path / "history.parquet"))  # fmt: skip
    assert code == 0, out
    table = pq.read_table(tmp_path / "history.parquet")
    assert table.num_rows == 3 and "generation" in table.column_names
    code, out = cli(stack, "export", "front", "ffffffff")
    assert code == 2 and "ffffffff" in out

    with stack.client() as c:
        jobs = c.jobs(sweep_id=sweep_id)["items"]
    assert len(jobs) == 4
    for j in jobs:
        stack.wait_for(j["id"], lambda j: j["status"] == "succeeded", timeout_s=120)
    code, out = cli(stack, "export", "cells", sweep_id[:8], "--out", str(tmp_path / "cells.csv"))
    assert code == 0, out
    with open(tmp_path / "cells.csv", newline="") as fh:
        cells = list(csv.DictReader(fh))
    assert [c["optimizer.params.pop_size"] for c in cells] == ["12", "16"]
    assert [(c["jobs"], c["succeeded"]) for c in cells] == [("2", "2"), ("2", "2")]
    assert all(float(c["time_mean [s]"]) > 0 and c["time_n"] == "2" for c in cells)
    code, out = cli(stack, "export", "cells", sweep_id[:8], "--format", "parquet",
                    "--out", str(tmp_path / "cells.parquet"))  # fmt: skip
    assert code == 0, out
    assert pq.read_table(tmp_path / "cells.parquet").num_rows == 2
    code, out = cli(stack, "export", "cells", "ffffffff")
    assert code == 2 and "SWEEP: no sweep id starts with 'ffffffff'" in out
