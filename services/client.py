"""A small HTTP client of the LegOpt API (used by the CLI, the demo and the integration tests).

c = Client.from_env()             # LEGOPT_API_URL, LEGOPT_API_KEY or ./legopt-data/api-key
job = c.submit(spec)              # {"id": ..., "status": "queued", ...}; safe to retry
job = c.wait(job["id"])           # polls until succeeded | failed | cancelled
c.result(job["id"]); c.pareto(job["id"]); c.recording(job["id"])
c.ids_with_prefix("jobs", "2253")  # the full ids of your jobs starting with a prefix
"""

from __future__ import annotations

import os
import re
import time
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any
from urllib.parse import quote

import httpx

__all__ = ["ApiError", "Client", "TERMINAL", "is_full_id"]

TERMINAL = frozenset({"succeeded", "failed", "cancelled"})
DEFAULT_URL = "http://127.0.0.1:8000"
#: Attempts of a creating POST when the connection fails or the server answers 502/503/504
#: (each attempt sends the same Idempotency-Key, so the resource is created once).
CREATE_ATTEMPTS = 5
#: A 429 whose ``Retry-After`` is at most this (s) is waited out and retried; a longer one
#: (a quota: a slot frees in 30 s, the next hour) is the caller's to decide.
MAX_RETRY_AFTER_S = 10.0
#: How long (s) a creating POST keeps coming back when the server asks it to (429 with a short
#: ``Retry-After``: its earlier attempt is still being validated, which on a busy machine can
#: take a while); counted apart from ``CREATE_ATTEMPTS``.
COME_BACK_WINDOW_S = 180.0
_RETRY_STATUS = frozenset({502, 503, 504})
_FULL_ID = re.compile(r"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}", re.I)
#: Page size when listing ids (the API's largest page).
_PAGE = 1000
#: Length of a whole id (a UUID): no id starts with anything longer.
_ID_LENGTH = 36


def is_full_id(text: str) -> bool:
    """True for a whole job/sweep id (a UUID), False for a prefix."""
    return _FULL_ID.fullmatch(text) is not None


class ApiError(Exception):
    """An HTTP error answer: ``status`` code, the server's ``detail`` and its ``Retry-After``
    (seconds; None when the answer has none)."""

    def __init__(self, status: int, detail: Any, retry_after: float | None = None) -> None:
        self.status = status
        self.detail = detail
        self.retry_after = retry_after
        super().__init__(f"HTTP {status}: {format_detail(detail)}")


def format_detail(detail: Any) -> str:
    """FastAPI's ``detail`` (a string or a list of ``{loc, msg}``) as ``field: reason`` lines."""
    if isinstance(detail, list):
        lines = []
        for d in detail:
            if isinstance(d, dict):
                loc = ".".join(str(p) for p in d.get("loc", []) if p != "body")
                lines.append(f"{loc}: {d.get('msg', '')}" if loc else str(d.get("msg", "")))
            else:
                lines.append(str(d))
        return "; ".join(lines)
    return str(detail)


class Client:
    """Thin wrapper over ``httpx.Client`` with the API key header and error mapping."""

    def __init__(self, url: str = DEFAULT_URL, key: str | None = None, timeout: float = 60.0):
        headers = {"X-API-Key": key} if key else {}
        self.url = url.rstrip("/")
        self.http = httpx.Client(base_url=self.url + "/api/v1", headers=headers, timeout=timeout)

    @classmethod
    def from_env(cls, url: str | None = None, key: str | None = None) -> Client:
        """URL from ``LEGOPT_API_URL`` (default localhost:8000); key from ``LEGOPT_API_KEY`` or
        the embedded default's ``<LEGOPT_DATA_DIR or ./legopt-data>/api-key``."""
        url = url or os.environ.get("LEGOPT_API_URL", DEFAULT_URL)
        if key is None:
            key = os.environ.get("LEGOPT_API_KEY")
        if key is None:
            path = Path(os.environ.get("LEGOPT_DATA_DIR", "legopt-data")) / "api-key"
            if path.exists():
                key = path.read_text().strip()
        return cls(url, key)

    def close(self) -> None:
        self.http.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ plumbing
    def _req(self, method: str, path: str, **kw: Any) -> httpx.Response:
        resp = self.http.request(method, path, **kw)
        if resp.status_code >= 400:
            try:
                detail = resp.json().get("detail", resp.text)
            except ValueError:
                detail = resp.text
            try:
                retry_after: float | None = float(resp.headers["Retry-After"])
            except (KeyError, ValueError):
                retry_after = None
            raise ApiError(resp.status_code, detail, retry_after)
        return resp

    def get(self, path: str, **params: Any) -> Any:
        return self._req("GET", path, params=params or None).json()

    def post(self, path: str, body: Any = None) -> Any:
        """POST ``body``; a 429 with a short ``Retry-After`` (the server did nothing: e.g. this
        key's previous submission is still being validated) is sent again after the wait, for
        up to ``COME_BACK_WINDOW_S``."""
        return self._post_coming_back(path, body, time.monotonic() + COME_BACK_WINDOW_S)

    def _post_coming_back(
        self, path: str, body: Any, until: float, headers: dict[str, str] | None = None
    ) -> Any:
        """POST ``body``, sent again after the wait while the server answers 429 with a short
        ``Retry-After`` (at most ``MAX_RETRY_AFTER_S``) that ends before ``until`` (a
        ``time.monotonic()``); any other error, or a longer wait, is raised."""
        while True:
            try:
                return self._req("POST", path, json=body, headers=headers).json()
            except ApiError as exc:
                wait = exc.retry_after if exc.retry_after is not None else -1.0
                if exc.status != 429 or not 0 <= wait <= MAX_RETRY_AFTER_S:
                    raise
                if time.monotonic() + wait > until:
                    raise
                time.sleep(wait)

    def create(self, path: str, body: Any, *, idempotency_key: str | None = None) -> Any:
        """POST that creates a resource, retried when the request may or may not have reached
        the server (connection errors, timeouts, 502/503/504) or the server asks to come back
        (429 with ``Retry-After``: e.g. the same request still being validated after a timed
        out attempt): every attempt carries the same ``Idempotency-Key``, so the server creates
        it once and a retry returns it."""
        headers = {"Idempotency-Key": idempotency_key or uuid.uuid4().hex}
        delay = 0.5
        failures = 0
        come_back_until = time.monotonic() + COME_BACK_WINDOW_S
        while True:
            try:
                return self._post_coming_back(path, body, come_back_until, headers)
            except httpx.TransportError:
                failures += 1
                if failures >= CREATE_ATTEMPTS:
                    raise
            except ApiError as exc:
                failures += 1
                if exc.status not in _RETRY_STATUS or failures >= CREATE_ATTEMPTS:
                    raise
            time.sleep(delay)
            delay = min(delay * 2, 5.0)
    # ------------------------------------------------------------------ endpoints
    def health(self) -> dict[str, Any]:
        return dict(self.get("/health"))

    def submit(self, spec: dict[str, Any], *, idempotency_key: str | None = None) -> dict[str, Any]:
        """Submit a job; retried safely on connection errors (see :meth:`create`)."""
        return dict(self.create("/jobs", spec, idempotency_key=idempotency_key))

    def job(self, job_id: str) -> dict[str, Any]:
        return dict(self.get(f"/jobs/{job_id}"))

    def jobs(self, **params: Any) -> dict[str, Any]:
        return dict(self.get("/jobs", **params))

    def result(self, job_id: str) -> dict[str, Any]:
        return dict(self.get(f"/jobs/{job_id}/result"))

    def pareto(self, job_id: str, limit: int = 1000) -> dict[str, Any]:
        return dict(self.get(f"/jobs/{job_id}/pareto", limit=limit))

    def generations(self, job_id: str, limit: int = 1000) -> dict[str, Any]:
        return dict(self.get(f"/jobs/{job_id}/generations", limit=limit))

    def _download(self, path: str) -> bytes:
        """The body of a download, following a 307 to a presigned URL of the artifact store
        (``LEGOPT_ARTIFACTS_PRESIGN``) without the API key."""
        resp = self._req("GET", path)
        if resp.status_code != 307 or "location" not in resp.headers:
            return resp.content
        with httpx.Client(timeout=self.http.timeout) as plain:
            direct = plain.get(resp.headers["location"])
        if direct.status_code >= 400:
            raise ApiError(direct.status_code, f"artifact store: {direct.text[:200]}")
        return direct.content

    def recording(self, job_id: str) -> bytes:
        return self._download(f"/jobs/{job_id}/recording")

    def point_recording(self, job_id: str, k: int, *, wait_s: float = 120.0) -> bytes:
        """The recording of point ``k`` of a job's Pareto front (made on demand by the API;
        a 503 while another one is being made is retried until ``wait_s`` seconds)."""
        deadline = time.monotonic() + wait_s
        while True:
            try:
                return self._download(f"/jobs/{job_id}/pareto/{k}/recording")
            except ApiError as exc:
                if exc.status != 503 or time.monotonic() > deadline:
                    raise
                time.sleep(2.0)

    def delete_job(self, job_id: str) -> None:
        """Delete a finished job and everything stored for it (409 while queued or running)."""
        self._req("DELETE", f"/jobs/{job_id}")

    def delete_sweep(self, sweep_id: str) -> None:
        """Delete a finished sweep: every job of it with everything stored for them, then the
        sweep (409 while any of its jobs is queued or running)."""
        self._req("DELETE", f"/sweeps/{sweep_id}")

    def delete_robot(self, robot_id: str) -> None:
        """Delete one of your stored robots (by id)."""
        self._req("DELETE", f"/robots/{quote(robot_id, safe='')}")

    def cancel(self, job_id: str) -> dict[str, Any]:
        return dict(self.post(f"/jobs/{job_id}/cancel"))

    def cancel_sweep(self, sweep_id: str) -> dict[str, Any]:
        """Cancel every unfinished job of a sweep in one request: the sweep's counts and how
        many jobs were ``cancelled``, are ``stopping`` or had ``already_finished``."""
        return dict(self.post(f"/sweeps/{sweep_id}/cancel"))

    def sweep(self, doc: dict[str, Any], *, idempotency_key: str | None = None) -> dict[str, Any]:
        """Create a sweep; retried safely on connection errors (see :meth:`create`)."""
        return dict(self.create("/sweeps", doc, idempotency_key=idempotency_key))

    def sweep_recording(self, sweep_id: str, jobs: list[str] | None = None) -> bytes:
        """One .rrd merging the chosen jobs of a sweep (default: all with a recording)."""
        params = {"jobs": jobs} if jobs else None
        return self._req("GET", f"/sweeps/{sweep_id}/recording", params=params).content

    def get_sweep(self, sweep_id: str, **params: Any) -> dict[str, Any]:
        return dict(self.get(f"/sweeps/{sweep_id}", **params))

    def sweeps(self, **params: Any) -> dict[str, Any]:
        return dict(self.get("/sweeps", **params))

    def ids_with_prefix(self, collection: str, prefix: str) -> list[str]:
        """The ids of your ``collection`` ("jobs" or "sweeps") that start with ``prefix``
        (case-insensitive): the listing filtered by the server (``id_prefix``, a range of the
        primary key's index), so one request unless more than a page of ids share the prefix
        (a server without the filter sends every id: they are filtered here too)."""
        prefix = prefix.lower()
        if len(prefix) > _ID_LENGTH:
            return []
        out: list[str] = []
        offset = 0
        while True:
            params: dict[str, Any] = {"limit": _PAGE, "offset": offset}
            if prefix:
                params["id_prefix"] = prefix
            page = self.get(f"/{collection}", **params)
            items = page.get("items") or []
            out.extend(str(i["id"]) for i in items if str(i["id"]).lower().startswith(prefix))
            offset += len(items)
            if not items or offset >= int(page.get("total", 0)):
                return out

    def add_robot(
        self, name: str, spec: dict[str, Any], *, idempotency_key: str | None = None
    ) -> dict[str, Any]:
        """Store an inline robot ``spec`` under ``name`` (validated and built by the server);
        retried safely on connection errors (see :meth:`create`)."""
        body = {"name": name, "spec": spec}
        return dict(self.create("/robots", body, idempotency_key=idempotency_key))

    def robots(
        self, *, include_catalog: bool = False, limit: int = 100, offset: int = 0
    ) -> dict[str, Any]:
        """One page of your robots (``{"items", "total", "limit", "offset"}``)."""
        params = {"include_catalog": include_catalog, "limit": limit, "offset": offset}
        return dict(self.get("/robots", **params))

    def robot(self, robot_id: str) -> dict[str, Any]:
        """One robot (yours by id, or a catalog name): spec, summary and capabilities."""
        return dict(self.get(f"/robots/{quote(robot_id, safe='')}"))

    def wait(
        self,
        job_id: str,
        *,
        poll_s: float = 0.5,
        timeout_s: float | None = None,
        on_update: Callable[[dict[str, Any]], None] | None = None,
    ) -> dict[str, Any]:
        """Poll ``GET /jobs/{id}`` until the job is terminal; returns its last state."""
        t0 = time.monotonic()
        while True:
            job = self.job(job_id)
            if on_update is not None:
                on_update(job)
            if job["status"] in TERMINAL:
                return job
            if timeout_s is not None and time.monotonic() - t0 > timeout_s:
                raise TimeoutError(f"job {job_id} still {job['status']} after {timeout_s} s")
            time.sleep(poll_s)
