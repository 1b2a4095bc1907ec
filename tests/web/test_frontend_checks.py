"""The dashboard's front-end checks pass: ``services/web/check_frontend.sh`` (ESLint and the
TypeScript type check of ``services/web/static/js`` against the API types; ``npm ci`` of the
pinned tools first when ``node_modules`` is missing or stale).

Needs node and npm (Node 20 or newer): without them the test is skipped, unless
``LEGOPT_REQUIRE_BROWSER=1`` (CI): then it fails."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # the quick lane (run.py test --quick) leaves it out

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "services" / "web" / "check_frontend.sh"


def test_the_front_end_checks_pass() -> None:
    missing = [tool for tool in ("node", "npm") if shutil.which(tool) is None]
    if missing:
        why = f"{' and '.join(missing)} not installed (the front-end checks need Node 20+ and npm)"
        if os.environ.get("LEGOPT_REQUIRE_BROWSER") == "1":
            pytest.fail(f"the front-end checks are required here (LEGOPT_REQUIRE_BROWSER=1): {why}")
        pytest.skip(why)
    bash = shutil.which("bash") or "bash"
    proc = subprocess.run(
        [bash, str(SCRIPT)], cwd=ROOT, capture_output=True, text=True, timeout=900, check=False
    )
    assert proc.returncode == 0, (
        f"services/web/check_frontend.sh failed (exit {proc.returncode}):\n"
        f"{proc.stdout[-6000:]}\n{proc.stderr[-6000:]}"
    )
