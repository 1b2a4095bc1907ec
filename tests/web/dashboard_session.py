"""What the dashboard's browser tests share (``test_dashboard_browser.py``,
``test_dashboard_pages_browser.py``): the jobs they submit, a logged-in page that records every
request, error and Content-Security-Policy violation of the module, CSV downloads, and the check
that nothing any page of a module asked for left this server."""

from __future__ import annotations

import csv
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from tests.gait_specs import GAIT, UNSTABLE
from tests.integration.stack import Stack

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
#: Seed 002's study (examples/002_hexapod_workspace.yaml: three objectives, f1 and f2 in rad, f3
#: in m) at a test's budget: a few seconds of the worker.
THREE_OBJECTIVES: dict[str, Any] = {
    "name": "browser 3-D front",
    "robot": "citedi_hexapod",
    "problem": {"kind": "hexapod_workspace"},
    "optimizer": {"kind": "moead", "params": {"n_subproblems": 24, "n_neighbors": 6}},
    "budget": {"generations": 5},
    "seed": 1,
    "record": False,
}
#: Still running when the test cancels it (minutes of work; cancelled in seconds).
LONG: dict[str, Any] = {
    **TWO_OBJECTIVES,
    "name": "browser cancel me",
    "record": False,
    "budget": {"generations": 5000},  # the API's limit
}
#: Seed 003's walk with its verdict known (tests/gait_specs.py): feasible, and one asking for a
#: margin no step has, which succeeds with an infeasible optimum.
FEASIBLE_GAIT: dict[str, Any] = {**GAIT, "name": "browser gait, 1 mm margin"}
INFEASIBLE_GAIT: dict[str, Any] = {**UNSTABLE, "name": "browser gait, 20 mm margin"}
#: Seed 004's minimum time with a speed profile: its gap to the physical minimum (TOPP-RA).
MIN_TIME: dict[str, Any] = {
    "name": "browser minimum time",
    "problem": {"kind": "path_tracking", "speeds": "profile"},
    "optimizer": {"kind": "nsga2", "params": {"pop_size": 12}},
    "budget": {"generations": 3},
    "seed": 1,
    "record": False,
}
#: The stylesheet's red and green (--bad, --ok), as the browser computes them.
RED, GREEN = "rgb(192, 57, 43)", "rgb(31, 138, 76)"
TIMEOUT_MS = 60_000
#: The servers the Rerun web viewer calls by itself (viewer.html swallows those calls).
VIEWER_CALLS_HOME = {"tel.rerun.io", "api.github.com"}
#: Reported to the console by every document of the page (an init script): a request the
#: page's Content-Security-Policy refused never reaches the "request" event.
#: (``page.wait_for_function`` predicates are arrow functions, not expressions: Playwright
#: evaluates an expression again with ``eval`` in the page at each poll, which the dashboard's
#: policy refuses — no ``'unsafe-eval'`` — while a function is compiled once, by DevTools.)
CSP_REPORTER = """document.addEventListener("securitypolicyviolation", (e) =>
  console.error(`legopt-csp-violation ${e.violatedDirective} ${e.blockedURI}`));"""


def logged_in_page(browser: Any, stack: Stack, shots: Path) -> Iterator[Any]:
    """A logged-in page of the dashboard. Collected over the whole module: its uncaught errors
    (of the page and its frames, the viewer's iframe included) in ``page.legopt_errors``, every
    request of every page and frame in ``page.legopt_requests`` (url, resource type), the
    documents' response headers in ``page.legopt_documents`` and the Content-Security-Policy
    violations in ``page.legopt_csp``."""
    context = browser.new_context(viewport={"width": 1400, "height": 1000}, accept_downloads=True)
    context.add_init_script(CSP_REPORTER)
    pg = context.new_page()
    pg.set_default_timeout(TIMEOUT_MS)
    pg.legopt_errors = []
    pg.legopt_requests = []
    pg.legopt_documents = {}
    pg.legopt_csp = []
    pg.on("pageerror", lambda exc: pg.legopt_errors.append(str(exc)))
    pg.on(
        "console",
        lambda m: pg.legopt_csp.append(m.text) if "legopt-csp-violation" in m.text else None,
    )
    context.on("request", lambda r: pg.legopt_requests.append((r.url, r.resource_type)))
    context.on(
        "response",
        lambda r: (
            pg.legopt_documents.setdefault(urlsplit(r.url).path, r.headers)
            if r.request.resource_type == "document"
            else None
        ),
    )
    pg.goto(stack.url + "/")
    pg.wait_for_selector("#login[open]")
    pg.screenshot(path=shots / "login.png")
    pg.fill("#login-key", "not-a-key")
    pg.click("#login-submit")
    pg.wait_for_selector("#login-error:text('not valid')")
    pg.fill("#login-key", stack.key)
    pg.click("#login-submit")
    pg.wait_for_selector("#who:text('it')")
    yield pg
    context.close()


def download(page: Any, selector: str, to: Path) -> list[dict[str, str]]:
    with page.expect_download() as info:
        page.click(selector)
    info.value.save_as(to)
    with open(to, newline="") as f:
        return list(csv.DictReader(f))


def assert_nothing_left_this_server(page: Any, stack: Stack, visited: set[str]) -> None:
    """Every request of every page the module's tests visited went to this server (``visited``:
    paths that must be among them) and the pages' Content-Security-Policy refused nothing."""
    origin = "{0.scheme}://{0.netloc}".format(urlsplit(stack.url))
    paths = {urlsplit(url).path for url, _ in page.legopt_requests}
    assert visited <= paths, f"not visited (run the whole module): {sorted(visited - paths)}"
    foreign = sorted(
        {(url, kind) for url, kind in page.legopt_requests
         if not url.startswith(("data:", "blob:")) and not url.startswith(origin + "/")}
    )  # fmt: skip
    assert not foreign, foreign
    assert not page.legopt_csp, page.legopt_csp  # nothing was even tried and refused


def assert_dashboard_csp(page: Any) -> None:
    """The dashboard's own policy: this server's scripts only, only plotly's empty <style>, no
    inline script or style, no eval; and nosniff."""
    dashboard_csp = page.legopt_documents["/"]["content-security-policy"]
    assert "default-src 'self'" in dashboard_csp and "connect-src 'self'" in dashboard_csp
    assert "script-src 'self'" in dashboard_csp and "style-src 'self' 'sha256-" in dashboard_csp
    assert "'unsafe-inline'" not in dashboard_csp and "'unsafe-eval'" not in dashboard_csp
    assert page.legopt_documents["/"]["x-content-type-options"] == "nosniff"
