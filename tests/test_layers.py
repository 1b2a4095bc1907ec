"""The house's shape (issue 24): every import points down the layers of ``tools.import_graph``
(legcore below the store, the store below recording, recording below the worker, the worker
below the API, the CLI on top), no new import circle appears, and docs/architecture.md shows
the graph as it is in the code."""

from __future__ import annotations

from pathlib import Path

import pytest

from tools import import_graph as g


@pytest.fixture(scope="module")
def found() -> list[g.Import]:
    return g.imports()


def test_every_import_points_down(found: list[g.Import]) -> None:
    wrong = g.violations(found)
    assert not wrong, "imports across the layers that point up:\n" + "\n".join(wrong)


def test_no_new_import_circle(found: list[g.Import]) -> None:
    new = [c for c in g.circles(found) if c not in g.KNOWN_CIRCLES]
    assert not new, "new import circles:\n" + "\n".join(" <-> ".join(c) for c in new)


def test_known_circles_are_still_there(found: list[g.Import]) -> None:
    """A circle that was broken leaves the known list (so it cannot come back unnoticed)."""
    gone = sorted(g.KNOWN_CIRCLES - set(g.circles(found)))
    assert not gone, f"remove from tools.import_graph.KNOWN_CIRCLES: {gone}"


def test_every_module_has_a_layer() -> None:
    for module in g.module_files():
        g.layer_of(module)  # raises naming the module


def test_architecture_document_is_current() -> None:
    text = g.DOC.read_text(encoding="utf-8")
    assert g.updated(text, g.render()) == text, (
        "docs/architecture.md is out of date: run python -m tools.import_graph --write"
    )


def test_the_checker_catches_an_upward_import_and_a_circle(tmp_path: Path) -> None:
    """A store module importing the API, and two modules importing each other, are found."""
    (tmp_path / "legcore").mkdir()
    (tmp_path / "legcore" / "__init__.py").write_text("")
    (tmp_path / "legcore" / "a.py").write_text("from legcore import b\n")
    (tmp_path / "legcore" / "b.py").write_text("def f():\n    from legcore.a import x\n")
    store = tmp_path / "services" / "store"
    store.mkdir(parents=True)
    (tmp_path / "services" / "__init__.py").write_text("")
    (store / "__init__.py").write_text("")
    (store / "q.py").write_text("from services.api.routes import jobs\n")
    api = tmp_path / "services" / "api" / "routes"
    api.mkdir(parents=True)
    for init in (api.parent / "__init__.py", api / "__init__.py"):
        init.write_text("")
    (api / "jobs.py").write_text("from ..deps import x\n")
    (api.parent / "deps.py").write_text("x = 1\n")
    found = g.imports(tmp_path)
    assert g.Import("services.api.routes.jobs", "services.api.deps", 1) in found  # relative
    wrong = g.violations(found)
    assert len(wrong) == 1 and "services.store.q" in wrong[0] and "store -> api" in wrong[0]
    assert g.circles(found) == [("legcore.a", "legcore.b")]
