"""The dashboard's API types (``services/web/static/js/api_types.d.ts``, which ``tsc`` checks
its modules against) are what the API's OpenAPI document gives now; and the generator
(``services.web.api_types``) translates the schema forms FastAPI writes."""

from __future__ import annotations

import difflib
from typing import Any

import pytest

from services.api.app import API_PREFIX
from services.web import api_types


def test_the_committed_api_types_are_current() -> None:
    committed = api_types.OUTPUT.read_text(encoding="utf-8")
    generated = api_types.render_current()
    if committed != generated:
        diff = difflib.unified_diff(
            committed.splitlines(), generated.splitlines(), "committed", "generated", lineterm=""
        )
        shown = "\n".join(list(diff)[:60])
        pytest.fail(
            f"{api_types.OUTPUT.name} is out of date with the API: "
            f"run python -m services.web.api_types to update\n{shown}"
        )


def _doc(schemas: dict[str, Any], response: dict[str, Any]) -> dict[str, Any]:
    ok = {"200": {"content": {"application/json": {"schema": response}}}}
    return {
        "paths": {f"{API_PREFIX}/things/{{thing_id}}": {"get": {"responses": ok}}},
        "components": {"schemas": schemas},
    }


def test_the_schema_forms_fastapi_writes_are_translated() -> None:
    schemas = {
        "Page_Thing_": {
            "type": "object",
            "properties": {
                "items": {"type": "array", "items": {"$ref": "#/components/schemas/Thing"}},
                "next": {"anyOf": [{"type": "string"}, {"type": "null"}]},
            },
            "required": ["items"],
        },
        "Thing": {
            "type": "object",
            "description": "A thing. Not */ the end of a comment.",
            "properties": {
                "status": {"$ref": "#/components/schemas/Status"},
                "values": {
                    "type": "array",
                    "items": {"anyOf": [{"type": "number"}, {"type": "null"}]},
                },
                "spec": {"title": "Spec", "description": "Anything (Any)."},
                "counts": {
                    "type": "object",
                    "additionalProperties": {"type": "integer"},
                    "propertyNames": {"$ref": "#/components/schemas/Status"},
                },
                "extra": {"type": "object", "additionalProperties": True},
                "seeds": {"type": "array", "items": {}},
                "flag": {"type": "boolean", "default": False},
            },
            "required": ["status", "values", "spec", "counts", "extra", "seeds"],
        },
        "Status": {"type": "string", "enum": ["queued", "done"]},
        "Unused": {"type": "object", "properties": {"x": {"type": "integer"}}},
    }
    ref = {"$ref": "#/components/schemas/Page_Thing_"}
    out = api_types.render(_doc(schemas, ref), (("GET", "/things/{thing_id}"),))
    assert "export interface Page_Thing {\n  items: Thing[];\n  next: string | null;\n}" in out
    assert 'export type Status = "queued" | "done";' in out
    assert "/** A thing. Not *\\/ the end of a comment. */\nexport interface Thing {" in out
    for line in (
        "  status: Status;",
        "  values: Array<number | null>;",
        "  /** Anything (Any). */\n  spec: unknown;",
        "  counts: Partial<Record<Status, number>>;",
        "  extra: Record<string, unknown>;",
        "  seeds: unknown[];",
        "  flag: boolean;",  # a response holds every field, defaults too
    ):
        assert line in out, line
    assert "Unused" not in out  # only what the dashboard's responses use
    assert '  "GET /things/{thing_id}": Page_Thing;' in out


def test_an_endpoint_the_dashboard_calls_must_exist() -> None:
    doc = _doc({}, {"type": "string"})
    with pytest.raises(api_types.ApiTypesError, match="GET /gone: not an endpoint"):
        api_types.render(doc, (("GET", "/gone"),))


def test_a_stored_document_may_lack_its_optional_keys() -> None:
    """A ``TypedDict`` passed on as stored (``x-optional-keys``) declares the keys outside its
    ``required`` optional, and the keys it does not name as an index signature."""
    schemas = {
        "Doc": {
            "type": "object",
            "properties": {"name": {"type": "string"}, "value": {"type": "number"}},
            "required": ["name"],
            "additionalProperties": True,
            api_types.OPTIONAL_KEYS: True,
        }
    }
    out = api_types.render(
        _doc(schemas, {"$ref": "#/components/schemas/Doc"}), (("GET", "/things/{thing_id}"),)
    )
    assert (
        "export interface Doc {\n  name: string;\n  value?: number;\n  [key: string]: unknown;\n}"
        in out
    )
