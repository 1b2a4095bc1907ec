"""A small HTTP client of the LegOpt API (used by the CLI, the demo and the integration tests).

c = Client.from_env()             # LEGOPT_API_URL, LEGOPT_API_KEY or ./legopt-data/api-key
job = c.submit(spec)              # {"id": ..., "status": "queued", ...}
job = c.wait(job["id"])           # polls until succeeded | failed | cancelled
c.result(job["id"]); c.pareto(job["id"]); c.recording(job["id"])
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import httpx

__all__ = ["ApiError", "Client", "TERMINAL"]

TERMINAL = frozenset({"succeeded", "failed", "cancelled"})
DEFAULT_URL = "http://127.0.0.1:8000"


class ApiError(Exception):
    """An HTTP error answer: ``status`` code and the server's ``detail``."""

    def __init__(self, status: int, detail: Any) -> None:
        self.status = status
        self.detail = detail
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
            raise ApiError(resp.status_code, detail)
        return resp

    def get(self, path: str, **params: Any) -> Any:
        return self._req("GET", path, params=params or None).json()

    def post(self, path: str, body: Any = None) -> Any:
        return self._req("POST", path, json=body).json()

    # ------------------------------------------------------------------ endpoints
    def health(self) -> dict[str, Any]:
        return dict(self.get("/health"))

    def submit(self, spec: dict[str, Any]) -> dict[str, Any]:
        return dict(self.post("/jobs", spec))

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

    def recording(self, job_id: str) -> bytes:
        return self._req("GET", f"/jobs/{job_id}/recording").content

    def cancel(self, job_id: str) -> dict[str, Any]:
        return dict(self.post(f"/jobs/{job_id}/cancel"))

    def sweep(self, doc: dict[str, Any]) -> dict[str, Any]:
        return dict(self.post("/sweeps", doc))

    def sweep_recording(self, sweep_id: str, jobs: list[str] | None = None) -> bytes:
        """One .rrd merging the chosen jobs of a sweep (default: all with a recording)."""
        params = {"jobs": jobs} if jobs else None
        return self._req("GET", f"/sweeps/{sweep_id}/recording", params=params).content

    def get_sweep(self, sweep_id: str) -> dict[str, Any]:
        return dict(self.get(f"/sweeps/{sweep_id}"))

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
