"""Tables as CSV, JSON or Parquet files (the dashboard's and ``legopt export``'s downloads).

A table is its column names and an iterable of rows (tuples in column order). CSV and JSON are
written as they are read (a 10^5-job list streams page by page); Parquet (pyarrow, which
rerun-sdk already needs) is built in memory, column types inferred (numbers, strings, times).

Every CSV cell goes through :func:`csv_cell`: text that a spreadsheet would read as a formula
(starting with ``= + - @``, a tab or a carriage return: a job's name, a tag, a robot's or a
swept value, all the tenant's) gets a leading ``'`` (OWASP's advice against CSV injection);
numbers stay numbers (``-1.5`` written from a float is not text). Rows end in CRLF (RFC 4180),
so the ``csv`` module quotes a cell holding a separator, a quote, a line feed or a lone carriage
return (which a spreadsheet could otherwise take for the start of a new row).
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Iterable, Iterator, Mapping, Sequence
from datetime import datetime
from typing import Any, Literal

__all__ = [
    "FORMATS",
    "MEDIA_TYPES",
    "ExportFormat",
    "FILENAME_PATTERN",
    "Units",
    "csv_cell",
    "encode",
    "filename",
    "header",
]

ExportFormat = Literal["csv", "json", "parquet"]
FORMATS: tuple[str, ...] = ("csv", "json", "parquet")
MEDIA_TYPES = {
    "csv": "text/csv; charset=utf-8",
    "json": "application/json",
    "parquet": "application/vnd.apache.parquet",
}
#: Per column key, ``(unit, label)`` (unit "" when dimensionless or unknown).
Units = Mapping[str, tuple[str, str]]

#: What a spreadsheet reads as the start of a formula (OWASP, CSV injection).
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


def _cell(value: Any) -> Any:
    if isinstance(value, datetime):
        return value.isoformat()
    if isinstance(value, float) and value != value:
        return None
    if isinstance(value, list | tuple | dict):
        return json.dumps(value, separators=(",", ":"))
    return value


def csv_cell(value: Any) -> Any:
    """``value`` as a CSV cell: empty for None, times in ISO 8601, lists and mappings as JSON,
    and text starting like a formula (:data:`FORMULA_STARTS`) behind a ``'`` so that a
    spreadsheet shows it as text. Numbers (and booleans) are returned as they are, whatever
    their sign: only text is the tenant's."""
    value = None if value is None else _cell(value)
    if value is None:  # also NaN
        return ""
    if isinstance(value, str) and value.startswith(FORMULA_STARTS):
        return "'" + value
    return value


def header(column: str, units: Units) -> str:
    """A CSV header cell: ``key [unit]``, or ``key`` when it has no unit."""
    unit = units.get(column, ("", ""))[0]
    return f"{column} [{unit}]" if unit else column


def _csv(columns: Sequence[str], rows: Iterable[Sequence[Any]], units: Units) -> Iterator[bytes]:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\r\n")
    writer.writerow([csv_cell(header(c, units)) for c in columns])
    n = 0
    for row in rows:
        writer.writerow([csv_cell(v) for v in row])
        n += 1
        if n % 500 == 0:
            yield buf.getvalue().encode()
            buf.seek(0)
            buf.truncate()
    yield buf.getvalue().encode()


def _json(columns: Sequence[str], rows: Iterable[Sequence[Any]], units: Units) -> Iterator[bytes]:
    yield (
        b'{"columns":' + json.dumps(list(columns)).encode()
        + b',"units":' + json.dumps({c: units.get(c, ("", ""))[0] for c in columns}).encode()
        + b',"labels":' + json.dumps({c: units.get(c, ("", c))[1] for c in columns}).encode()
        + b',"rows":['
    )  # fmt: skip
    first = True
    for row in rows:
        items = [v.isoformat() if isinstance(v, datetime) else v for v in row]
        text = json.dumps(dict(zip(columns, items, strict=True)), default=str)
        yield (b"" if first else b",") + text.encode()
        first = False
    yield b"]}"


def _parquet(
    columns: Sequence[str], rows: Iterable[Sequence[Any]], units: Units
) -> Iterator[bytes]:
    import pyarrow as pa
    import pyarrow.parquet as pq

    data: list[list[Any]] = [[] for _ in columns]
    for row in rows:
        for i, v in enumerate(row):
            data[i].append(json.dumps(v) if isinstance(v, list | tuple | dict) else v)
    arrays = []
    for values in data:
        try:
            arrays.append(pa.array(values))
        except (pa.ArrowInvalid, pa.ArrowTypeError):  # mixed types: as text
            arrays.append(pa.array([None if v is None else str(v) for v in values]))
    fields = [
        pa.field(c, a.type, metadata={"unit": units.get(c, ("", ""))[0],
                                      "label": units.get(c, ("", c))[1]})
        for c, a in zip(columns, arrays, strict=True)
    ]  # fmt: skip
    meta = {
        "legopt.units": json.dumps({c: units.get(c, ("", ""))[0] for c in columns}),
        "legopt.labels": json.dumps({c: units.get(c, ("", c))[1] for c in columns}),
    }
    table = pa.Table.from_arrays(arrays, schema=pa.schema(fields, metadata=meta))
    out = io.BytesIO()
    pq.write_table(table, out)
    yield out.getvalue()


def encode(
    fmt: str, columns: Sequence[str], rows: Iterable[Sequence[Any]], units: Units | None = None
) -> Iterator[bytes]:
    """The bytes of the table in ``fmt`` (``csv``, ``json`` or ``parquet``), in chunks, with
    the columns' ``units`` and labels (module docstring)."""
    units = units or {}
    if fmt == "csv":
        return _csv(columns, rows, units)
    if fmt == "json":
        return _json(columns, rows, units)
    if fmt == "parquet":
        return _parquet(columns, rows, units)
    raise ValueError(f"format: expected one of {', '.join(FORMATS)}, got {fmt!r}")


#: How every export's file is named: ``legopt-<what>-<id8>.<format>`` (``id8``: the first 8
#: characters of the job or sweep id; the job list has none: ``legopt-jobs.csv``).
FILENAME_PATTERN = "legopt-<what>-<id8>.<format>"


def filename(what: str, fmt: str, ident: str | None = None) -> str:
    """The download's name (:data:`FILENAME_PATTERN`): ``legopt-front-1a2b3c4d.csv`` for
    ``what="front"`` of job ``1a2b3c4d-…``, ``legopt-jobs.parquet`` without ``ident``."""
    return f"legopt-{what}-{ident[:8]}.{fmt}" if ident else f"legopt-{what}.{fmt}"
