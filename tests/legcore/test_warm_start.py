"""Issue 12, warm starts: the content-hash result cache, seed 000's GA baselines reused across
processes through it, the warm-up jobs and the service's cache environment."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

import legcore.studies.swing_energy.baselines as sb
from legcore.result_cache import cache_dir, cached, code_version, content_key
from legcore.runner import prepare
from legcore.studies.registry import STUDY_MODULES, studies
from legcore.warmup import warmup_spec
from services.store.settings import Settings

SMALL = {"problem": {"kind": "swing_energy", "baseline_generations": 2,
                     "baseline_pop_size": 8}}


def test_cached_computes_once_and_recovers(tmp_path: Path) -> None:
    calls: list[int] = []

    def compute() -> dict[str, Any]:
        calls.append(1)
        return {"x": [1.0, 2.0]}

    assert cached("k", compute, tmp_path) == {"x": [1.0, 2.0]}
    assert cached("k", compute, tmp_path) == {"x": [1.0, 2.0]}
    assert len(calls) == 1 and json.loads((tmp_path / "k.json").read_text()) == {"x": [1.0, 2.0]}
    (tmp_path / "k.json").write_text("{not json")  # a torn or foreign file: recomputed
    assert cached("k", compute, tmp_path) == {"x": [1.0, 2.0]} and len(calls) == 2
    assert not list(tmp_path.glob("*.tmp"))


def test_no_directory_no_io(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.delenv("LEGOPT_CACHE_DIR", raising=False)
    assert cache_dir() is None
    monkeypatch.setenv("LEGOPT_CACHE_DIR", str(tmp_path))
    assert cache_dir() == tmp_path / "results"


def test_content_key_changes_with_content() -> None:
    a = content_key("kind", [{"a": 1, "b": 2}, "x"])
    assert a == content_key("kind", [{"b": 2, "a": 1}, "x"])
    assert a != content_key("kind", [{"a": 1, "b": 3}, "x"])
    assert a.startswith("kind-") and len(code_version()) == 64


def test_ga_baselines_are_reused_across_processes(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setenv("LEGOPT_CACHE_DIR", str(tmp_path))
    problem = prepare(SMALL).problem
    first = sb.compute_baselines(problem)  # type: ignore[arg-type]
    assert len(list((tmp_path / "results").glob("swing_energy_ga_baseline-*.json"))) == 3

    def no_optimising(*_: Any, **__: Any) -> Any:
        raise AssertionError("the cached baseline was optimised again")

    monkeypatch.setattr(sb, "minimize", no_optimising)  # a new process: only the files remain
    again = sb.compute_baselines(prepare(SMALL).problem)  # type: ignore[arg-type]
    assert again.keys() == first.keys()
    for name, sol in first.items():
        np.testing.assert_array_equal(again[name].x, sol.x)
        assert again[name].metrics == sol.metrics
        assert again[name].extra.get("optimizer") == sol.extra.get("optimizer")


def test_ga_baseline_key_depends_on_the_parameters() -> None:
    p1 = prepare(SMALL).problem
    p2 = prepare({"problem": {**SMALL["problem"], "baseline_seed": 7}}).problem
    refs = dict.fromkeys(sb.MULTI_TERMS, 1.0)
    assert sb._ga_key(p1, "energy", refs) == sb._ga_key(prepare(SMALL).problem, "energy", refs)
    assert sb._ga_key(p1, "energy", refs) != sb._ga_key(p2, "energy", refs)
    assert sb._ga_key(p1, "energy", refs) != sb._ga_key(p1, "theta_total", refs)


@pytest.mark.parametrize("kind", sorted(STUDY_MODULES))
def test_warmup_specs_are_valid_tiny_jobs(kind: str) -> None:
    prepared = prepare(warmup_spec(kind, studies()[kind]))
    assert prepared.total_generations == 2  # the first generation and a steady-state one


def test_cache_environment(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    settings = Settings.from_env(env={}, data_dir=tmp_path)
    assert settings.cache_environment()["LEGOPT_CACHE_DIR"] == str(tmp_path / "cache")
    monkeypatch.setattr("services.store.settings.os.access", lambda *_: True)
    assert "NUMBA_CACHE_DIR" not in settings.cache_environment()  # numba's in-tree cache
    monkeypatch.setattr("services.store.settings.os.access", lambda *_: False)  # an image
    assert settings.cache_environment()["NUMBA_CACHE_DIR"] == str(tmp_path / "cache" / "numba")


def test_command_line_warm_up_includes_the_numerical_ik(monkeypatch: pytest.MonkeyPatch) -> None:
    """`python -m legcore.warmup` (the image build) ends with the numerical IK, which no study
    kind's default robot compiles; a worker's start-up warm-up (`warm_up()`) leaves it out."""
    import legcore.warmup as w

    ran: list[str | None] = []
    monkeypatch.setitem(w._EXTRA, "numeric_ik", lambda: ran.append("numeric_ik"))
    monkeypatch.setattr(  # a result whose extras the warm-up reads (the API's on-demand work)
        "legcore.runner.run",
        lambda spec: SimpleNamespace(extras=ran.append(spec["problem"]["kind"])),
    )
    kinds = [k for k in studies() if k in STUDY_MODULES]
    w.warm_up(verbose=False)
    assert ran == kinds
    ran.clear()
    assert w.main([]) == 0
    assert ran == [*kinds, "numeric_ik"]


def test_numeric_ik_warm_up_runs() -> None:
    from legcore.warmup import warm_numeric_ik

    warm_numeric_ik()  # the same kernels the numerical IK tests compile (shared cache)
