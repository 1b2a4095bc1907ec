"""The researcher's workbench in Chromium (issue 21): a finished job's parameter importance
drawn per objective; deleting a job from its page (confirmed in a dialog; the jobs list no
longer has it, the API answers 404 and its artifact files are gone; a running job's delete
shows the API's 409); deleting a finished sweep from its page (its jobs and their files go
with it); the sweep page redrawn from the server's push while the sweep runs."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from services.client import ApiError
from tests.integration.stack import Stack

pytestmark = pytest.mark.integration

SPEC: dict[str, Any] = {
    "name": "browser workbench",
    "problem": {"kind": "path_tracking", "objective": "energy_time"},
    "optimizer": {"kind": "nsga2", "params": {"pop_size": 16}},
    "budget": {"generations": 4},
    "seed": 5,
    "record": False,
}
RUNNING: dict[str, Any] = {
    **SPEC,
    "name": "browser workbench running",
    "budget": {"generations": 3000},
}


def _finished_job(stack: Stack, spec: dict[str, Any]) -> str:
    with stack.client() as c:
        job_id = str(c.submit(spec)["id"])
    stack.wait_for(job_id, lambda j: j["status"] == "succeeded")
    return job_id


def _artifact_files(stack: Stack, job_id: str) -> list[Path]:
    """The files of the stack's artifact directory that belong to ``job_id``."""
    root = Path(stack.env["LEGOPT_ARTIFACT_DIR"])
    return [p for p in root.rglob("*") if p.is_file() and job_id in p.relative_to(root).as_posix()]


def test_parameter_importance_per_objective(page: Any, stack: Stack, shots: Path) -> None:
    job_id = _finished_job(stack, SPEC)
    with stack.client() as c:
        imp = c.get(f"/jobs/{job_id}/trials/importance")
        feasible = c.get(f"/jobs/{job_id}/trials", feasible="true", limit=1)["matched"]
    page.goto(f"{stack.url}/#/job/{job_id}")
    page.wait_for_selector(
        "#importance-body[data-state='ok'], #importance-body[data-state='few-feasible']"
    )
    state = page.get_attribute("#importance-body", "data-state")
    assert state == ("few-feasible" if feasible < 10 else "ok")
    assert "random-forest impurity importance, scikit-learn" in page.inner_text("#importance")
    assert "RandomForestRegressor" in page.inner_text("#importance-method")
    charts = page.locator(".importance-chart")
    assert charts.count() == len(imp["objectives"])
    for j, q in enumerate(imp["objectives"]):
        chart = f".importance-chart[data-objective='{q['name']}']"
        shares = [float(s) for s in page.eval_on_selector_all(
            f"{chart} .imp-row", "els => els.map(e => e.dataset.share)")]  # fmt: skip
        row = imp["importance"][j]
        if not any(row):
            assert page.get_attribute(chart, "data-flat") == "true"
            continue
        assert sum(shares) == pytest.approx(1.0, abs=1e-6)
        top = max(range(len(row)), key=lambda i: row[i])
        first = page.get_attribute(f"{chart} .imp-row:first-child", "data-variable")
        assert first == imp["variables"][top]["name"]  # largest first
    page.locator("#importance").screenshot(path=shots / "importance.png")
    assert not page.legopt_errors, page.legopt_errors


def test_delete_a_finished_job_from_its_page(page: Any, stack: Stack, shots: Path) -> None:
    job_id = _finished_job(stack, SPEC)
    before = _artifact_files(stack, job_id)
    assert before, "a finished job has artifact files (its result)"
    page.goto(f"{stack.url}/#/job/{job_id}")
    page.wait_for_selector("#metrics-table")  # the result is drawn
    page.click("button[data-action=delete]")
    page.wait_for_selector("#delete-dialog[open]")
    assert job_id[:8] in page.inner_text("#delete-message")
    page.click("#delete-cancel")  # "Keep it": nothing happens
    page.wait_for_selector("#delete-dialog:not([open])", state="attached")
    with stack.client() as c:
        assert c.job(job_id)["status"] == "succeeded"

    page.click("button[data-action=delete]")
    page.screenshot(path=shots / "delete-dialog.png")
    page.click("#delete-confirm")
    page.wait_for_function("() => location.hash === '#/jobs'")
    page.wait_for_selector("#jobs-table tbody tr[data-job]")
    assert page.locator(f"#jobs-table tr[data-job='{job_id}']").count() == 0
    with stack.client() as c, pytest.raises(ApiError) as gone:
        c.job(job_id)
    assert gone.value.status == 404
    assert _artifact_files(stack, job_id) == []
    assert not page.legopt_errors, page.legopt_errors


def test_deleting_a_running_job_shows_the_409(page: Any, stack: Stack) -> None:
    with stack.client() as c:
        job_id = c.submit(RUNNING)["id"]
    stack.wait_for(job_id, lambda j: j["status"] == "running")
    page.goto(f"{stack.url}/#/job/{job_id}")
    page.wait_for_selector(".badge.running")
    page.click("button[data-action=delete]")
    page.click("#delete-confirm")
    page.wait_for_selector("#delete-error[data-status='409']")
    assert "cancel it first" in page.inner_text("#delete-error")
    assert page.locator("#delete-dialog[open]").count() == 1  # the dialog stays, with the reason
    page.click("#delete-cancel")
    with stack.client() as c:
        assert c.job(job_id)["status"] == "running"
        c.cancel(job_id)
    stack.wait_for(job_id, lambda j: j["status"] == "cancelled")
    assert not page.legopt_errors, page.legopt_errors


def test_delete_a_finished_sweep_from_its_page(page: Any, stack: Stack, shots: Path) -> None:
    sweep = {"base": {**SPEC, "name": "browser sweep to delete"}, "seeds": [1, 2]}
    with stack.client() as c:
        created = c.sweep(sweep)
    sweep_id, job_ids = created["id"], created["job_ids"]
    for job_id in job_ids:
        stack.wait_for(job_id, lambda j: j["status"] == "succeeded")
    assert all(_artifact_files(stack, j) for j in job_ids)
    page.goto(f"{stack.url}/#/sweep/{sweep_id}")
    page.wait_for_selector("#overlay-plot[data-sweep-state='finished']")
    page.click("button[data-action=delete]")
    page.wait_for_selector("#delete-dialog[open]")
    message = page.inner_text("#delete-message")
    assert sweep_id[:8] in message and "2 jobs, finished" in message
    page.screenshot(path=shots / "delete-sweep-dialog.png")
    page.click("#delete-confirm")
    page.wait_for_function("() => location.hash === '#/sweeps'")
    page.wait_for_selector("#sweeps-table tbody")  # the list is drawn
    assert page.locator(f"#sweeps-table tr[data-sweep='{sweep_id}']").count() == 0
    with stack.client() as c:
        for path in (f"/sweeps/{sweep_id}", *[f"/jobs/{j}" for j in job_ids]):
            with pytest.raises(ApiError) as gone:
                c.get(path)
            assert gone.value.status == 404, path
    assert all(_artifact_files(stack, j) == [] for j in job_ids)
    assert not page.legopt_errors, page.legopt_errors


def test_the_sweep_page_updates_without_reload(page: Any, stack: Stack) -> None:
    sweep = {"base": {**RUNNING, "name": "browser live sweep"}, "seeds": [1, 2]}
    with stack.client() as c:
        created = c.sweep(sweep)
    sweep_id, first = created["id"], created["job_ids"][0]
    stack.wait_for(first, lambda j: j["status"] == "running" and j["generation"] >= 1)
    streams: list[str] = []
    page.on("request", lambda r: streams.append(r.url) if r.url.endswith("/events") else None)
    page.goto(f"{stack.url}/#/sweep/{sweep_id}")
    page.wait_for_selector("#sweep-progress[data-state='running']")
    page.wait_for_function("() => document.querySelector('#sweep-progress').dataset.generation > 0")
    generation = page.get_attribute("#sweep-progress", "data-generation")
    # pushed: the generations grow with no reload (the fallback poll would take 15 s)
    page.wait_for_function(
        f"() => document.querySelector('#sweep-progress').dataset.generation !== {generation!r}",
        timeout=10_000,
    )
    assert any(f"/sweeps/{sweep_id}/events" in u for u in streams)
    with stack.client() as c:
        c.cancel_sweep(sweep_id)
    page.wait_for_selector("#overlay-plot[data-sweep-state='finished']")
    page.wait_for_selector("#sweep-progress[data-state='finished']")
    assert "2 of 2 jobs finished" in page.inner_text("#sweep-progress")
    assert not page.legopt_errors, page.legopt_errors
