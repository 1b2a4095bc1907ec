"""``GET /api/v1/studies`` in-process (the real-service run is in tests/studies): every kind with
its parameter schema and defaults, catalog and stored robots checked, refusals with a reason."""

from __future__ import annotations

from fastapi.testclient import TestClient

from legcore.robots import catalog
from legcore.studies.registry import studies

API = "/api/v1"


def test_every_kind_lists_schema_defaults_and_robot_fits(
    client: TestClient, alice: dict[str, str]
) -> None:
    r = client.get(f"{API}/studies", headers=alice)
    assert r.status_code == 200, r.text
    body = r.json()
    kinds = {s["kind"]: s for s in body["items"]}
    assert set(kinds) == set(studies())
    for kind, s in kinds.items():
        assert s["params_schema"]["type"] == "object" and s["defaults"] is not None, kind
        fits = {f["robot"]: f for f in s["robots"]}
        assert set(fits) == set(catalog.names()), kind
        assert fits[studies()[kind].default_robot]["accepted"], kind  # its own preset robot
        for f in fits.values():
            assert f["accepted"] == (f["reason"] is None), f
    refused = [f for s in body["items"] for f in s["robots"] if not f["accepted"]]
    assert refused and all(len(f["reason"]) > 10 for f in refused)
    assert body["stored_robots_total"] == 0
    # the parameters derived from the robot are named, and their default is left to the robot
    for kind, s in kinds.items():
        assert s["robot_relative"] == list(studies()[kind].robot_relative), kind
        assert all(s["defaults"][f] is None for f in s["robot_relative"]), kind
    assert "q_start" in kinds["swing_energy"]["robot_relative"]


def test_one_kind_without_robots_and_an_unknown_kind(
    client: TestClient, alice: dict[str, str]
) -> None:
    kind = sorted(studies())[0]
    r = client.get(f"{API}/studies", params={"kind": kind, "robots": "false"}, headers=alice)
    assert r.status_code == 200, r.text
    (only,) = r.json()["items"]
    assert only["kind"] == kind and only["robots"] == []
    r = client.get(f"{API}/studies", params={"kind": "no_such_kind"}, headers=alice)
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["query", "kind"], r.text
    assert client.get(f"{API}/studies").status_code == 401  # a key is needed
