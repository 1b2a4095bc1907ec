"""Robots and the catalog: create (catalog, DH, URDF), validation errors naming the field,
listing with the catalog, validate-only, ownership."""

from __future__ import annotations

from typing import Any

import pytest
from api_helpers import dh_spec, locs, row_counts, urdf_text
from fastapi.testclient import TestClient

from legcore.robots import catalog
from services.api.deps import ApiContext

API = "/api/v1"


def test_create_catalog_robot(client: TestClient, alice: dict[str, str]) -> None:
    r = client.post(f"{API}/robots", json={"name": "leg", "catalog": "calderon_leg"}, headers=alice)
    assert r.status_code == 201, r.text
    body = r.json()
    assert r.headers["location"] == f"{API}/robots/{body['id']}"
    assert body["source"] == "catalog" and body["catalog"] == "calderon_leg"
    assert body["summary"]["nq"] == 3 and body["summary"]["kind"] == "serial"
    assert body["spec"] == {"catalog": "calderon_leg"}


def test_create_dh_robot(client: TestClient, alice: dict[str, str]) -> None:
    r = client.post(f"{API}/robots", json={"name": "arm", "spec": dh_spec()}, headers=alice)
    assert r.status_code == 201, r.text
    body = r.json()
    assert body["source"] == "dh"
    assert body["summary"]["nq"] == 2
    assert body["summary"]["mass_kg"] == pytest.approx(1.8)
    got = client.get(f"{API}/robots/{body['id']}", headers=alice)
    assert got.status_code == 200
    assert got.json()["spec"]["joints"][1]["mass"] == 0.8


def test_create_urdf_robot(client: TestClient, alice: dict[str, str]) -> None:
    spec = {"kind": "urdf", "name": "arm2", "urdf": urdf_text()}
    r = client.post(f"{API}/robots", json={"name": "u", "spec": spec}, headers=alice)
    assert r.status_code == 201, r.text
    assert r.json()["source"] == "urdf"
    assert r.json()["summary"]["joint_names"] == ["j1", "j2"]


def test_dh_kind_defaults_to_dh(client: TestClient, alice: dict[str, str]) -> None:
    spec = dh_spec()
    del spec["kind"]
    r = client.post(f"{API}/robots", json={"name": "arm", "spec": spec}, headers=alice)
    assert r.status_code == 201, r.text
    assert r.json()["spec"]["kind"] == "dh"


@pytest.mark.parametrize(
    ("body", "loc"),
    [
        # inertia not positive semi-definite
        (
            {"spec": dh_spec(inertia=[[0.001, 0, 0], [0, -0.005, 0], [0, 0, 0.005]])},
            ["body", "spec", "joints", 1, "inertia"],
        ),
        # triangle inequality
        (
            {"spec": dh_spec(inertia=[[0.001, 0, 0], [0, 0.001, 0], [0, 0, 0.05]])},
            ["body", "spec", "joints", 1, "inertia"],
        ),
        ({"spec": dh_spec(mass=-1.0)}, ["body", "spec", "joints", 1, "mass"]),
        ({"spec": dh_spec(q_min=1.0, q_max=0.5)}, ["body", "spec", "joints", 1]),
        ({"spec": dh_spec(bogus=1)}, ["body", "spec", "joints", 1, "bogus"]),
        ({"spec": {**dh_spec(), "joints": []}}, ["body", "spec", "joints"]),
        (
            {"spec": {"kind": "urdf", "name": "u", "urdf": urdf_text(izz=0.1)}},
            ["body", "spec", "urdf"],
        ),
        (
            {"spec": {"kind": "urdf", "name": "u", "urdf": urdf_text(lower=2.0)}},
            ["body", "spec", "urdf"],
        ),
        ({"spec": {"kind": "urdf", "name": "u", "urdf": "<robot"}}, ["body", "spec", "urdf"]),
        ({"spec": {"kind": "sdf", "name": "u"}}, ["body", "spec"]),
        ({"spec": "puma560"}, ["body", "spec"]),
        ({"catalog": "nope"}, ["body", "catalog"]),
        ({"catalog": "puma560", "spec": dh_spec()}, ["body"]),
        ({}, ["body"]),
        ({"catalog": "puma560", "extra": 1}, ["body", "extra"]),
    ],
)
def test_bad_robot_is_422_naming_the_field_and_stores_nothing(
    client: TestClient, ctx: ApiContext, alice: dict[str, str], body: dict[str, Any], loc: list[Any]
) -> None:
    before = row_counts(ctx)
    for path, payload in (("robots", {"name": "bad", **body}), ("robots/validate", body)):
        r = client.post(f"{API}/{path}", json=payload, headers=alice)
        assert loc in locs(r), r.json()
        assert all(isinstance(e["msg"], str) and e["msg"] for e in r.json()["detail"])
    assert row_counts(ctx) == before


def test_validate_without_storing(
    client: TestClient, ctx: ApiContext, alice: dict[str, str]
) -> None:
    before = row_counts(ctx)
    r = client.post(f"{API}/robots/validate", json={"spec": dh_spec()}, headers=alice)
    assert r.status_code == 200, r.text
    assert r.json()["valid"] is True and r.json()["summary"]["nq"] == 2
    r = client.post(f"{API}/robots/validate", json={"catalog": "citedi_hexapod"}, headers=alice)
    assert r.json()["summary"]["kind"] == "legged" and r.json()["summary"]["n_legs"] == 6
    assert row_counts(ctx) == before


def test_name_conflicts(client: TestClient, alice: dict[str, str], bob: dict[str, str]) -> None:
    body = {"name": "arm", "spec": dh_spec()}
    assert client.post(f"{API}/robots", json=body, headers=alice).status_code == 201
    r = client.post(f"{API}/robots", json=body, headers=alice)
    assert r.status_code == 409 and "arm" in r.json()["detail"]
    assert client.post(f"{API}/robots", json=body, headers=bob).status_code == 201
    r = client.post(f"{API}/robots", json={"name": "puma560", "spec": dh_spec()}, headers=alice)
    assert locs(r) == [["body", "name"]]


def test_list_robots_with_catalog_and_pagination(client: TestClient, alice: dict[str, str]) -> None:
    for name in ("c", "a", "b"):
        client.post(f"{API}/robots", json={"name": name, "spec": dh_spec()}, headers=alice)
    r = client.get(f"{API}/robots", headers=alice)
    assert r.json()["total"] == 3
    assert [i["name"] for i in r.json()["items"]] == ["a", "b", "c"]
    n_cat = len(catalog.names())
    full = client.get(f"{API}/robots?include_catalog=true&limit=100", headers=alice).json()
    assert full["total"] == n_cat + 3
    assert [i["name"] for i in full["items"]] == [*catalog.names(), "a", "b", "c"]
    assert all(i["builtin"] for i in full["items"][:n_cat])
    # every window of size 2 matches the full listing
    for offset in range(n_cat + 4):
        page = client.get(
            f"{API}/robots?include_catalog=true&limit=2&offset={offset}", headers=alice
        ).json()
        assert page["items"] == full["items"][offset : offset + 2]
        assert (page["total"], page["limit"], page["offset"]) == (n_cat + 3, 2, offset)
    assert client.get(f"{API}/robots?limit=0", headers=alice).status_code == 422
    assert client.get(f"{API}/robots?offset=-1", headers=alice).status_code == 422


def test_catalog(client: TestClient, alice: dict[str, str]) -> None:
    r = client.get(f"{API}/catalog", headers=alice)
    assert r.status_code == 200
    entries = {e["name"]: e for e in r.json()}
    assert set(entries) == set(catalog.names())
    assert entries["puma560"]["nq"] == 6
    assert "seed 001" in entries["puma560"]["source"]
    detail = client.get(f"{API}/robots/puma560", headers=alice).json()
    assert detail["builtin"] and detail["summary"]["nq"] == 6
    assert len(detail["inline_spec"]["joints"]) == 6  # copyable as an inline robot
    r = client.post(f"{API}/robots/validate", json={"spec": detail["inline_spec"]}, headers=alice)
    assert r.status_code == 200 and r.json()["summary"]["nq"] == 6
    legged = client.get(f"{API}/robots/citedi_hexapod", headers=alice).json()
    assert legged["inline_spec"] is None and legged["summary"]["n_legs"] == 6


def test_robots_of_another_key_are_404(
    client: TestClient, alice: dict[str, str], bob: dict[str, str]
) -> None:
    rid = client.post(f"{API}/robots", json={"name": "a", "spec": dh_spec()}, headers=alice).json()[
        "id"
    ]
    r = client.get(f"{API}/robots/{rid}", headers=bob)
    assert r.status_code == 404 and r.json()["detail"]
    assert client.get(f"{API}/robots", headers=bob).json()["total"] == 0
    assert client.get(f"{API}/robots/{rid}", headers=alice).status_code == 200


def test_delete_a_stored_robot(
    client: TestClient, alice: dict[str, str], bob: dict[str, str]
) -> None:
    """A stored robot can be deleted by its owner only (another key's, a catalog name or a
    second delete: 404); the name is free again."""
    r = client.post(f"{API}/robots", json={"name": "mine", "catalog": "puma560"}, headers=alice)
    assert r.status_code == 201, r.text
    rid = r.json()["id"]
    assert client.delete(f"{API}/robots/{rid}", headers=bob).status_code == 404
    assert client.delete(f"{API}/robots/puma560", headers=alice).status_code == 404
    assert client.delete(f"{API}/robots/{rid}", headers=alice).status_code == 204
    assert client.get(f"{API}/robots/{rid}", headers=alice).status_code == 404
    assert client.delete(f"{API}/robots/{rid}", headers=alice).status_code == 404
    again = client.post(f"{API}/robots", json={"name": "mine", "catalog": "puma560"}, headers=alice)
    assert again.status_code == 201, again.text


def test_a_retried_robot_upload_returns_the_stored_robot(
    client: TestClient, alice: dict[str, str]
) -> None:
    """A client that timed out and retries with the same Idempotency-Key gets the robot the
    first request stored, not a 409 for its name (CI on a busy machine found the 409)."""
    body = {"name": "retried_arm", "catalog": "puma560"}
    headers = {**alice, "Idempotency-Key": "robot-retry-1"}
    first = client.post(f"{API}/robots", json=body, headers=headers)
    assert first.status_code == 201, first.text
    again = client.post(f"{API}/robots", json=body, headers=headers)
    assert again.status_code == 201 and again.headers["Idempotent-Replayed"] == "true"
    assert again.json()["id"] == first.json()["id"]
    other = client.post(f"{API}/robots", json=body, headers={**alice, "Idempotency-Key": "x2"})
    assert other.status_code == 409  # a new request with the same name is still a conflict
