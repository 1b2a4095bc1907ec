"""Fixtures of the browser tests: Debian's Chromium driven by Playwright against the real
embedded service (``tests.integration.stack.Stack``: uvicorn + a Celery worker, SQLite,
filesystem broker).

Where Chromium or Playwright is missing the tests are skipped, unless
``LEGOPT_REQUIRE_BROWSER=1`` (CI sets it in ``.ci/run``): then a missing browser is a failure.
Playwright's own browser download is never used (it cannot work offline): the system
``chromium`` is launched by path. Screenshots of every page go to ``tests/web/screenshots/``
(ignored by git), or to ``LEGOPT_SCREENSHOT_DIR``.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.integration.stack import Stack, embedded_stack
from tests.web.dashboard_session import logged_in_page

CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
    "--disable-sync",
]
SCREENSHOTS = Path(os.environ.get("LEGOPT_SCREENSHOT_DIR") or Path(__file__).parent / "screenshots")


def _missing(why: str) -> None:
    if os.environ.get("LEGOPT_REQUIRE_BROWSER") == "1":
        pytest.fail(f"browser tests are required here (LEGOPT_REQUIRE_BROWSER=1) but {why}")
    pytest.skip(why)


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """A headless Debian Chromium driven by Playwright."""
    executable = shutil.which("chromium") or shutil.which("chromium-browser")
    if executable is None:
        _missing("chromium is not installed (apt-get install -y chromium)")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _missing("playwright is not installed (pip install playwright)")
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=executable, args=CHROMIUM_ARGS)
        try:
            yield b
        finally:
            b.close()


@pytest.fixture(scope="module")
def stack(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Stack]:
    """The embedded service (API + one worker) on a fresh data directory."""
    tmp = tmp_path_factory.mktemp("web-stack")
    with embedded_stack(tmp) as st:
        yield st


@pytest.fixture(scope="module")
def shots() -> Path:
    """Where the tests write their screenshots."""
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    return SCREENSHOTS


@pytest.fixture(scope="module")
def page(browser: Any, stack: Stack, shots: Path) -> Iterator[Any]:
    """A logged-in page of the dashboard, recording the whole module's requests, errors and
    Content-Security-Policy violations (``tests/web/dashboard_session.py``)."""
    yield from logged_in_page(browser, stack, shots)
