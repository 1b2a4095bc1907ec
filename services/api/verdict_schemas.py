"""The verdict of a job and the task it ran, as the API returns them (issue 25, item 2):
``ViolationOut`` (one violated constraint and by how much), ``TaskOut`` (the parameters a job
ran with on its robot and the rules that derived them), read from what the worker stores."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field, JsonValue

__all__ = [
    "FEASIBLE_DESCRIPTION",
    "GapOut",
    "VIOLATIONS_DESCRIPTION",
    "TaskOut",
    "ViolationOut",
    "feasible_of",
    "violations_out",
]


class ViolationOut(BaseModel):
    """One constraint a solution violates, and by how much (``legcore.studies.task.Violation``)."""

    constraint: str = Field(description="The constraint's name (a column of the study's G).")
    amount: float = Field(
        description="How far past its limit (> 0), in `unit`; for a ratio constraint (e.g. "
        "peak speed / limit - 1) the fraction over, with unit ''."
    )
    unit: str = Field(default="", description="Unit of `amount` ('' when a ratio or unknown).")
    text: str = Field(default="", description="In words, with the number.")


def violations_out(raw: Any) -> list[ViolationOut]:
    """The violations stored with a job or a solution summary (a list of dicts) as models;
    malformed entries are skipped."""
    out = []
    for v in raw if isinstance(raw, list) else []:
        if not isinstance(v, dict) or not isinstance(v.get("constraint"), str):
            continue
        amount = v.get("amount")
        if isinstance(amount, bool) or not isinstance(amount, int | float):
            continue
        unit, text = str(v.get("unit") or ""), str(v.get("text") or "")
        out.append(
            ViolationOut(constraint=v["constraint"], amount=float(amount), unit=unit, text=text)
        )
    return out


def feasible_of(doc: Any) -> bool | None:
    """The ``feasible`` flag of a stored solution summary (None when it was not checked)."""
    flag = doc.get("feasible") if isinstance(doc, dict) else None
    return flag if isinstance(flag, bool) else None


class TaskOut(BaseModel):
    """The task a job ran: the study's parameters with every robot-relative default filled in
    for its robot, and the rule that gave each derived value."""

    params: dict[str, JsonValue] = Field(
        description="The study parameters the job ran with (the fields of its kind's "
        "`params_schema` in `GET /studies`: any JSON, each study's own)."
    )
    rules: dict[str, str] = Field(
        default_factory=dict,
        description="Parameter -> the rule (words with numbers) that derived its value from "
        "the robot; the values the user gave and the preset's have none.",
    )
    preset: str | None = Field(
        default=None, description="The paper whose settings filled the unset fields, if any."
    )

    @classmethod
    def from_doc(cls, doc: Any) -> TaskOut | None:
        """From the ``task`` a worker stores in the result summary (None when absent)."""
        if not isinstance(doc, dict) or not isinstance(doc.get("params"), dict):
            return None
        rules = doc.get("rules")
        preset = doc.get("preset")
        return cls(
            params=doc["params"],
            rules={str(k): str(v) for k, v in rules.items()} if isinstance(rules, dict) else {},
            preset=preset if isinstance(preset, str) else None,
        )


FEASIBLE_DESCRIPTION = (
    "The verdict of a succeeded job: true when its reported optimum meets every constraint of "
    "the study, false when it violates one (see `violations`); null until the job succeeds "
    "(and for jobs finished before the service checked). `status` stays `succeeded` either way: "
    "the run completed."
)
VIOLATIONS_DESCRIPTION = "What the reported optimum violates (empty unless `feasible` is false)."


class GapOut(BaseModel):
    """How far a single-objective optimum is from the best its problem allows (an exact
    solution of the same problem, e.g. ``path_tracking``'s physical minimum by TOPP-RA), or
    why there is no such reference (``legcore.optimality_gap``)."""

    objective: str | None = Field(default=None, description="The objective compared.")
    value: float | None = Field(default=None, description="The optimum's value, its units.")
    reference: float | None = Field(
        default=None, description="The best value the problem allows (null: none known)."
    )
    kind: str | None = Field(default=None, description="What the reference is, in words.")
    method: str | None = Field(default=None, description="How the reference was computed.")
    pct: float | None = Field(
        default=None,
        description="100 (value - reference) / |reference| for a minimised objective: how "
        "much worse the optimum is (>= 0).",
    )
    reason: str | None = Field(default=None, description="Why there is no reference.")

    @classmethod
    def from_doc(cls, doc: Any) -> GapOut | None:
        """From the ``gap`` a worker stores in the result summary (None when absent)."""
        if not isinstance(doc, dict):
            return None

        def num(k: str) -> float | None:
            v = doc.get(k)
            return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else None

        def text(k: str) -> str | None:
            v = doc.get(k)
            return v if isinstance(v, str) else None

        return cls(
            objective=text("objective"),
            value=num("value"),
            reference=num("reference"),
            kind=text("kind"),
            method=text("method"),
            pct=num("pct"),
            reason=text("reason"),
        )
