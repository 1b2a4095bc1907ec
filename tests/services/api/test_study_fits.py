"""Issue 25, item 4: one answer to "does study X fit robot R".

For every robot of the study matrix (example-robot-data's URDFs, stored by the caller) and the
catalog robots, and every study kind with its DEFAULT task, these give the same verdict — all
from ``Study.fit``, the function ``POST /jobs`` runs:

- ``GET /studies`` (its ``robots`` rows) and so ``legopt studies``;
- ``GET /robots/{id}`` (its ``studies``) and so ``legopt robots show``;
- the dashboard's robot page (``GET /dashboard/robots/{id}``);
- ``POST /jobs`` with ``{"robot": id, "problem": {"kind": K}}``: 201 exactly when accepted,
  else a 422 located at the field the listings name, with the same reason.

The CLI commands are run against this in-process app (their client's transport is the test
client), so what they print is what the API answers.
"""

from __future__ import annotations

import json
from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from legcore.robots import catalog
from legcore.studies.registry import studies
from services.cli import app as cli_app
from services.client import Client
from tests.robot_files import ERD_URDF, require_erd
from tests.studies.conftest import MATRIX_ROBOTS

API = "/api/v1"


@pytest.fixture
def stored(client: TestClient, alice: dict[str, str]) -> dict[str, str]:
    """Every matrix robot stored by alice: name -> id."""
    root = require_erd()
    ids = {}
    for name, (file_key, extra) in MATRIX_ROBOTS.items():
        spec = {
            "kind": "urdf",
            "name": name,
            "urdf": (root / ERD_URDF[file_key]).read_text(),
            **extra,
        }
        r = client.post(f"{API}/robots", json={"name": name, "spec": spec}, headers=alice)
        assert r.status_code == 201, r.text
        ids[name] = r.json()["id"]
    return ids


@pytest.fixture
def cli(
    client: TestClient, alice: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> Iterator[CliRunner]:
    """A CLI runner whose API client talks to the in-process app."""

    def make(url: str | None, key: str | None) -> Client:
        c = Client("http://testserver", alice["X-API-Key"])
        c.http.close()
        c.http = TestClient(client.app, base_url="http://testserver/api/v1", headers=alice)
        return c

    for module in ("services.cli.studies", "services.cli.robots"):
        monkeypatch.setattr(f"{module}.client", make)
    yield CliRunner()


def _verdict(accepted: bool, field: str | None, reason: str | None) -> tuple[bool, str, str]:
    return (accepted, field or "", reason or "")


@pytest.mark.slow
def test_every_place_gives_the_submissions_answer(
    client: TestClient, alice: dict[str, str], stored: dict[str, str], cli: CliRunner
) -> None:
    kinds = sorted(studies())
    listing = client.get(f"{API}/studies", headers=alice).json()
    robots = {**{n: n for n in catalog.names()}, **stored}  # name -> what a spec takes
    by_study = {
        (it["kind"], r["robot"]): _verdict(r["accepted"], r.get("field"), r["reason"])
        for it in listing["items"]
        for r in it["robots"]
    }
    out = cli.invoke(cli_app, ["studies", "--json"])
    assert out.exit_code == 0, out.output
    assert json.loads(out.output)["items"] == listing["items"]  # what `legopt studies` shows
    seen = 0
    for name, ident in robots.items():
        detail = client.get(f"{API}/robots/{ident}", headers=alice).json()
        page = client.get(f"{API}/dashboard/robots/{ident}", headers=alice).json()
        from_detail = {
            f["kind"]: _verdict(f["accepted"], f["field"], f["reason"]) for f in detail["studies"]
        }
        from_page = {
            f["kind"]: _verdict(f["accepts"], f["field"], f["reason"]) for f in page["studies"]
        }
        show = cli.invoke(cli_app, ["robots", "show", ident])
        assert show.exit_code == 0, show.output
        for kind in kinds:
            verdict = by_study[(kind, name)]
            assert from_detail[kind] == verdict == from_page[kind], (name, kind)
            r = client.post(
                f"{API}/jobs",
                json={"robot": ident, "problem": {"kind": kind}, "budget": {"generations": 1}},
                headers=alice,
            )
            accepted, field, reason = verdict
            if accepted:
                assert r.status_code == 202, (name, kind, r.text)
                continue
            assert r.status_code == 422, (name, kind, r.text)
            (err,) = r.json()["detail"]
            where = err["loc"][1:] if err["loc"][1] == "robot" else err["loc"][2:]
            assert ".".join(str(p) for p in where) == field, (name, kind, err)
            assert err["msg"] == reason, (name, kind, err)
            seen += 1
        assert "study kinds" in show.output, show.output
    assert seen > 0


def test_robots_show_and_studies_print_the_verdicts(
    client: TestClient, alice: dict[str, str], cli: CliRunner
) -> None:
    """The CLI prints each kind's verdict: the paper's preset on its own robot, the field and
    reason of a refusal."""
    out = cli.invoke(cli_app, ["robots", "show", "calderon_leg"])
    assert out.exit_code == 0, out.output
    text = " ".join(out.output.split())
    assert "swing_energy" in text and "path_placement" in text
    assert "robot: path_placement needs" in text
    out = cli.invoke(cli_app, ["studies", "--robot", "calderon_leg"])
    assert out.exit_code == 0, out.output
    assert "path_tracking: robot: path_tracking needs" in " ".join(out.output.split())
