"""Robot models: what ``POST /robots`` and ``POST /robots/validate`` take, and the robots, their
model summaries and the catalog the robot routes answer with."""

from __future__ import annotations

from datetime import datetime
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, JsonValue, model_validator

from services.api.robot_validation import RobotSummary
from services.api.schemas.common import RobotDocOut, RobotSpecDoc, RobotSpecOut, _In

_DH_EXAMPLE: dict[str, JsonValue] = {
    "kind": "dh",
    "name": "two_link",
    "joints": [
        {
            "a": 0.3,
            "mass": 1.0,
            "com": [-0.15, 0, 0],
            "inertia": [[0.001, 0, 0], [0, 0.008, 0], [0, 0, 0.008]],
        },
        {
            "a": 0.25,
            "mass": 0.8,
            "com": [-0.125, 0, 0],
            "inertia": [[0.001, 0, 0], [0, 0.005, 0], [0, 0, 0.005]],
        },
    ],
}


class RobotValidate(_In):
    """A robot model: an inline DH/URDF ``spec`` or a ``catalog`` name (exactly one)."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={"examples": [{"spec": _DH_EXAMPLE}, {"catalog": "puma560"}]},
    )

    spec: RobotSpecDoc | None = Field(default=None, description="Inline DH or URDF robot spec.")
    catalog: str | None = Field(default=None, max_length=64, description="A catalog robot name.")

    @model_validator(mode="after")
    def _exactly_one(self) -> RobotValidate:
        if (self.spec is None) == (self.catalog is None):
            raise ValueError("give exactly one of 'spec' (an inline robot) or 'catalog' (a name)")
        return self


class RobotCreate(RobotValidate):
    """A robot to store under ``name`` (unique per API key)."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={
            "examples": [
                {"name": "my_arm", "spec": _DH_EXAMPLE},
                {"name": "puma", "catalog": "puma560"},
            ]
        },
    )

    name: str = Field(min_length=1, max_length=200)


class RobotSummaryOut(BaseModel):
    """What the built model looks like."""

    name: str
    kind: Literal["serial", "legged"]
    nq: int = Field(description="Degrees of freedom (all legs together for a legged robot).")
    joint_names: list[str]
    n_legs: int
    mass_kg: float = Field(description="Total mass of the links (and body), kg.")
    electrical_motors: int = Field(description="Joints with a full DC motor model (Kt, Ke, R).")

    @classmethod
    def from_summary(cls, s: RobotSummary) -> RobotSummaryOut:
        return cls(
            name=s.name,
            kind=s.kind,  # type: ignore[arg-type]
            nq=s.nq,
            joint_names=list(s.joint_names),
            n_legs=s.n_legs,
            mass_kg=s.mass_kg,
            electrical_motors=s.electrical_motors,
        )


RobotSource = Literal["catalog", "dh", "urdf"]


class RobotOut(BaseModel):
    """A robot in a listing. Catalog entries have ``builtin`` true and their name as id."""

    id: str
    name: str
    source: RobotSource
    catalog: str | None = Field(default=None, description="The catalog name (catalog robots).")
    builtin: bool = False
    created_at: datetime | None = None


class RobotDetail(RobotOut):
    """A robot with its spec and the summary of its built model."""

    spec: RobotDocOut = Field(description="The inline spec, or {'catalog': name}.")
    inline_spec: RobotSpecOut | None = Field(
        default=None,
        description="The model as an inline DH/URDF spec (serial robots, catalog ones too, and "
        "URDF legged robots): copy it to modify the robot, or use it as a sweep base to sweep "
        "its parameters. Null for the catalog's legged robots.",
    )
    summary: RobotSummaryOut


class RobotValidation(BaseModel):
    """Result of ``POST /robots/validate``: the model was validated and built."""

    valid: Literal[True] = True
    source: RobotSource
    summary: RobotSummaryOut


class CatalogEntry(BaseModel):
    """A robot of the catalog (from the seed papers)."""

    name: str
    kind: Literal["serial", "legged"]
    nq: int
    n_legs: int
    joint_names: list[str]
    source: str = Field(description="Provenance: the seed paper, tables and assumed values.")
