"""Error shapes of the API and the handlers that produce them.

Two shapes only, both FastAPI's:

- validation errors (422): ``{"detail": [{"loc": [...], "msg": "...", "type": "..."}]}``; the
  location starts with ``"body"``, ``"query"``, ``"header"`` or ``"path"`` and then names the
  field, e.g. ``["body", "robot", "joints", 1, "inertia"]``. Every 422 has this shape: an
  ``HTTPException(422, "message")`` is answered as one error of that shape (``loc`` empty,
  ``type`` ``value_error``) — raise :func:`invalid` instead, which names the field;
- every other error: ``{"detail": "message"}`` (401, 403, 404, 409, 413, 429, 503, 500).

legcore reports a bad spec either as a pydantic ``ValidationError`` or as a ``ValueError`` whose
message starts with the field (``"urdf: not well-formed XML"``); :func:`from_pydantic` and
:func:`from_value_error` turn both into a ``RequestValidationError`` with a proper ``loc``.
Store errors map to statuses in :func:`install_error_handlers`; anything unexpected becomes a
logged 500 with a short message (user input never gets there: it is validated first).
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Iterable, Sequence
from typing import Any

from fastapi import FastAPI, HTTPException, Request, status
from fastapi.exception_handlers import http_exception_handler
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from pydantic import ValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException

from services.api.security_headers import SECURITY_HEADERS
from services.store.errors import (
    ArtifactError,
    ArtifactMissingError,
    ArtifactUnavailableError,
    ConflictError,
    NotFoundError,
)

log = logging.getLogger("legopt.api")

Loc = tuple[str | int, ...]

#: The OpenAPI schema of a 422 body (FastAPI's ``HTTPValidationError``), for a route that
#: documents its own 422s.
VALIDATION_ERROR_SCHEMA = {"$ref": "#/components/schemas/HTTPValidationError"}

#: How many errors one response lists at most (a sweep of 1000 bad jobs stays readable).
MAX_ERRORS = 20

# "field.path: reason" at the start of a legcore message (no spaces in the field path).
_FIELD_MESSAGE = re.compile(r"^(?P<field>[A-Za-z_][\w-]*(?:\.[\w-]+)*): (?P<reason>.+)$", re.S)
_VALUE_ERROR_PREFIX = "Value error, "


def loc_parts(dotted: str) -> Loc:
    """``"joints.1.inertia"`` -> ``("joints", 1, "inertia")`` (digit segments become ints)."""
    return tuple(int(p) if p.isdigit() else p for p in dotted.split(".") if p)


def split_field_message(message: str) -> tuple[Loc, str]:
    """Split ``"field.path: reason"`` into ``(("field", "path"), "reason")``.

    A message that does not start with a field path comes back as ``((), message)``.
    """
    m = _FIELD_MESSAGE.match(message.strip())
    if m is None:
        return (), message
    return loc_parts(m.group("field")), m.group("reason")


def field_error(loc: Sequence[str | int], msg: str, type_: str = "value_error") -> dict[str, Any]:
    """One validation error entry."""
    return {"type": type_, "loc": list(loc), "msg": msg}


def validation_error(errors: Iterable[dict[str, Any]]) -> RequestValidationError:
    """A 422 carrying ``errors`` (at most ``MAX_ERRORS``)."""
    return RequestValidationError(list(errors)[:MAX_ERRORS])


def invalid(
    loc: Sequence[str | int], msg: str, type_: str = "value_error"
) -> RequestValidationError:
    """A 422 with one error at ``loc``."""
    return validation_error([field_error(loc, msg, type_)])


def _is_internal_loc_part(part: str | int) -> bool:
    """Pydantic's names of union members in a location (``tagged-union[...]``, ``str``...)."""
    return isinstance(part, str) and ("[" in part or part in {"str", "int", "float", "bool"})


def clean_pydantic_errors(
    exc: ValidationError, prefix: Loc = (), locs: Sequence[Sequence[str | int]] | None = None
) -> list[dict[str, Any]]:
    """The errors of ``exc`` as plain JSON entries located under ``prefix``.

    Locations (``locs[i]`` when given: one per error, e.g. from
    ``legcore.jobspec.spec_error_locations``) drop pydantic's internal union member names, and a
    ``value_error`` whose message starts with a field path (``"params.pop_size: must be >= 2"``)
    gets that path appended to its location. Inputs and contexts are left out (they may be
    large or not JSON).
    """
    out: list[dict[str, Any]] = []
    raw = exc.errors(include_url=False, include_context=False, include_input=False)
    for i, err in enumerate(raw):
        given = locs[i] if locs is not None else err["loc"]
        loc: Loc = tuple(p for p in given if not _is_internal_loc_part(p))
        msg = str(err["msg"])
        if err["type"] == "value_error" and msg.startswith(_VALUE_ERROR_PREFIX):
            msg = msg[len(_VALUE_ERROR_PREFIX) :]
            sub, reason = split_field_message(msg)
            if sub:
                loc, msg = loc + sub, reason
        out.append(field_error(prefix + loc, msg, str(err["type"])))
    return out


def from_pydantic(exc: ValidationError, prefix: Loc = ()) -> RequestValidationError:
    """A 422 from a pydantic ``ValidationError`` raised while validating the field ``prefix``."""
    return validation_error(clean_pydantic_errors(exc, prefix))


def from_value_error(
    exc: BaseException, prefix: Loc = (), default_loc: Loc | None = None
) -> RequestValidationError:
    """A 422 from a legcore ``ValueError("field: reason")`` raised for the field ``prefix``.

    Without a field in the message the error is located at ``default_loc`` (default: ``prefix``).
    """
    message = str(exc) or type(exc).__name__
    sub, reason = split_field_message(message)
    if not sub:
        return invalid(prefix if default_loc is None else default_loc, message)
    return invalid(prefix + sub, reason)


# --------------------------------------------------------------------------- handlers


def _detail(status_code: int, message: str, headers: dict[str, str] | None = None) -> JSONResponse:
    return JSONResponse(status_code=status_code, content={"detail": message}, headers=headers)


def _text(value: Any) -> str:
    """``str(value)`` encodable as UTF-8 (a lone surrogate from the input becomes ``\\udXXX``)."""
    return str(value).encode("utf-8", "backslashreplace").decode("utf-8")


def _json_safe(value: Any, depth: int = 0) -> Any:
    """``value`` with anything JSON cannot carry (NaN, bytes, objects) turned into text."""
    if isinstance(value, str):
        return _text(value)
    if value is None or isinstance(value, bool | int):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else repr(value)
    if depth < 4 and isinstance(value, dict):
        return {str(k): _json_safe(v, depth + 1) for k, v in value.items()}
    if depth < 4 and isinstance(value, list | tuple):
        return [_json_safe(v, depth + 1) for v in value]
    return _text(value)[:200]


def public_errors(errors: Sequence[Any]) -> list[dict[str, Any]]:
    """Validation errors as the API answers them: ``type``, ``loc``, ``msg`` (and ``ctx`` made
    JSON-safe). The offending ``input`` is never echoed back: it may be large (a URDF), not
    JSON at all (bytes, NaN) or another part of the request the client already has."""
    out: list[dict[str, Any]] = []
    for err in list(errors)[:MAX_ERRORS]:
        if not isinstance(err, dict):
            out.append(field_error([], str(err)))
            continue
        entry = {
            "type": _text(err.get("type", "value_error")),
            "loc": [p if isinstance(p, int) else _text(p) for p in err.get("loc", ())],
            "msg": _text(err.get("msg", "")),
        }
        if isinstance(err.get("ctx"), dict):
            entry["ctx"] = _json_safe(err["ctx"])
        out.append(entry)
    return out


async def _request_invalid(_request: Request, exc: Exception) -> JSONResponse:
    errors = exc.errors() if isinstance(exc, RequestValidationError) else []
    return JSONResponse(
        status_code=status.HTTP_422_UNPROCESSABLE_CONTENT, content={"detail": public_errors(errors)}
    )


async def _http_error(request: Request, exc: Exception) -> Response:
    """FastAPI's answer to an ``HTTPException``, except that a 422 whose detail is a message
    (not a list of errors) is answered in the validation errors' shape, like every 422."""
    assert isinstance(exc, StarletteHTTPException)
    if exc.status_code == status.HTTP_422_UNPROCESSABLE_CONTENT and not isinstance(
        exc.detail, list
    ):
        errors = [field_error([], str(exc.detail))]
        return JSONResponse(
            status_code=exc.status_code,
            content={"detail": public_errors(errors)},
            headers=exc.headers,
        )
    return await http_exception_handler(request, exc)


async def _not_found(_request: Request, exc: Exception) -> JSONResponse:
    return _detail(status.HTTP_404_NOT_FOUND, str(exc) or "not found")


async def _conflict(_request: Request, exc: Exception) -> JSONResponse:
    return _detail(status.HTTP_409_CONFLICT, str(exc) or "conflict")


async def _artifact(_request: Request, exc: Exception) -> JSONResponse:
    log.error("artifact store error: %s", exc)
    return _detail(status.HTTP_500_INTERNAL_SERVER_ERROR, f"artifact store error: {exc}")


#: Seconds a client is asked to wait before retrying when the artifact store is unreachable.
ARTIFACT_RETRY_AFTER_S = 30


async def _artifact_missing(_request: Request, exc: Exception) -> JSONResponse:
    log.warning("artifact missing: %s", exc)
    return _detail(status.HTTP_404_NOT_FOUND, str(exc))


async def _artifact_unavailable(_request: Request, exc: Exception) -> JSONResponse:
    log.error("artifact store unavailable: %s", exc)
    return _detail(
        status.HTTP_503_SERVICE_UNAVAILABLE,
        f"{exc}; retry in {ARTIFACT_RETRY_AFTER_S} s",
        headers={"Retry-After": str(ARTIFACT_RETRY_AFTER_S)},
    )


async def _unexpected(request: Request, exc: Exception) -> JSONResponse:
    log.exception("unhandled error on %s %s", request.method, request.url.path, exc_info=exc)
    return _detail(  # sent from outside every middleware: its own security headers
        status.HTTP_500_INTERNAL_SERVER_ERROR,
        "internal server error (logged); please report it with the time of the request",
        headers=dict(SECURITY_HEADERS),
    )


def install_error_handlers(app: FastAPI) -> None:
    """422 for request validation errors (JSON-safe, see ``public_errors``) and for an
    ``HTTPException(422, ...)`` (the same shape); store errors to 404 / 409 / 500 (an artifact
    whose file or object is gone: 404 naming it; an artifact store that cannot be reached: 503
    with ``Retry-After``) and anything unexpected to a logged 500."""
    app.add_exception_handler(RequestValidationError, _request_invalid)
    app.add_exception_handler(StarletteHTTPException, _http_error)
    app.add_exception_handler(NotFoundError, _not_found)
    app.add_exception_handler(ConflictError, _conflict)
    app.add_exception_handler(ArtifactError, _artifact)
    app.add_exception_handler(ArtifactMissingError, _artifact_missing)
    app.add_exception_handler(ArtifactUnavailableError, _artifact_unavailable)
    app.add_exception_handler(Exception, _unexpected)


def not_found(what: str, ident: str) -> HTTPException:
    """The 404 of a missing resource (also for a resource of another API key)."""
    return HTTPException(status.HTTP_404_NOT_FOUND, f"{what} {ident!r} not found")


__all__ = [
    "MAX_ERRORS",
    "VALIDATION_ERROR_SCHEMA",
    "clean_pydantic_errors",
    "field_error",
    "from_pydantic",
    "from_value_error",
    "install_error_handlers",
    "invalid",
    "loc_parts",
    "not_found",
    "public_errors",
    "split_field_message",
    "validation_error",
]
