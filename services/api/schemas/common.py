"""What every part of the API's schemas shares: page sizes, the error body, the page of a
listing, liveness and readiness, the job and robot spec documents (their JSON schemas are
legcore's, inlined), and the types of stored JSON the responses pass on."""

from __future__ import annotations

import copy
from functools import cache
from typing import Annotated, Any, Generic, Literal, TypeVar

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    JsonValue,
    RootModel,
    TypeAdapter,
    WithJsonSchema,
)

from legcore.jobspec import JobSpec
from legcore.robots import RobotSpec

T = TypeVar("T")

#: Default and maximum page sizes of every listing.
DEFAULT_LIMIT = 50
MAX_LIMIT = 1000


def inline_json_schema(schema: dict[str, Any]) -> dict[str, Any]:
    """``schema`` with every ``#/$defs/...`` reference replaced by its definition.

    OpenAPI components and pydantic's ``$defs`` do not mix inside a plain ``dict`` field, so
    the spec schemas are inlined; ``discriminator`` keywords (whose mappings point into
    ``$defs``) are dropped: each member's ``kind`` is a ``const`` anyway.
    """
    defs: dict[str, Any] = schema.get("$defs", {})

    def resolve(node: Any, seen: tuple[str, ...]) -> Any:
        if isinstance(node, dict):
            ref = node.get("$ref")
            if isinstance(ref, str) and ref.startswith("#/$defs/"):
                name = ref.split("/")[-1]
                if name in seen:  # recursive model: stop expanding
                    return {"type": "object"}
                target = resolve(defs[name], (*seen, name))
                extra = {k: v for k, v in node.items() if k != "$ref"}
                return {**target, **resolve(extra, seen)}
            return {
                k: resolve(v, seen) for k, v in node.items() if k not in ("$defs", "discriminator")
            }
        if isinstance(node, list):
            return [resolve(v, seen) for v in node]
        return node

    return resolve(schema, ())


@cache
def job_spec_schema() -> dict[str, Any]:
    """The JSON schema of a job spec (legcore's ``JobSpec``), inlined."""
    schema = inline_json_schema(TypeAdapter(JobSpec).json_schema())
    schema["description"] = (
        "The job spec of `legopt run`. `robot`: a catalog name, the id (or name) of one of your "
        "stored robots, or an inline DH/URDF robot spec."
    )
    return schema


@cache
def robot_spec_schema() -> dict[str, Any]:
    """The JSON schema of an inline robot spec (legcore's ``RobotSpec``: DH or URDF), inlined."""
    return inline_json_schema(TypeAdapter(RobotSpec).json_schema())


#: A job spec document (validated by legcore in the route, so errors name its fields).
JobSpecDoc = Annotated[dict[str, Any], WithJsonSchema(job_spec_schema())]
#: An inline robot spec document (validated and built by legcore in the route).
RobotSpecDoc = Annotated[dict[str, Any], WithJsonSchema(robot_spec_schema())]

#: An inline robot spec (DH or URDF) as a response gives it, passed on as stored.
RobotSpecOut = Annotated[dict[str, JsonValue], WithJsonSchema(robot_spec_schema())]
#: A stored robot's document: an inline DH/URDF spec, or ``{"catalog": name}``.
RobotDocOut = Annotated[
    dict[str, JsonValue],
    WithJsonSchema(
        {
            "anyOf": [
                robot_spec_schema(),
                {
                    "type": "object",
                    "properties": {"catalog": {"type": "string"}},
                    "required": ["catalog"],
                    "additionalProperties": False,
                    "description": "A catalog robot, by name.",
                },
            ]
        }
    ),
]

#: The ``problem`` of a job spec in a response: its study kind and that kind's parameters.
_PROBLEM_OUT: dict[str, Any] = {
    "type": "object",
    "description": "The study kind and its parameters: the fields of that kind's "
    "`params_schema` (`GET /studies`), each study's own.",
    "properties": {"kind": {"type": "string", "description": "The study kind."}},
    "required": ["kind"],
    "additionalProperties": True,
}


@cache
def job_spec_out_schema() -> dict[str, Any]:
    """The JSON schema of a job spec in a response: legcore's ``JobSpec`` (inlined) with
    ``problem`` described as any study's parameters, so that the responses' schemas are the
    same whichever study plug-ins are installed (a request's ``JobSpecDoc`` lists them)."""
    schema = copy.deepcopy(job_spec_schema())
    schema["properties"]["problem"] = _PROBLEM_OUT
    schema["title"] = "JobSpecOut"
    schema["description"] = (
        "A job spec as stored: the fields it was submitted with (`POST /jobs` takes it), a "
        "stored robot resolved (`robot`, when given, is a catalog name or an inline DH/URDF "
        "robot spec)."
    )
    return schema


def _job_spec_out(schema: dict[str, Any]) -> None:
    schema.clear()
    schema.update(copy.deepcopy(job_spec_out_schema()))


class JobSpecOut(RootModel[dict[str, JsonValue]]):
    """A job spec as a response gives it: the stored JSON, passed on as stored (the fields it
    was submitted with; parsing it again would add every default), described by
    :func:`job_spec_out_schema` (one component of the OpenAPI document)."""

    model_config = ConfigDict(json_schema_extra=_job_spec_out)


#: A job's best objective(s) so far as the worker records them per generation: one value
#: per objective (null where it is not finite), or one number (rows written by hand).
BestObjective = float | list[float | None] | None

#: The config of a stored document passed on as stored (a ``TypedDict``): keys outside its
#: ``required`` may be absent (older rows lack the newer ones) and keys it does not name are
#: passed on too (a plug-in study's own). ``x-optional-keys`` tells the dashboard's type
#: generator (``services.web.api_types``) that an absent key is possible.
STORED_DOC = ConfigDict(extra="allow", json_schema_extra={"x-optional-keys": True})


class _In(BaseModel):
    model_config = ConfigDict(extra="forbid")


class ErrorOut(BaseModel):
    """Every non-validation error: ``{"detail": "message"}``."""

    detail: str


class Page(BaseModel, Generic[T]):
    """One page of a listing."""

    items: list[T]
    total: int = Field(description="Number of matching items (all pages).")
    limit: int
    offset: int


class HealthOut(BaseModel):
    """Liveness."""

    status: Literal["ok"] = "ok"


class ReadyOut(BaseModel):
    """Readiness: the database answers and its schema is at the head revision."""

    status: Literal["ready"] = "ready"
    revision: str
    warmup_s: float | None = Field(
        default=None,
        description="Seconds the validation warm-up at start took (null: none, "
        "LEGOPT_API_WARMUP off or an in-process app).",
    )
