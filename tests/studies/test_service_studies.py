"""Issue 9 through the real service (API + worker processes, embedded stack): one real robot per
legged study kind, the capability refusal as a 422 at ``robot``, ``GET /studies`` and
``legopt studies``, and a study kind from a plug-in package.

Each run's stored result is checked physically, as the ``legcore.run`` matrix is
(:mod:`tests.studies.checks`): its decision vectors (optimum and baselines) decoded again here
reproduce the stored metrics, and the feet are where they must be by Pinocchio FK (1e-6 m),
the energies at least the gravity bound.

The plug-in (``examples/plugin_study``) is really installed — ``pip install --no-deps
--no-build-isolation --target`` a temporary directory, its build backend (setuptools, as its
``pyproject.toml`` requires) taken from the venv, so nothing is fetched — and that directory is
put on the service processes' ``PYTHONPATH``: the API and the workers find the kind through its
``legopt.studies`` entry point exactly as in a venv, while the shared environment of the test
run stays untouched (nothing to uninstall: the directory is removed). Beside it, a broken
plug-in (its module imports a package that is not installed) is on the same path: it is
reported by ``GET /studies`` and the registry, and nothing else notices.
"""

from __future__ import annotations

import importlib.metadata
import json
import math
import os
import shutil
import subprocess
import sys
import tomllib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from packaging.requirements import Requirement

from legcore.robots import LeggedRobot, build_any_robot
from legcore.runner import prepare
from services.client import TERMINAL, ApiError
from tests.integration.stack import ROOT, Stack, embedded_stack
from tests.robot_files import ERD_URDF, erd_robots_dir, require_erd
from tests.studies.checks import (
    check_gait,
    check_hexapod,
    check_swing,
    stored_baselines,
    stored_best,
    stored_solution,
)

pytestmark = pytest.mark.integration

PLUGIN = ROOT / "examples" / "plugin_study"
#: A plug-in whose entry point fails to import: its module needs a package that is not there.
BROKEN_KIND = "broken_kind"
BROKEN_ERROR = "ModuleNotFoundError: No module named 'lab_only_dependency'"


def _missing_build_requirements() -> list[str]:
    """The plug-in's ``build-system.requires`` that the venv does not satisfy (pip builds it
    with ``--no-build-isolation``: from the venv, offline)."""
    requires = tomllib.loads((PLUGIN / "pyproject.toml").read_text())["build-system"]["requires"]
    missing = []
    for text in requires:
        req = Requirement(text)
        try:
            have = importlib.metadata.version(req.name)
        except importlib.metadata.PackageNotFoundError:
            missing.append(f"{text} (not installed)")
            continue
        if not req.specifier.contains(have, prereleases=True):
            missing.append(f"{text} (the venv has {have})")
    return missing


def _install_plugin(site: Path, tmp: Path) -> str | None:
    """pip-install the example plug-in into ``site``, offline; None, or why it could not."""
    missing = _missing_build_requirements()
    if missing:
        return (f"the example plug-in's build backend is not in the venv: {missing}; pip builds "
                "it with --no-build-isolation (offline), so requirements.lock must pin it")
    src = tmp / "plugin_src"
    shutil.copytree(PLUGIN, src, ignore=shutil.ignore_patterns("build", "*.egg-info",
                                                               "__pycache__"))
    out = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--no-deps", "--no-build-isolation",
         "--check-build-dependencies", "--no-index", "--disable-pip-version-check", "--quiet",
         "--target", str(site), str(src)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    if out.returncode != 0:
        return f"pip install of the example plug-in failed:\n{out.stderr}"
    assert list(site.glob("legopt_example_study-*.dist-info/entry_points.txt"))
    return None


def _install_broken_plugin(site: Path) -> None:
    """What pip leaves for a plug-in distribution (its module and its ``.dist-info`` with the
    ``legopt.studies`` entry point), whose module fails to import."""
    site.mkdir(exist_ok=True)
    (site / "legopt_broken_study.py").write_text(
        "import lab_only_dependency  # noqa: F401  (a package the lab forgot to list)\n")
    info = site / "legopt_broken_study-0.1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(
        "Metadata-Version: 2.1\nName: legopt-broken-study\nVersion: 0.1.0\n")
    (info / "entry_points.txt").write_text(
        f"[legopt.studies]\n{BROKEN_KIND} = legopt_broken_study:STUDY\n")
    (info / "RECORD").write_text("")


@pytest.fixture(scope="module")
def stack(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Stack]:
    """The service with the plug-ins' directory on its path. If the example plug-in could not
    be installed, the tests that need it fail saying why (``plugin``); the others still run."""
    global _PLUGIN_PROBLEM
    require_erd()
    tmp = tmp_path_factory.mktemp("studies-stack")
    site = tmp / "site"
    _PLUGIN_PROBLEM = _install_plugin(site, tmp)
    _install_broken_plugin(site)
    with embedded_stack(tmp, {"PYTHONPATH": os.pathsep.join([str(site), str(ROOT)])}) as st:
        yield st


_PLUGIN_PROBLEM: str | None = None


@pytest.fixture
def plugin(stack: Stack) -> None:
    """The example plug-in is installed in ``stack`` (fails, saying why, otherwise)."""
    if _PLUGIN_PROBLEM is not None:
        pytest.fail(_PLUGIN_PROBLEM)


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


@pytest.mark.usefixtures("plugin")
def test_studies_listing_names_what_each_kind_needs(stack: Stack) -> None:
    with stack.client() as c:
        c.add_robot("go1", _urdf("go1", legs="auto"))
        data = c.get("/studies")
    kinds = {it["kind"]: it for it in data["items"]}
    assert {"swing_energy", "quadruped_gait", "hexapod_workspace", "holding_torque"} <= set(kinds)
    assert data["plugin_errors"] == {BROKEN_KIND: BROKEN_ERROR}  # reported, not a crash
    assert BROKEN_KIND not in kinds and data["stored_robots_checked"] == 1
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
    spec: dict[str, Any] = {
        "robot": _urdf("solo12", legs="auto"),
        "problem": {"kind": "swing_energy", "leg": "FL", "foot_start": start, "foot_end": end,
                    "exact_ends": True, "T": 1.0, "dt": 0.02,
                    "baselines": ["calderon2008_parabolic"]},
        "optimizer": {"kind": "ga", "params": {"pop_size": 16, "fitness": "window",
                                               "penalty": None}},
        "budget": {"generations": 3}, "seed": 1,
    }
    res = _run(stack, spec)
    ex = res["summary"]["extras"]
    assert ex["leg"] == "solo12.FL"
    assert max(abs(a - b) for a, b in zip(ex["foot_start"] + ex["foot_end"], start + end,
                                          strict=True)) < 1e-6
    assert any(a["kind"] == "recording" for a in res["artifacts"])
    # the stored optimum and baseline: feet at the ends by Pinocchio, energy ≥ the bound
    problem = prepare(spec).problem
    robot = build_any_robot(spec["robot"])
    assert isinstance(robot, LeggedRobot)
    for stored in (stored_best(res), stored_baselines(res)["calderon2008_parabolic"]):
        check_swing(robot, "FL", stored_solution(problem, stored), start, end)


def test_quadruped_gait_on_a_stored_go1(stack: Stack) -> None:
    with stack.client() as c:
        if not any(r["name"] == "go1" for r in c.robots()["items"]):
            c.add_robot("go1", _urdf("go1", legs="auto"))
    spec: dict[str, Any] = {
        "robot": "go1",
        "problem": {"kind": "quadruped_gait", "depth": 0.28, "stroke_center": 0.0,
                    "speed": 0.1, "samples_per_cycle": 32},
        "optimizer": {"kind": "hka", "params": {"n_samples": 8, "n_best": 3}},
        "budget": {"generations": 2}, "seed": 1, "record": False,
    }
    res = _run(stack, spec)
    base = _baselines(res)["default_step"]
    assert base["reachable"] == 1.0 and base["energy_per_cycle_J"] > 0
    assert res["summary"]["extras"]["legs"] == {"FL": "FL", "FR": "FR", "RL": "RL", "RR": "RR"}
    # decoded here with the stored robot's file: every foot on its target by Pinocchio, the
    # stance feet on the ground, each leg's energy ≥ its bound
    local = {**spec, "robot": _urdf("go1", legs="auto")}
    problem = prepare(local).problem
    robot = build_any_robot(local["robot"])
    assert isinstance(robot, LeggedRobot)
    sols = [stored_solution(problem, stored_baselines(res)["default_step"])]
    if res["metrics"]["reachable"] == 1.0:
        sols.append(stored_solution(problem, stored_best(res)))
    for sol in sols:
        check_gait(robot, sol)


def test_hexapod_workspace_on_a_urdf_hexapod(stack: Stack) -> None:
    from legcore.studies.hexapod_workspace.robot import HexapodGeometry, hexapod_urdf

    g = HexapodGeometry(link_lengths=(0.03, 0.08, 0.12))
    spec: dict[str, Any] = {
        "robot": {"kind": "urdf", "name": "hexapod", "urdf": hexapod_urdf(g), "legs": "auto"},
        "problem": {"kind": "hexapod_workspace", "paper_baselines": False,
                    "pose_x_extent": 0.04, "pose_xy_step": 0.004, "pose_y_extent": 0.04,
                    "pose_yaw_step": math.pi / 12},
        "optimizer": {"kind": "moead", "params": {"n_subproblems": 30}},
        "budget": {"generations": 3}, "seed": 1, "record": False,
    }
    res = _run(stack, spec)
    ex = res["summary"]["extras"]
    assert ex["legs"] == ["L1", "L3", "L5"]
    pw = ex["pose_workspace"]
    assert sum(pw["n_reachable"]) > 0
    # each yaw's mask has as many reachable cells as it reports, and the start pose is one
    assert [sum(row.count("1") for row in mask) for mask in pw["masks"]] == pw["n_reachable"]
    i0 = int(np.argmin(np.abs(pw["yaw"])))
    assert pw["masks"][i0][len(pw["y"]) // 2][len(pw["x"]) // 2] == "1"
    # the stored optimum and baselines decoded: the stance feet stay put (Pinocchio, 1e-6 m)
    problem = prepare(spec).problem
    stored = [stored_best(res), *stored_baselines(res).values()]
    assert all(check_hexapod(problem, stored_solution(problem, s)) for s in stored)


@pytest.mark.usefixtures("plugin")
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


def test_a_plugin_that_fails_to_import_is_reported(stack: Stack) -> None:
    """The broken plug-in on the service's path: the registry keeps its import error by kind
    (a fresh process, as a worker starts), ``GET /studies`` reports it (the listing test) and
    ``legopt studies`` prints it; the kind is not offered, and the service runs the others."""
    out = subprocess.run(
        [sys.executable, "-c", "import json; from legcore.studies.registry import "
         "plugin_errors, studies; print(json.dumps([plugin_errors(), sorted(studies())]))"],
        env=stack.env, cwd=ROOT, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    errors, kinds = json.loads(out.stdout.strip().splitlines()[-1])
    assert errors == {BROKEN_KIND: BROKEN_ERROR}
    assert BROKEN_KIND not in kinds
    assert ("holding_torque" in kinds) == (_PLUGIN_PROBLEM is None)  # the working one loads
    assert f"study plug-in not loaded: {BROKEN_ERROR}" in out.stderr  # logged as a warning
    err = _422(stack, {"problem": {"kind": BROKEN_KIND}})
    assert err["loc"][:2] == ["body", "problem"] and BROKEN_KIND in err["msg"]
    env = {**stack.env, "LEGOPT_API_URL": stack.url, "LEGOPT_API_KEY": stack.key,
           "COLUMNS": "200"}
    cli = subprocess.run([sys.executable, "-m", "services.cli", "studies"], env=env, cwd=ROOT,
                         capture_output=True, text=True, timeout=120)
    assert cli.returncode == 0, cli.stderr
    assert f"plug-in {BROKEN_KIND} not loaded: {BROKEN_ERROR}" in " ".join(cli.stdout.split())


@pytest.mark.usefixtures("plugin")
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


def test_a_job_of_a_broken_plugin_kind_says_why(stack: Stack) -> None:
    err = _422(stack, {"problem": {"kind": BROKEN_KIND}})
    assert "not loaded" in err["msg"] and "lab_only_dependency" in err["msg"], err
