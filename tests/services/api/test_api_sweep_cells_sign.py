"""A sweep's cells show each quantity once, under its own name and in its own sign: a maximised
objective, which a result names as the optimiser minimises it (``neg_score``), is the column
``score`` with every seed's sample (n = seeds) and a finite, positive mean, whether the study
keyed its value by the quantity's own name or by the negated one; its best cell is the largest.
Before, the column was ``neg_score`` while its samples were kept under ``score``: n = 0, no
mean, for every swing_energy sweep."""

from __future__ import annotations

import math
from collections.abc import Iterator
from types import SimpleNamespace
from typing import Any

import pytest
from api_helpers import fresh_app

from services.api.sweep_cells import build_cells, job_values
from services.store.states import JobStatus

API = "/api/v1"
SCORE: dict[str, Any] = {
    "robot": "calderon_leg",
    "problem": {"kind": "swing_energy", "n_via": 3},
    "optimizer": {"kind": "ga", "params": {"pop_size": 12, "fitness": "negated"}},
    "budget": {"generations": 3},
    "record": False,
}


def _jobs(n: int) -> list[Any]:
    return [SimpleNamespace(id=f"job{i}", status=JobStatus.SUCCEEDED) for i in range(n)]


@pytest.mark.parametrize("stored_as", ["score", "neg_score"])
def test_a_maximised_objective_is_one_column_in_its_own_sign(stored_as: str) -> None:
    jobs = _jobs(4)  # two cells (a, b) of two seeds
    cell = {"job0": "a", "job1": "a", "job2": "b", "job3": "b"}
    scores = {"job0": 10.0, "job1": 12.0, "job2": 20.0, "job3": 22.0}
    sign = -1.0 if stored_as == "neg_score" else 1.0
    results = {
        j: ({"names": ["neg_score"], "values": {stored_as: sign * f}}, {"score": f, "f_d": 1.0})
        for j, f in scores.items()
    }

    def value(job: Any, path: str) -> Any:
        return cell[job.id] if path == "x" else int(job.id[-1]) % 2

    table = build_cells(jobs, value, ["x", "seed"], results, {})  # type: ignore[arg-type]
    assert table.stat_columns == ["score", "f_d"]  # the metric `score` is the objective's column
    assert table.objective_columns == ["score"] and table.objective_names == ["neg_score"]
    assert [c.samples["score"] for c in table.cells] == [[10.0, 12.0], [20.0, 22.0]]
    assert "neg_score" not in table.cells[0].samples
    assert table.best == {"score": 1}  # maximised: the largest mean


def test_job_values_keep_a_minimised_objective_as_it_is() -> None:
    shown, maximised, row = job_values(
        {"names": ["energy", "time"], "values": {"energy": 1.5, "time": 2.0}},
        {"energy_J": 1.5, "energy": 9.0, "bad": float("nan")},
    )
    assert (shown, maximised) == (["energy", "time"], [False, False])
    assert row == {"energy": 1.5, "time": 2.0, "energy_J": 1.5}  # the objective wins


@pytest.fixture(scope="module")
def score_sweep(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """Alice's swing_energy sweep (1 cell x 2 seeds) run to the end by the real executor."""
    from services.worker.execute import execute_job

    with fresh_app(tmp_path_factory.mktemp("cells-sign"), "alice") as app:
        body = {"base": SCORE, "seeds": [1, 2]}
        r = app.client.post(f"{API}/sweeps", json=body, headers=app.keys["alice"])
        assert r.status_code == 202, r.text
        for j in r.json()["job_ids"]:
            assert execute_job(j, app.settings).status == "succeeded"
        yield {"client": app.client, "alice": app.keys["alice"], "id": r.json()["id"],
               "jobs": r.json()["job_ids"]}  # fmt: skip


def test_a_swing_energy_sweeps_cells_have_every_seed_and_a_mean(
    score_sweep: dict[str, Any],
) -> None:
    client, alice = score_sweep["client"], score_sweep["alice"]
    r = client.get(f"{API}/sweeps/{score_sweep['id']}/cells", headers=alice)
    assert r.status_code == 200, r.text
    cells = r.json()
    names = [q["name"] for q in cells["stat_columns"]]
    assert names[0] == "score" and "neg_score" not in names and names.count("score") == 1
    assert cells["objective_names"] == ["score"]
    score = next(q for q in cells["stat_columns"] if q["name"] == "score")
    assert score["sense"] == "max"
    (cell,) = cells["cells"]
    stat = cell["stats"]["score"]
    assert stat["n"] == 2  # n = seeds
    assert stat["mean"] is not None and math.isfinite(stat["mean"]) and stat["mean"] > 0
    bests = [
        client.get(f"{API}/jobs/{j}/result", headers=alice).json()["metrics"]["score"]
        for j in score_sweep["jobs"]
    ]
    assert stat["mean"] == pytest.approx(sum(bests) / 2)
