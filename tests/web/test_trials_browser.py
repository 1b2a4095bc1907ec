"""Every evaluated solution explorable in Chromium (issue 21, item 1): on a finished job's
page the trial table lists every trial, filters (infeasible only, a value range) and sorts it;
the parallel-coordinates plot draws one line per trial; clicking a trial that is not on the
front opens its motion and hands its recording to the viewer."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.integration.stack import Stack
from tests.web.dashboard_session import THREE_OBJECTIVES

pytestmark = pytest.mark.integration

SPEC: dict[str, Any] = {
    "name": "browser trials",
    "problem": {"kind": "path_tracking", "objective": "energy_time"},
    "optimizer": {"kind": "nsga2", "params": {"pop_size": 16}},
    "budget": {"generations": 4},
    "seed": 3,
    "record": False,
}


def test_trial_table_parallel_coordinates_and_a_trials_motion(
    page: Any, stack: Stack, shots: Path
) -> None:
    with stack.client() as c:
        job_id = c.submit(SPEC)["id"]
    stack.wait_for(job_id, lambda j: j["status"] == "succeeded")
    with stack.client() as c:
        trials = c.get(f"/jobs/{job_id}/trials?limit=1000")
        front = c.get(f"/jobs/{job_id}/front")
    stored = trials["stored"]
    assert stored > 16
    page.goto(f"{stack.url}/#/job/{job_id}")
    page.wait_for_selector("#trial-table tbody tr[data-trial]")
    assert f"{stored} of {stored} trials" in page.locator("#trial-info").inner_text()
    page.wait_for_selector("#trial-parallel svg .pc-line")
    lines = page.locator("#trial-parallel .pc-line").count()
    assert lines == stored  # fewer than the plot's sample size: every trial is a line

    # only the infeasible ones, sorted by the first objective, largest first
    infeasible = [r for r in trials["items"] if not r["feasible"]]
    page.select_option("#trial-feasible", "false")
    info = "document.querySelector('#trial-info').textContent"
    page.wait_for_function(f"() => {info}.startsWith('{len(infeasible)} of')")
    first = trials["objectives"][0]["name"]
    page.select_option("#trial-sort", first)
    page.check("#trial-desc")
    if infeasible:
        top = max(infeasible, key=lambda r: r["objectives"][0])
        page.wait_for_selector(f"#trial-table tbody tr:first-child[data-trial='{top['trial']}']")
    # a value range typed as column:low:high
    page.select_option("#trial-feasible", "")
    values = sorted(r["objectives"][0] for r in trials["items"])
    lo, hi = values[len(values) // 3], values[2 * len(values) // 3]
    expected = sum(1 for v in values if lo <= v <= hi)
    page.fill("#trial-range", f"f1:{lo!r}:{hi!r}")
    page.press("#trial-range", "Enter")
    page.wait_for_function(
        f"() => document.querySelector('#trial-info').textContent.startsWith('{expected} of')"
    )
    page.fill("#trial-range", "f1:nonsense")
    page.press("#trial-range", "Enter")
    page.wait_for_selector("#trial-error:text('COLUMN:LOW:HIGH')")
    page.fill("#trial-range", "")
    page.press("#trial-range", "Enter")
    page.wait_for_function("() => document.querySelector('#trial-error').textContent === ''")

    # a trial that is not on the front: its motion and its recording
    front_x = [p["x"] for p in front["points"]]
    off = next(r for r in trials["items"] if r["x"] not in front_x)
    recordings: list[str] = []
    page.on("response", lambda r: recordings.append(r.url) if "/recording" in r.url else None)
    page.select_option("#trial-sort", "trial")
    page.uncheck("#trial-desc")
    line = page.locator(f"#trial-parallel .pc-line[data-trial='{off['trial']}']")
    line.dispatch_event("click")
    page.wait_for_selector(f"#motion h2:text('trial {off['trial']}')")
    page.wait_for_selector("#joint-plot .scatterlayer .trace")
    page.wait_for_selector(f"#trial-parallel .pc-line.selected[data-trial='{off['trial']}']")
    page.wait_for_function(
        f"() => performance.getEntriesByType('resource')"
        f".some(e => e.name.includes('/trials/{off['trial']}/recording'))"
    )
    page.screenshot(path=shots / "trials.png", full_page=True)
    assert not page.legopt_errors, page.legopt_errors


THREE: dict[str, Any] = {
    **THREE_OBJECTIVES,
    "name": "browser steer",
    "budget": {"generations": 4},
    "seed": 2,
}
RUNNING: dict[str, Any] = {
    **SPEC,
    "name": "browser live",
    "budget": {"generations": 3000},
}


def _drawn(page: Any) -> Any:
    return page.wait_for_function(
        """() => { const el = document.querySelector('#front-plot');
          const L = el && el._fullLayout;
          if (!L || !el._fullData || !el._fullData.length) return null;
          const t = el._fullData[0].type;
          const titles = t === 'scatter3d'
            ? [L.scene.xaxis.title.text, L.scene.yaxis.title.text, L.scene.zaxis.title.text]
            : [L.xaxis.title.text, L.yaxis.title.text];
          return { type: t, titles }; }"""
    ).json_value()


def test_pick_the_objectives_of_a_three_objective_front(page: Any, stack: Stack) -> None:
    with stack.client() as c:
        job_id = c.submit(THREE)["id"]
    stack.wait_for(job_id, lambda j: j["status"] == "succeeded")
    page.goto(f"{stack.url}/#/job/{job_id}")
    page.wait_for_selector("#front-table tbody tr[data-point]")
    first = _drawn(page)
    assert first["type"] == "scatter3d" and len(first["titles"]) == 3
    page.select_option("#front-z", "")  # two objectives: a 2-D plot of x and y
    page.wait_for_function(
        "() => document.querySelector('#front-plot')._fullData[0].type === 'scatter'"
    )
    page.select_option("#front-x", "2")  # the third objective across
    page.wait_for_function(
        f"() => document.querySelector('#front-plot')._fullLayout.xaxis.title.text"
        f" === {first['titles'][2]!r}"
    )
    two = _drawn(page)
    assert two["titles"] == [first["titles"][2], first["titles"][1]]
    assert not page.legopt_errors, page.legopt_errors


def test_a_running_job_updates_without_reload(page: Any, stack: Stack) -> None:
    with stack.client() as c:
        job_id = c.submit(RUNNING)["id"]
    stack.wait_for(job_id, lambda j: j["status"] == "running" and j["generation"] >= 1)
    streams: list[str] = []
    page.on("request", lambda r: streams.append(r.url) if r.url.endswith("/events") else None)
    page.goto(f"{stack.url}/#/job/{job_id}")
    page.wait_for_selector("#front-plot .scatterlayer .point")  # the live front, while it runs
    text = page.locator("#trial-info").inner_text()
    # the page redraws from the server's push: the stored trials grow with no reload
    page.wait_for_function(f"() => document.querySelector('#trial-info').textContent !== {text!r}")
    assert streams  # the page follows the job's event stream
    with stack.client() as c:
        c.cancel(job_id)
    stack.wait_for(job_id, lambda j: j["status"] == "cancelled")
    page.wait_for_selector(".badge.cancelled")
    assert not page.legopt_errors, page.legopt_errors
