"""The dashboard's other pages in a real Chromium against the real embedded service: an
infeasible job's verdict in red (jobs table and job page) and a feasible one's in green, the gap
to the physical minimum, a sweep and its cell table, the robots page and the API docs (Swagger
UI), CSVs downloaded and read back. Every request any page makes is recorded and must stay on
this server. Each page is screenshotted (``shots``). Jobs, fronts and the viewer:
``test_dashboard_browser.py``.

The tests share one logged-in page (a module fixture): run the module whole, in order."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.integration.stack import Stack
from tests.web.dashboard_session import (
    FEASIBLE_GAIT,
    GREEN,
    INFEASIBLE_GAIT,
    MIN_TIME,
    RED,
    SWEEP,
    assert_dashboard_csp,
    assert_nothing_left_this_server,
    download,
)

pytestmark = pytest.mark.integration


def _color(page: Any, selector: str, prop: str = "color") -> str:
    return str(page.eval_on_selector(selector, f"el => getComputedStyle(el).{prop}"))


def test_the_verdict_is_red_or_green(page: Any, stack: Stack, shots: Path) -> None:
    """An infeasible job is a red "infeasible" badge in the jobs table (never the green
    "succeeded"), and its page shows the verdict first, in red, with each violated constraint
    and by how much; a feasible job's page says so in green."""
    with stack.client() as c:
        bad_id = c.submit(INFEASIBLE_GAIT)["id"]
        good_id = c.submit(FEASIBLE_GAIT)["id"]
        fast_id = c.submit(MIN_TIME)["id"]
    bad = stack.wait_for(bad_id, lambda j: j["status"] == "succeeded")
    good = stack.wait_for(good_id, lambda j: j["status"] == "succeeded")
    assert bad["feasible"] is False and good["feasible"] is True, (bad, good)

    page.goto(f"{stack.url}/#/jobs")
    row = f"tr[data-job='{bad_id}'][data-status='succeeded'][data-verdict='infeasible']"
    page.wait_for_selector(f"{row} .badge.infeasible")
    assert page.inner_text(f"{row} .badge") == "infeasible"
    assert _color(page, f"{row} .badge", "backgroundColor") == RED
    ok_row = f"tr[data-job='{good_id}'][data-verdict='feasible']"
    assert _color(page, f"{ok_row} .badge.succeeded") == GREEN
    page.select_option("#verdict-filter", "false")  # the verdict filter: only infeasible jobs
    page.wait_for_selector(f"tr[data-job='{good_id}']", state="detached")
    assert page.locator(f"tr[data-job='{bad_id}']").count() == 1
    page.screenshot(path=shots / "jobs-infeasible.png", full_page=True)

    # the search box: one or two letters are not sent (no index answers them: the API says
    # 422), a hint shows and the list stays as it is; a job's id finds that job
    page.select_option("#verdict-filter", "")
    page.wait_for_selector(f"tr[data-job='{good_id}']")
    page.fill("#job-search", "ga")
    page.wait_for_selector("#search-hint")
    page.wait_for_timeout(700)  # past the search box's 300 ms pause
    assert page.locator("#jobs-table tbody tr").count() == 3
    assert page.inner_text("#jobs-count") == "1–3 of 3"
    page.fill("#job-search", f"ga {bad_id}")
    page.wait_for_selector("#search-hint", state="hidden")
    page.wait_for_selector(f"tr[data-job='{good_id}']", state="detached")
    assert page.locator("#jobs-table tbody tr").count() == 1
    assert page.inner_text("#jobs-count") == "1–1 of 1"
    page.fill("#job-search", "")
    page.wait_for_selector(f"tr[data-job='{good_id}']")

    page.goto(f"{stack.url}/#/job/{bad_id}")
    # the card is drawn from the job, then again once its result (task, gap) is loaded: wait
    # for that last drawing before reading its colours
    page.wait_for_selector("#verdict.infeasible #gap")
    assert page.inner_text("#verdict h2").startswith("Infeasible")
    assert _color(page, "#verdict h2") == RED
    assert _color(page, "#verdict", "borderLeftColor") == RED
    margin = page.inner_text("#violations li[data-constraint='stability_margin_mm']")
    amount = next(v for v in bad["violations"] if v["constraint"] == "stability_margin_mm")
    assert "over its limit by" in margin and f"{amount['amount']:.4g}" in margin, margin
    page.wait_for_selector("#metrics-table")  # the result is drawn below the verdict
    with stack.client() as c:
        task = c.result(bad_id)["task"]
    assert task["params"]["stability_margin"] == 0.02
    if task["rules"] or task["preset"]:  # the rules the robot-relative values came from
        page.wait_for_selector("#verdict #task")
        for field in task["rules"]:
            assert page.locator(f"#task li[data-field='{field}']").count() == 1
    page.screenshot(path=shots / "job-infeasible.png", full_page=True)

    page.goto(f"{stack.url}/#/job/{good_id}")
    page.wait_for_selector("#verdict.feasible #gap")
    assert page.inner_text("#verdict h2").startswith("Feasible")
    assert _color(page, "#verdict h2") == GREEN
    assert page.locator("#violations").count() == 0
    # a study without an exact reference says so (issue 19)
    page.wait_for_selector("#verdict #gap[data-gap='none']")
    assert page.inner_text("#gap").startswith("No optimality gap")
    page.screenshot(path=shots / "job-feasible.png", full_page=True)

    # the minimum time's gap to the physical minimum (TOPP-RA), and its marked point
    stack.wait_for(fast_id, lambda j: j["status"] == "succeeded")
    with stack.client() as c:
        gap = c.result(fast_id)["gap"]
    assert gap["kind"] == "physical minimum" and gap["pct"] >= 0.0, gap
    page.goto(f"{stack.url}/#/job/{fast_id}")
    page.wait_for_selector("#verdict #gap[data-gap='reference']")
    text = page.inner_text("#gap")
    assert text.startswith("Gap to the physical minimum: +") and "TOPP-RA" in text, text
    page.wait_for_selector("#front-table tr[data-baseline='time_optimal']")
    page.screenshot(path=shots / "job-gap.png", full_page=True)
    assert not page.legopt_errors, page.legopt_errors


def test_sweep_cells_robots_and_docs(page: Any, stack: Stack, shots: Path, tmp_path: Path) -> None:
    with stack.client() as c:
        sweep_id = c.sweep(SWEEP)["id"]
    page.goto(f"{stack.url}/#/sweeps")
    row = page.wait_for_selector(f"#sweeps-table tr[data-sweep='{sweep_id}']")
    page.screenshot(path=shots / "sweeps.png", full_page=True)
    row.click()
    page.wait_for_selector("#cells-table tbody tr[data-cell-row='1']")
    # the page polls until the sweep is finished, then draws its cells and fronts once more
    # (the summary line says "finished" before those are drawn: wait for the plot's state)
    page.wait_for_selector("#overlay-plot[data-sweep-state='finished']", timeout=120_000)
    assert "finished" in page.inner_text("main > p.muted")
    page.wait_for_selector("#cells-table td.best")
    page.wait_for_selector("#overlay-plot .legendtext")
    legend = page.locator("#overlay-plot .legendtext").all_text_contents()
    assert legend == ["cell 0: pop_size=24", "cell 1: pop_size=32"], legend
    page.screenshot(path=shots / "sweep.png", full_page=True)
    cells = download(page, "[data-export=cells-csv]", tmp_path / "cells.csv")
    assert [r["optimizer.params.pop_size"] for r in cells] == ["24", "32"]
    assert all(r["succeeded"] == "2" and float(r["time_mean [s]"]) > 0 for r in cells)
    jobs = download(page, "[data-export=sweep-jobs-csv]", tmp_path / "sweep-jobs.csv")
    assert sorted(r["cell"] for r in jobs) == ["0", "0", "1", "1"], jobs  # beside its cells

    page.goto(f"{stack.url}/#/robots")
    page.click("#robots-table tr[data-robot='articulated_5dof']")
    page.wait_for_selector("#joints-table tbody tr")
    assert page.locator("#joints-table tbody tr").count() == 5
    page.wait_for_selector("#studies-table tbody tr")
    page.screenshot(path=shots / "robots.png", full_page=True)

    page.goto(f"{stack.url}/docs")  # -> /api/v1/docs, Swagger UI from local files
    page.wait_for_selector(".swagger-ui .opblock")
    page.screenshot(path=shots / "api-docs.png")
    assert not page.legopt_errors, page.legopt_errors


def test_nothing_leaves_this_server(page: Any, stack: Stack) -> None:
    """Every request of every page the tests above visited (dashboard pages, Swagger UI) went
    to this server; the pages' Content-Security-Policy is the one services/web sends."""
    visited = {
        "/", "/static/js/pages/jobs.js", "/api/v1/dashboard/jobs",  # the jobs page
        "/api/v1/sweeps", "/api/v1/robots",
        "/api/v1/docs", "/static/vendor/swagger-ui/swagger-ui-bundle.js", "/api/v1/openapi.json",
    }  # fmt: skip
    assert_nothing_left_this_server(page, stack, visited)
    assert_dashboard_csp(page)
    assert page.legopt_documents["/api/v1/docs"]["x-content-type-options"] == "nosniff"
    docs_csp = page.legopt_documents["/api/v1/docs"]["content-security-policy"]  # Swagger UI
    assert "default-src 'self'" in docs_csp and "connect-src 'self'" in docs_csp, docs_csp
