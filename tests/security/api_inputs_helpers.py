"""The in-process API the hostile-input tests post to (``test_api_inputs.py``,
``test_api_amplification.py``) and the check of a located 422."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

from fastapi.testclient import TestClient
from httpx import Response

from services.api.app import create_app
from services.api.deps import ApiContext
from services.store.api_keys import create_api_key
from services.store.keys import generate_api_key
from services.store.settings import Settings

API = "/api/v1"
JSON = {"content-type": "application/json"}


@dataclass
class Api:
    """The in-process app, its context and one API key's headers."""

    client: TestClient
    ctx: ApiContext
    headers: dict[str, str]

    def post(self, path: str, body: str | bytes) -> Response:
        """POST a raw JSON text (Python's json would refuse to write NaN for us)."""
        return self.client.post(f"{API}{path}", content=body, headers={**self.headers, **JSON})


@contextmanager
def in_process_api(db_settings: Settings) -> Iterator[Api]:
    """The app on ``db_settings`` with one API key (alice's), jobs never enqueued."""
    app = create_app(db_settings, enqueue=lambda _job_id: None)
    ctx: ApiContext = app.state.context
    raw, key_hash = generate_api_key()
    with ctx.write() as session:
        create_api_key(session, name="alice", key_hash=key_hash)
    with TestClient(app, raise_server_exceptions=False) as client:
        yield Api(client, ctx, {"X-API-Key": raw})


def error_at(response: Response, loc: list[Any], type_: str | None = None) -> dict[str, Any]:
    """The validation error of a 422 located at ``loc`` (fails naming what came instead)."""
    assert response.status_code == 422, f"{response.status_code}: {response.text[:500]}"
    errors = response.json()["detail"]
    for err in errors:
        if err["loc"] == loc and (type_ is None or err["type"] == type_):
            return dict(err)
    raise AssertionError(f"no {type_ or 'error'} at {loc}; got {errors}")
