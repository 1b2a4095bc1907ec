"""ASGI middleware refusing JSON request bodies that are valid to Python but not to the API.

Python's ``json`` accepts what JSON (RFC 8259) does not — ``NaN``, ``Infinity``, ``-Infinity``,
and literals beyond the float range such as ``1e309`` (parsed as ``inf``) — and parses nesting
up to the interpreter's recursion limit, after which every recursive step of a request
(``copy.deepcopy`` of a sweep base, pydantic, ``json.dumps`` into the store) can raise
``RecursionError``. Neither is meaningful in a job spec, a robot or a sweep, so this middleware
checks every JSON body once, before any route (or anything recursive) sees it:

- nesting deeper than ``max_depth`` arrays/objects -> 422 ``json_too_deep`` located at the
  first container past the limit (``["body", "grid", "problem.x", 0, 0, ...]``);
- a non-finite number -> 422 ``finite_number`` located at each such value
  (``["body", "seeds", 0]``);
- an integer literal longer than Python converts (4300 digits) or bytes that are not UTF-8
  -> 422 ``json_invalid`` (FastAPI would answer 400 without a location);
- a NUL character (``\\u0000``) in any string or key -> 422 ``nul_character`` at each: no
  field has a use for it and PostgreSQL's text cannot store it (psycopg raises, which was a 500).

The same NUL rule covers every request, JSON or not: a NUL in the path (``/jobs/%00x``) is a 404
(no id holds one), in a query parameter a 422 at ``["query", name]``.

Malformed JSON is left to FastAPI (its 422 ``json_invalid`` names the character position).
Bodies are JSON when their ``Content-Type`` is ``application/json`` or ``application/*+json``,
exactly the bodies FastAPI parses as JSON. The guard runs inside ``BodySizeLimitMiddleware``, so
it never buffers more than the body limit; large bodies are checked in a worker thread so the
event loop keeps serving (e.g. ``/health``) meanwhile.
"""

from __future__ import annotations

import email.message
import json
import math
from collections.abc import Iterator
from typing import Any

import anyio.to_thread
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from services.api.errors import MAX_ERRORS

#: Deepest nesting of arrays/objects accepted in a request body (a job spec needs about 8).
MAX_JSON_DEPTH = 64

#: Bodies at least this large are checked in a worker thread (bytes).
THREAD_THRESHOLD_BYTES = 64 * 1024

Loc = tuple[str | int, ...]


def is_json_content_type(value: str | None) -> bool:
    """True for ``application/json`` and ``application/*+json`` (with any parameters)."""
    if not value:
        return False
    message = email.message.Message()
    message["content-type"] = value
    if message.get_content_maintype() != "application":
        return False
    subtype = message.get_content_subtype()
    return subtype == "json" or subtype.endswith("+json")


def _error(loc: Loc, msg: str, type_: str) -> dict[str, Any]:
    return {"type": type_, "loc": ["body", *loc], "msg": msg}


def _too_deep_message(max_depth: int) -> str:
    return (
        f"JSON nested more than {max_depth} arrays/objects deep here; the API accepts at most "
        f"{max_depth} levels: flatten this value"
    )


_NON_FINITE_MESSAGE = (
    "not a finite number: NaN, Infinity, -Infinity and literals beyond ±1.8e308 (e.g. 1e309) "
    "are not valid JSON numbers; send a finite number"
)


def _children(node: Any) -> Iterator[tuple[str | int, Any]]:
    if isinstance(node, dict):
        yield from node.items()
    else:
        yield from enumerate(node)


def _is_non_finite(value: Any) -> bool:
    return type(value) is float and not math.isfinite(value)


_NUL_MESSAGE = "contains a NUL character (\\u0000), which no field accepts: remove it"


def _has_nul(value: Any) -> bool:
    return type(value) is str and "\x00" in value


def _needs_report(doc: Any, max_depth: int) -> bool:
    """Fast pass (no locations): does ``doc`` nest too deep or hold a non-finite number?"""
    if _is_non_finite(doc):
        return True
    stack: list[tuple[Any, int]] = [(doc, 1)] if isinstance(doc, dict | list) else []
    pop, push = stack.pop, stack.append
    while stack:
        node, depth = pop()
        if depth > max_depth:
            return True
        for value in node.values() if type(node) is dict else node:
            kind = type(value)
            if kind is dict or kind is list:
                push((value, depth + 1))
            elif kind is float and not math.isfinite(value):
                return True
    return False


def _locate(doc: Any, max_depth: int, nul: bool = False) -> list[dict[str, Any]]:
    """Errors (at most ``MAX_ERRORS``) of a document ``_needs_report`` flagged, in order;
    with ``nul`` also every string value or object key holding a NUL."""
    if _is_non_finite(doc):
        return [_error((), _NON_FINITE_MESSAGE, "finite_number")]
    if nul and _has_nul(doc):
        return [_error((), _NUL_MESSAGE, "nul_character")]
    errors: list[dict[str, Any]] = []
    stack: list[tuple[Any, Loc]] = [(doc, ())]
    while stack and len(errors) < MAX_ERRORS:
        node, loc = stack.pop()
        if len(loc) >= max_depth:  # ``node`` is container number len(loc) + 1 on its path
            errors.append(_error(loc, _too_deep_message(max_depth), "json_too_deep"))
            break
        nested: list[tuple[Any, Loc]] = []
        for key, value in _children(node):
            if nul and _has_nul(key):
                errors.append(_error((*loc, key), _NUL_MESSAGE, "nul_character"))
            if isinstance(value, dict | list):
                nested.append((value, (*loc, key)))
            elif _is_non_finite(value):
                errors.append(_error((*loc, key), _NON_FINITE_MESSAGE, "finite_number"))
            elif nul and _has_nul(value):
                errors.append(_error((*loc, key), _NUL_MESSAGE, "nul_character"))
        stack.extend(reversed(nested))  # depth first, in document order
    return errors[:MAX_ERRORS]


def check_json_body(body: bytes, max_depth: int = MAX_JSON_DEPTH) -> list[dict[str, Any]]:
    """Validation errors (FastAPI's shape, ``loc`` starting with ``"body"``) of a JSON body;
    empty when the body is acceptable or malformed (FastAPI reports malformed JSON itself)."""
    try:
        doc = json.loads(body)
    except RecursionError:
        return [_error((), _too_deep_message(max_depth), "json_too_deep")]
    except json.JSONDecodeError:
        return []
    except UnicodeDecodeError as exc:
        msg = f"invalid {exc.encoding} at byte {exc.start}: send the JSON text as UTF-8"
        return [_error((exc.start,), msg, "json_invalid")]
    except ValueError as exc:  # an integer literal over sys.get_int_max_str_digits()
        return [_error((), f"JSON number out of range: {exc}", "json_invalid")]
    nul = b"\\u0000" in body  # JSON escapes every NUL in a string this way: a cheap test
    if not nul and not _needs_report(doc, max_depth):
        return []
    return _locate(doc, max_depth, nul)


class JsonGuardMiddleware:
    """Answer 422 to JSON bodies nested deeper than ``max_depth`` or holding non-finite numbers
    (see the module docstring); every other request passes through with its body replayed."""

    def __init__(self, app: ASGIApp, max_depth: int = MAX_JSON_DEPTH) -> None:
        self.app = app
        self.max_depth = int(max_depth)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] == "http" and "\x00" in scope.get("path", ""):
            await _send_json(send, 404, {"detail": "not found: no id contains a NUL character"})
            return
        if scope["type"] == "http" and (query := _nul_query_errors(scope)):
            await _send_422(send, query)
            return
        if scope["type"] != "http" or not is_json_content_type(_content_type(scope)):
            await self.app(scope, receive, send)
            return
        chunks: list[bytes] = []
        while True:
            message = await receive()
            if message["type"] != "http.request":  # client went away: let the app see it
                await self.app(scope, _replay([], message, receive), send)
                return
            chunks.append(message.get("body", b""))
            if not message.get("more_body", False):
                break
        body = b"".join(chunks)
        errors: list[dict[str, Any]] = []
        if body:
            if len(body) >= THREAD_THRESHOLD_BYTES:
                errors = await anyio.to_thread.run_sync(check_json_body, body, self.max_depth)
            else:
                errors = check_json_body(body, self.max_depth)
        if errors:
            await _send_422(send, errors)
            return
        await self.app(scope, _replay([body], None, receive), send)


def _content_type(scope: Scope) -> str | None:
    for name, value in scope.get("headers", []):
        if name == b"content-type":
            return bytes(value).decode("latin-1")
    return None


def _replay(chunks: list[bytes], pending: Message | None, receive: Receive) -> Receive:
    """A ``receive`` answering the buffered body (or ``pending``) first, then the real one."""
    queue: list[Message] = (
        [pending] if pending is not None else [{"type": "http.request", "body": b"".join(chunks)}]
    )

    async def replay() -> Message:
        if queue:
            return queue.pop(0)
        return await receive()

    return replay


def _nul_query_errors(scope: Scope) -> list[dict[str, Any]]:
    """A 422 error per query parameter whose name or value holds a NUL."""
    raw = bytes(scope.get("query_string", b""))
    if b"%00" not in raw and b"\x00" not in raw:
        return []
    from urllib.parse import parse_qsl

    pairs = parse_qsl(raw.decode("latin-1"), keep_blank_values=True)
    return [
        {"type": "nul_character", "loc": ["query", name.replace("\x00", "")],
         "msg": _NUL_MESSAGE}
        for name, value in pairs if "\x00" in name or "\x00" in value
    ][:MAX_ERRORS]  # fmt: skip


async def _send_422(send: Send, errors: list[dict[str, Any]]) -> None:
    await _send_json(send, 422, {"detail": errors})


async def _send_json(send: Send, status: int, doc: Any) -> None:
    body = json.dumps(
        doc, ensure_ascii=False, allow_nan=False, separators=(",", ":")
    ).encode("utf-8")
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [
                (b"content-type", b"application/json"),
                (b"content-length", str(len(body)).encode()),
            ],
        }
    )
    await send({"type": "http.response.body", "body": body})


__all__ = [
    "MAX_JSON_DEPTH",
    "JsonGuardMiddleware",
    "check_json_body",
    "is_json_content_type",
]
