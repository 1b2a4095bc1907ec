"""The dashboard in a real Chromium against the real embedded service: log in with the key,
submit a job from the page and another over the API, watch them finish, open a front, click a
point and see its joint plot and the Rerun viewer load that point's recording, open a sweep and
its cell table, download CSVs and read them back. Each page is screenshotted (``shots``)."""

from __future__ import annotations

import csv
import time
from pathlib import Path
from typing import Any

import pytest

from tests.integration.stack import Stack

pytestmark = pytest.mark.integration

TWO_OBJECTIVES: dict[str, Any] = {
    "name": "browser front",
    "problem": {"kind": "path_tracking", "objective": "energy_time"},
    "optimizer": {"kind": "nsga2", "params": {"pop_size": 24}},
    "budget": {"generations": 10},
    "seed": 1,
}
SWEEP: dict[str, Any] = {
    "base": {**TWO_OBJECTIVES, "name": "browser sweep", "record": False},
    "grid": {"optimizer.params.pop_size": [24, 32]},
    "seeds": [1, 2],
}
TIMEOUT_MS = 60_000


@pytest.fixture(scope="module")
def page(browser: Any, stack: Stack) -> Any:
    """A logged-in page of the dashboard (its console errors are collected in
    ``page.legopt_errors``)."""
    context = browser.new_context(viewport={"width": 1400, "height": 1000}, accept_downloads=True)
    pg = context.new_page()
    pg.set_default_timeout(TIMEOUT_MS)
    pg.legopt_errors = []
    pg.on("pageerror", lambda exc: pg.legopt_errors.append(str(exc)))
    pg.goto(stack.url + "/")
    pg.wait_for_selector("#login[open]")
    pg.fill("#login-key", "not-a-key")
    pg.click("#login-submit")
    pg.wait_for_selector("#login-error:text('not valid')")
    pg.fill("#login-key", stack.key)
    pg.click("#login-submit")
    pg.wait_for_selector("#who:text('it')")
    yield pg
    context.close()


def _download(page: Any, selector: str, to: Path) -> list[dict[str, str]]:
    with page.expect_download() as info:
        page.click(selector)
    info.value.save_as(to)
    with open(to, newline="") as f:
        return list(csv.DictReader(f))


def test_jobs_front_point_replay_and_csv(
    page: Any, stack: Stack, shots: Path, tmp_path: Path
) -> None:
    with stack.client() as c:
        job_id = c.submit(TWO_OBJECTIVES)["id"]
    # a job submitted from the page
    page.click("text=New job")
    page.select_option("#new-kind", "path_tracking")
    page.fill("#new-generations", "3")
    page.click("#submit-example")
    page.wait_for_selector("#new-job p:text('queued')")
    page.wait_for_function("document.querySelectorAll('#jobs-table tbody tr').length == 2")
    # live progress: the table polls until both are finished
    page.wait_for_selector(f"tr[data-job='{job_id}'][data-status='succeeded']", timeout=120_000)
    page.wait_for_function(
        "[...document.querySelectorAll('#jobs-table tbody tr')]"
        ".every(r => r.dataset.status === 'succeeded')",
        timeout=120_000,
    )
    page.screenshot(path=shots / "jobs.png", full_page=True)
    rows = _download(page, "[data-export=csv]", tmp_path / "jobs.csv")
    assert {r["id"] for r in rows} >= {job_id} and len(rows) == 2
    assert next(r for r in rows if r["id"] == job_id)["name"] == "browser front"

    # the job page: convergence, the front, the optimum's motion and recording
    recordings: list[tuple[str, int]] = []
    page.on(
        "response",
        lambda r: recordings.append((r.url, r.status)) if "/recording" in r.url else None,
    )
    page.click(f"tr[data-job='{job_id}'] a")
    page.wait_for_selector("#front-plot .scatterlayer .point")
    page.wait_for_selector("#front-table tbody tr[data-point]")
    axis_titles = page.locator("#front-plot .g-xtitle, #front-plot .g-ytitle").all_text_contents()
    assert [t[-3:] for t in axis_titles] == ["[s]", "[J]"], axis_titles
    page.wait_for_selector("#convergence .scatterlayer .trace")
    # what the optimiser earned (issue 11): one row per objective, initial best → optimum
    page.wait_for_selector("#earned table tbody tr")
    assert page.locator("#earned table tbody tr").count() == 2
    assert "initial population" in page.locator("#earned thead").inner_text()
    # the paper's own numbers beside ours (seed 004's time law, examples/papers)
    assert "paper" in page.locator("#metrics-table thead").inner_text()

    # click a front point on the plot: its row is selected, its joints plotted, its recording
    # fetched from /pareto/{k}/recording and handed to the viewer
    last = page.locator("#front-table tbody tr[data-point]").last
    k = last.get_attribute("data-point")
    last.click()
    page.wait_for_selector(f"#front-table tr.selected[data-point='{k}']")
    page.wait_for_selector("#motion h2:text('front point " + str(k) + "')")
    page.wait_for_selector("#joint-plot .scatterlayer .trace")
    page.click("#motion button[data-signal=tau]")
    page.wait_for_function(
        "(document.querySelector('#joint-plot .g-ytitle') || {}).textContent"
        " === 'joint torque [N·m]'"
    )
    # a point of the plot (the first one that is not the selected point): plotly picks the
    # point nearest the click, which is the point clicked or one drawn on top of it
    points = page.locator("#front-plot .scatterlayer .trace").first.locator(".point")
    points.nth(0 if k != "0" else 1).click(force=True)
    page.wait_for_function(
        f"(() => {{ const r = document.querySelector('#front-table tr.selected');"
        f" return r && r.dataset.point !== '{k}'; }})()"
    )
    picked = page.locator("#front-table tr.selected").get_attribute("data-point")
    page.wait_for_function(
        f"document.querySelector('#motion h2').textContent.includes('front point {picked}')"
    )
    viewer = page.frame_locator("iframe.viewer")
    viewer.locator("canvas#viewer-canvas").wait_for(state="attached")
    page.wait_for_function(
        "() => { const f = document.querySelector('iframe.viewer');"
        " return f && f.contentDocument && f.contentDocument.body.dataset.loaded"
        f" && f.contentDocument.body.dataset.loaded.includes('front point {picked} '); }}",
        timeout=120_000,
    )
    wanted = f"/api/v1/jobs/{job_id}/pareto/{picked}/recording"
    assert any(url.endswith(wanted) and status == 200 for url, status in recordings), recordings
    time.sleep(2)  # let the viewer draw for the screenshot
    page.screenshot(path=shots / "job.png", full_page=True)
    front = _download(page, "[data-export=front-csv]", tmp_path / "front.csv")
    assert list(front[0])[:3] == ["index", "time", "energy"] and front
    assert not [e for e in page.legopt_errors if "viewer" not in e.lower()], page.legopt_errors


def test_sweep_cells_robots_and_docs(page: Any, stack: Stack, shots: Path, tmp_path: Path) -> None:
    with stack.client() as c:
        sweep_id = c.sweep(SWEEP)["id"]
    page.goto(f"{stack.url}/#/sweeps")
    page.wait_for_selector(f"#sweeps-table tr[data-sweep='{sweep_id}']").click()
    page.wait_for_selector("#cells-table tbody tr[data-cell-row='1']")
    deadline = time.monotonic() + 120
    while "finished" not in page.inner_text("main > p.muted"):
        assert time.monotonic() < deadline, page.inner_text("main")
        time.sleep(1)
    page.wait_for_selector("#cells-table td.best")
    page.wait_for_selector("#overlay-plot .legendtext")
    legend = page.locator("#overlay-plot .legendtext").all_text_contents()
    assert legend == ["cell 0: pop_size=24", "cell 1: pop_size=32"], legend
    page.screenshot(path=shots / "sweep.png", full_page=True)
    cells = _download(page, "[data-export=cells-csv]", tmp_path / "cells.csv")
    assert [r["optimizer.params.pop_size"] for r in cells] == ["24", "32"]
    assert all(r["succeeded"] == "2" and float(r["time_mean"]) > 0 for r in cells)

    page.goto(f"{stack.url}/#/robots")
    page.click("#robots-table tr[data-robot='articulated_5dof']")
    page.wait_for_selector("#joints-table tbody tr")
    assert page.locator("#joints-table tbody tr").count() == 5
    page.wait_for_selector("#studies-table tbody tr")
    page.screenshot(path=shots / "robots.png", full_page=True)

    page.goto(f"{stack.url}/docs")  # -> /api/v1/docs, Swagger UI from local files
    page.wait_for_selector(".swagger-ui .opblock")
    page.screenshot(path=shots / "api-docs.png")
