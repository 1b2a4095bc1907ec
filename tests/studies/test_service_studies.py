"""Issue 9 through the real service (API + worker processes, embedded stack): one real robot per
legged study kind, the capability refusal as a 422 at ``robot``, ``GET /studies`` and
``legopt studies``, and a study kind from a plug-in package.

The plug-in (``examples/plugin_study``) is really installed — ``pip install --no-deps --target``
a temporary directory (its build backend fetched by pip as for any package) — and that
directory is put on the service processes' ``PYTHONPATH``: the API and the workers find the
kind through its ``legopt.studies`` entry point exactly as in a venv, while the shared
environment of the test run stays untouched (nothing to uninstall: the directory is removed).
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from services.client import TERMINAL, ApiError
from tests.integration.stack import ROOT, Stack, embedded_stack
from tests.robot_files import ERD_URDF, erd_robots_dir, require_erd

pytestmark = pytest.mark.integration

PLUGIN = ROOT / "examples" / "plugin_study"


def _install_plugin(tmp: Path) -> Path:
    src = tmp / "plugin_src"
    shutil.copytree(PLUGIN, src, ignore=shutil.ignore_patterns("build", "*.egg-info",
                                                               "__pycache__"))
    site = tmp / "site"
    out = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--no-deps", "--disable-pip-version-check",
         "--quiet", "--target", str(site), str(src)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert out.returncode == 0, f"pip install of the example plug-in failed:\n{out.stderr}"
    assert list(site.glob("legopt_example_study-*.dist-info/entry_points.txt"))
    return site


@pytest.fixture(scope="module")
def stack(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Stack]:
    require_erd()
    tmp = tmp_path_factory.mktemp("studies-stack")
    site = _install_plugin(tmp)
    with embedded_stack(tmp, {"PYTHONPATH": os.pathsep.join([str(site), str(ROOT)])}) as st:
        yield st


def _urdf(name: str, **extra: Any) -> dict[str, Any]:
    root = erd_robots_dir()
    assert root is not None
    return {"kind": "urdf", "name": name, "urdf": (root / ERD_URDF[name]).read_text(), **extra}


def _run(stack: Stack, spec: dict[str, Any]) -> dict[str, Any]:
    with stack.client() as c:
        job = c.submit(spec)
        done = c.wait(job["id"], timeout_s=180)
        assert done["status"] == "succeeded", f"{done.get('error')}\n{stack.log_tail()}"
        return c.result(job["id"])


def _baselines(res: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Baseline name -> its metrics, from ``GET /jobs/{id}/result``."""
    out = {}
    for b in res["baselines"]:
        m = b["metrics"]
        out[b["name"]] = m.get("metrics", m) if isinstance(m, dict) else m
    return out


def _422(stack: Stack, spec: dict[str, Any]) -> dict[str, Any]:
    with stack.client() as c, pytest.raises(ApiError) as exc:
        c.submit(spec)
    assert exc.value.status == 422, exc.value
    detail = exc.value.detail
    assert isinstance(detail, list)
    return dict(detail[0])


def test_studies_listing_names_what_each_kind_needs(stack: Stack) -> None:
    with stack.client() as c:
        c.add_robot("go1", _urdf("go1", legs="auto"))
        data = c.get("/studies")
    kinds = {it["kind"]: it for it in data["items"]}
    assert {"swing_energy", "quadruped_gait", "hexapod_workspace", "holding_torque"} <= set(kinds)
    assert data["plugin_errors"] == {} and data["stored_robots_checked"] == 1
    plug = kinds["holding_torque"]
    assert plug["plugin"] == "legopt-example-study" and plug["defaults"]["tolerance"] == 0.005
    assert plug["params_schema"]["properties"]["tolerance"]["exclusiveMinimum"] == 0.0
    fits = {it["kind"]: {r["robot"]: r for r in it["robots"]} for it in data["items"]}
    assert fits["quadruped_gait"]["go1"]["accepted"] and fits["quadruped_gait"]["go1"]["source"] \
        == "stored"
    assert fits["hexapod_workspace"]["go1"]["reason"] == (
        "hexapod_workspace needs 6 legs of 3 joints; robot go1 has 4 legs")
    assert fits["quadruped_gait"]["citedi_hexapod"]["reason"] == (
        "quadruped_gait needs 4 legs of 2–3 joints; robot citedi_hexapod has 6 legs")
    assert kinds["quadruped_gait"]["needs"] == [
        "a legged robot: 4 legs, each of 2–3 joints; revolute joints only"]


def test_a_refused_robot_is_a_422_at_robot(stack: Stack) -> None:
    err = _422(stack, {"robot": "citedi_hexapod", "problem": {"kind": "quadruped_gait"}})
    assert err["loc"] == ["body", "robot"]
    assert err["msg"] == (
        "quadruped_gait needs 4 legs of 2–3 joints; robot citedi_hexapod has 6 legs")
    err = _422(stack, {"robot": _urdf("panda", locked_joints={"panda_finger_joint1": 0.02}),
                       "problem": {"kind": "swing_energy"}})
    assert err["loc"] == ["body", "robot"] and err["msg"] == (
        "swing_energy needs 2–6 actuated joints; robot panda has 7")


def test_swing_energy_on_a_solo12_leg(stack: Stack) -> None:
    start, end = [-0.06, 0.0594, -0.22], [0.06, 0.0594, -0.22]
    res = _run(stack, {
        "robot": _urdf("solo12", legs="auto"),
        "problem": {"kind": "swing_energy", "leg": "FL", "foot_start": start, "foot_end": end,
                    "exact_ends": True, "T": 1.0, "dt": 0.02,
                    "baselines": ["calderon2008_parabolic"]},
        "optimizer": {"kind": "ga", "params": {"pop_size": 16, "fitness": "window",
                                               "penalty": None}},
        "budget": {"generations": 3}, "seed": 1,
    })
    ex = res["summary"]["extras"]
    assert ex["leg"] == "solo12.FL"
    assert max(abs(a - b) for a, b in zip(ex["foot_start"] + ex["foot_end"], start + end,
                                          strict=True)) < 1e-6
    assert res["metrics"]["energy_total"] > 0.0
    assert any(a["kind"] == "recording" for a in res["artifacts"])


def test_quadruped_gait_on_a_stored_go1(stack: Stack) -> None:
    with stack.client() as c:
        if not any(r["name"] == "go1" for r in c.robots()["items"]):
            c.add_robot("go1", _urdf("go1", legs="auto"))
    res = _run(stack, {
        "robot": "go1",
        "problem": {"kind": "quadruped_gait", "depth": 0.28, "stroke_center": 0.0,
                    "speed": 0.1, "samples_per_cycle": 32},
        "optimizer": {"kind": "hka", "params": {"n_samples": 8, "n_best": 3}},
        "budget": {"generations": 2}, "seed": 1, "record": False,
    })
    base = _baselines(res)["default_step"]
    assert base["reachable"] == 1.0 and base["energy_per_cycle_J"] > 0
    assert res["summary"]["extras"]["legs"] == {"FL": "FL", "FR": "FR", "RL": "RL", "RR": "RR"}


def test_hexapod_workspace_on_a_urdf_hexapod(stack: Stack) -> None:
    from legcore.problems.hexapod_workspace_robot import HexapodGeometry, hexapod_urdf

    g = HexapodGeometry(link_lengths=(0.03, 0.08, 0.12))
    res = _run(stack, {
        "robot": {"kind": "urdf", "name": "hexapod", "urdf": hexapod_urdf(g), "legs": "auto"},
        "problem": {"kind": "hexapod_workspace", "paper_baselines": False,
                    "pose_x_extent": 0.04, "pose_xy_step": 0.004, "pose_y_extent": 0.04,
                    "pose_yaw_step": math.pi / 12},
        "optimizer": {"kind": "moead", "params": {"n_subproblems": 30}},
        "budget": {"generations": 3}, "seed": 1, "record": False,
    })
    ex = res["summary"]["extras"]
    assert ex["legs"] == ["L1", "L3", "L5"]
    assert sum(ex["pose_workspace"]["n_reachable"]) > 0


def test_plugin_study_validated_and_run_by_the_service(stack: Stack) -> None:
    err = _422(stack, {"problem": {"kind": "holding_torque", "tolerance": -1.0}})
    assert err["loc"] == ["body", "problem", "tolerance"]
    err = _422(stack, {"robot": "citedi_hexapod", "problem": {"kind": "holding_torque"}})
    assert err["loc"] == ["body", "robot"] and "holding_torque needs a serial" in err["msg"]
    res = _run(stack, {"problem": {"kind": "holding_torque"}, "budget": {"generations": 10},
                       "seed": 1})
    assert res["metrics"]["tau_sq"] > 0 and "home" in _baselines(res)
    with stack.client() as c:
        jobs = c.jobs(limit=100)["items"]
        assert all(j["status"] in TERMINAL for j in jobs)


def test_legopt_studies_cli(stack: Stack) -> None:
    env = {**stack.env, "LEGOPT_API_URL": stack.url, "LEGOPT_API_KEY": stack.key,
           "COLUMNS": "200"}
    run: Callable[..., subprocess.CompletedProcess[str]] = lambda *a: subprocess.run(  # noqa: E731
        [sys.executable, "-m", "services.cli", "studies", *a], env=env, cwd=ROOT,
        capture_output=True, text=True, timeout=120)
    out = run()
    assert out.returncode == 0, out.stderr
    assert "holding_torque" in out.stdout and "quadruped_gait" in out.stdout
    out = run("hexapod_workspace", "--robot", "go1")
    assert out.returncode == 0, out.stderr
    why = "hexapod_workspace needs 6 legs of 3 joints; robot go1 has 4 legs"
    assert why in " ".join(out.stdout.split())
    assert "pose_xy_step" in out.stdout
    out = run("no_such_kind")
    assert out.returncode == 2 and "kind" in out.stdout + out.stderr
