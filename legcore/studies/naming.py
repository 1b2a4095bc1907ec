"""The display records of result keys: :class:`MetricName` (one key) and :class:`StudyDisplay`
(a study's one-block summary). Each study package's ``metrics.py`` fills them in;
:mod:`legcore.studies.metric_names` looks them up."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

__all__ = ["Kind", "MetricName", "Sense", "StudyDisplay"]

Sense = Literal["min", "max", ""]
Kind = Literal["value", "flag"]


@dataclass(frozen=True)
class MetricName:
    """How to show one result key.

    ``label``: readable name; ``unit``: SI unit ("" when dimensionless); ``sense``: "min" or
    "max" when smaller/larger is better, "" otherwise; ``paper``: the paper's own symbol;
    ``kind``: "flag" for 0/1 values (shown yes/no); ``same_as``: the key whose number this
    repeats (then hidden in tables); ``note``: what a reader must know (a different formula).
    """

    label: str
    unit: str = ""
    sense: Sense = ""
    paper: str = ""
    kind: Kind = "value"
    same_as: str | None = None
    note: str = ""


@dataclass(frozen=True)
class StudyDisplay:
    """What a study's one-block summary shows.

    ``task``: what the optimiser chooses; ``start``: the baseline shown as the starting point
    (the solution the optimum improves on); ``headline``: the metric keys shown after the
    objectives, in order.
    """

    task: str
    start: str | None
    headline: tuple[str, ...]
