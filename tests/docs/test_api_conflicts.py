"""Every 409 the API can answer is documented (issue 22, item 5): each route whose OpenAPI
responses list a 409 is a row of docs/api.md's "Conflicts (409)" table, and each row of that
table is such a route."""

from __future__ import annotations

import re
from pathlib import Path

from services.api.app import API_PREFIX, create_app
from services.store.settings import Settings

ROOT = Path(__file__).resolve().parents[2]


def _normal(route: str) -> str:
    """``GET /jobs/{job_id}/motion`` and ``GET /jobs/{id}/motion`` alike (``{}``)."""
    return re.sub(r"\{[^}]*\}", "{}", route)


def _documented() -> set[str]:
    text = (ROOT / "docs" / "api.md").read_text()
    section = text.split("### Conflicts (409)", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| `([A-Z]+ /[^`]*)` \|", section, flags=re.MULTILINE)
    assert rows, "docs/api.md has no table of its 409s"
    return {_normal(r) for r in rows}


def test_every_409_of_the_openapi_document_is_in_the_docs(tmp_path: Path) -> None:
    app = create_app(Settings.from_env(env={}, data_dir=tmp_path), enqueue=lambda _id: None)
    raised = {
        _normal(f"{method.upper()} {path.removeprefix(API_PREFIX)}")
        for path, operations in app.openapi()["paths"].items()
        for method, op in operations.items()
        if "409" in op.get("responses", {})
    }
    assert len(raised) >= 8  # robots, jobs (delete, cancel), points, dashboard robot, keys
    assert raised == _documented()
