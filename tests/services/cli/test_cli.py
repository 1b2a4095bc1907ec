"""`legopt run`: progress, result table, DIR/result.json and DIR/recording.rrd; exit 2 naming the
field on bad input."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import yaml
from typer.testing import CliRunner

from services.cli import app

ROOT = Path(__file__).resolve().parents[3]
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
    assert "Pareto front of 300 points" not in res.output  # 3 generations: the real size
    assert re.search(r"Pareto front of \d+ points, optimum = its knee point", res.output)
    assert "error of the triangle angle β1 (rad) — minimised (paper: f1)" in res.output
    verbose = runner.invoke(app, ["run", str(_spec(tmp_path, "002_hexapod_workspace.yaml",
                                                   record=False)),
                                  "--out", str(out), "--quiet", "--verbose"])  # fmt: skip
    assert verbose.exit_code == 0, verbose.output
    words = " ".join(verbose.output.split())  # column headers may wrap
    for baseline in ("start", "stance", "solution a", "straight", "paper: start"):
        assert baseline in words  # every baseline beside the optimum, the paper's numbers
    assert "per joint" in verbose.output


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


def test_keys_create_admin_list_and_revoke(tmp_path: Path, monkeypatch: object) -> None:
    """`legopt keys`: an admin key, an expiring key, the listing, revocation (defect 12)."""
    import pytest

    from services.store.api_keys import get_api_key_by_hash
    from services.store.keys import hash_api_key
    from services.store.session import reset_engine, session_scope
    from services.store.settings import get_settings

    mp: pytest.MonkeyPatch = monkeypatch  # type: ignore[assignment]
    mp.setenv("LEGOPT_DATA_DIR", str(tmp_path))
    mp.delenv("LEGOPT_DATABASE_URL", raising=False)
    get_settings.cache_clear()
    reset_engine()
    try:
        res = runner.invoke(app, ["keys", "create", "--name", "root", "--admin"])
        assert res.exit_code == 0, res.output
        admin_raw = res.output.strip().splitlines()[-1]
        res = runner.invoke(app, ["keys", "create", "--name", "temp", "--expires-in-days", "1"])
        temp_raw = res.output.strip().splitlines()[-1]
        with session_scope() as s:
            admin = get_api_key_by_hash(s, hash_api_key(admin_raw))
            temp = get_api_key_by_hash(s, hash_api_key(temp_raw))
        assert admin is not None and admin.is_admin
        assert temp is not None and not temp.is_admin and temp.expires_at is not None
        listing = runner.invoke(app, ["keys", "list"]).output
        assert "root" in listing and "admin" in listing and "temp" in listing
        assert runner.invoke(app, ["keys", "revoke", temp.id]).exit_code == 0
        with session_scope() as s:
            after = get_api_key_by_hash(s, hash_api_key(temp_raw))
        assert after is not None and after.revoked_at is not None
        assert runner.invoke(app, ["keys", "revoke", "nope"]).exit_code == 2
    finally:
        get_settings.cache_clear()
        reset_engine()


def test_version_prints_the_installed_version() -> None:
    from importlib.metadata import version

    res = runner.invoke(app, ["--version"])
    assert res.exit_code == 0 and res.output.strip() == f"legopt {version('legopt')}"


def test_replay_downloads_into_a_temporary_file_and_a_free_port(
    tmp_path: Path, monkeypatch: Any
) -> None:
    """`legopt replay JOB` without --save leaves no file in the working directory (the download
    goes to a temporary file, removed when the viewer stops) and asks for a free port (0)."""
    import contextlib

    from services.cli import jobs as cli_jobs
    from services.recording import replay

    seen: dict[str, Any] = {}

    class FakeClient:
        def recording(self, job_id: str) -> bytes:
            return b"RRF2-fake"

    class Handle:
        url = "http://127.0.0.1:1/"

        def wait(self) -> None:
            seen["exists_while_open"] = seen["path"].exists()

        def stop(self) -> None:
            pass

    def open_viewer(path: Path, *, web: bool | None, port: int) -> Handle:
        seen.update(path=path, port=port)
        return Handle()

    monkeypatch.setattr(cli_jobs, "client", lambda *a: contextlib.nullcontext(FakeClient()))
    monkeypatch.setattr(cli_jobs, "resolve_id", lambda c, t: ("job", "0" * 8 + "-full"))
    monkeypatch.setattr(replay, "open_viewer", open_viewer)
    monkeypatch.chdir(tmp_path)
    res = runner.invoke(app, ["replay", "00000000", "--web"])
    assert res.exit_code == 0, res.output
    assert seen["port"] == 0 and seen["exists_while_open"]
    assert not seen["path"].exists() and list(tmp_path.iterdir()) == []
