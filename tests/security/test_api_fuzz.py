"""OpenAPI fuzzing with schemathesis: no operation answers 5xx to generated input (positive
and negative cases, bounded and derandomized so the run is short and reproducible).

Operations with a path id run each generated case twice: as generated (an id that does not
exist) and with the id of a real resource of the caller's — a robot, a finished job with a
result, Pareto front and generations, a sweep, another API key (the fuzzer is an admin) — so
the handlers behind the 404 are fuzzed too (pagination, cursors, filters). Longer local runs:
``LEGOPT_FUZZ_EXAMPLES=100``.

Both databases (``tests.security.databases``): each generated case is sent to an app on SQLite
AND to one on PostgreSQL (generating the cases is most of the run's time, so the second
database costs little), and the stateful run goes once per database. Where PostgreSQL does not
answer, the two-database run is skipped and a SQLite-only run takes its place — unless
``LEGOPT_REQUIRE_SERVICES=1``, where the two-database run fails instead.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
import schemathesis
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, Phase, given
from hypothesis import settings as hypothesis_settings
from hypothesis.errors import Unsatisfiable
from schemathesis import GenerationMode

from services.api.app import create_app
from services.api.deps import ApiContext
from services.store.api_keys import create_api_key
from services.store.keys import generate_api_key
from services.store.settings import Settings
from tests.integration.stack import postgres_missing, services_required, when_available
from tests.security.databases import DATABASES, migrated_settings
from tests.services.api.api_helpers import finish_like_a_worker, new_key

MAX_EXAMPLES = int(os.environ.get("LEGOPT_FUZZ_EXAMPLES", "8"))

#: Methods whose calls with a real id would destroy the resource the other operations need.
DESTRUCTIVE = {"DELETE"}

#: The databases one stateless run sends every case to (see the module docstring).
FUZZ_DATABASES = [
    when_available(("sqlite", "postgresql"), postgres_missing(), id="sqlite+postgresql")
]
if postgres_missing() is not None and not services_required():
    FUZZ_DATABASES.append(pytest.param(("sqlite",), id="sqlite"))


@dataclass
class Target:
    """An app on one database, the headers of its admin key and the ids of its resources."""

    kind: str
    app: Any
    headers: dict[str, str]
    ids: dict[str, str]


def _real_ids(client: TestClient, ctx: ApiContext, headers: dict[str, str]) -> dict[str, str]:
    """A robot, a sweep and its first job (finished like a worker would, without a recording:
    the fake bytes of ``finish_like_a_worker`` are no .rrd the sweep merge could read)."""
    dh = client.get("/api/v1/robots/puma560", headers=headers).json()["inline_spec"]
    robot = client.post("/api/v1/robots", json={"name": "fuzz", "spec": dh}, headers=headers)
    assert robot.status_code == 201, robot.text
    base = {"problem": {"kind": "path_tracking"}, "budget": {"generations": 2}}
    sweep = client.post("/api/v1/sweeps", json={"base": base, "seeds": [1, 2]}, headers=headers)
    assert sweep.status_code == 202, sweep.text
    job_id = sweep.json()["job_ids"][0]
    finish_like_a_worker(ctx, job_id, n_pareto=40, recording=None)
    return {
        "robot_id": robot.json()["id"],
        "job_id": job_id,
        "sweep_id": sweep.json()["id"],
        "k": "0",
        "t": "0",
        "name": "parabolic",  # the baseline finish_like_a_worker stores
    }


def _app_and_admin(settings: Settings) -> tuple[Any, dict[str, str]]:
    """An app without rate limit (the fuzzer sends hundreds of requests a second) and the
    headers of an admin key, so the key routes are fuzzed beyond their 403."""
    sent: list[str] = []
    app = create_app(
        # event streams of queued jobs end at once (a fuzzer waits for each response's end)
        settings.with_overrides(rate_limit_per_s=1e9, rate_limit_burst=10**9, event_stream_s=0.01),
        enqueue=sent.append,
    )
    raw, key_hash = generate_api_key()
    with app.state.context.write() as session:
        create_api_key(session, name="fuzzer", key_hash=key_hash, role="admin")
    return app, {"X-API-Key": raw}


@contextmanager
def _target(kind: str, directory: Path) -> Iterator[Target]:
    """A running app on a fresh migrated database of ``kind``, with real resources."""
    with migrated_settings(kind, directory) as settings:
        app, headers = _app_and_admin(settings)
        with TestClient(app, raise_server_exceptions=False) as client:
            ctx: ApiContext = app.state.context
            ids = {**_real_ids(client, ctx, headers), "key_id": new_key(ctx, "victim")[1]}
            yield Target(kind, app, headers, ids)


@pytest.mark.slow
@pytest.mark.parametrize("kinds", FUZZ_DATABASES)
def test_openapi_fuzz_finds_no_server_error(kinds: tuple[str, ...], tmp_path: Path) -> None:
    with ExitStack() as stack:
        targets = [stack.enter_context(_target(k, tmp_path / k)) for k in kinds]
        _fuzz(targets)


@pytest.mark.slow  # the quick lane keeps the hostile bodies of test_api_inputs.py
@pytest.mark.parametrize("kind", DATABASES)
def test_openapi_stateful_finds_no_server_error(kind: str, tmp_path: Path) -> None:
    """Schemathesis' stateful phase: call sequences chained by the links it infers (POST
    /sweeps -> GET /sweeps/{id}, POST /jobs -> cancel, delete, ...)."""
    with migrated_settings(kind, tmp_path) as settings:
        _stateful(settings)


def _stateful(settings: Settings) -> None:
    app, headers = _app_and_admin(settings)
    failures: list[str] = []
    labels: set[str] = set()
    base = schemathesis.openapi.from_asgi("/api/v1/openapi.json", app).as_state_machine()

    class Workflow(base):  # type: ignore[misc, valid-type]
        def get_call_kwargs(self, case: Any) -> dict[str, Any]:
            return {"headers": headers}

        def validate_response(self, response: Any, case: Any, **kwargs: Any) -> None:
            labels.add(case.operation.label)
            if response.status_code >= 500:
                failures.append(
                    f"{case.operation.label} -> {response.status_code}: "
                    f"{response.text[:300]}\n  {case.as_curl_command()}"
                )

    with TestClient(app, raise_server_exceptions=False):
        Workflow.run(
            settings=hypothesis_settings(
                max_examples=MAX_EXAMPLES,
                stateful_step_count=6,
                deadline=None,
                database=None,
                derandomize=True,
                suppress_health_check=list(HealthCheck),
            )
        )
    assert len(labels) >= 8, f"the stateful phase reached only {sorted(labels)}"
    assert not failures, "\n".join(failures)


def _fuzz(targets: list[Target]) -> None:
    """Every operation, positive and negative cases; each case goes to every target (its own
    headers, and the target's real ids for a second call)."""
    schema = schemathesis.openapi.from_asgi("/api/v1/openapi.json", targets[0].app)
    failures: list[str] = []
    n_operations = 0
    for result in schema.get_all_operations():
        operation = result.ok()
        n_operations += 1
        for mode in (GenerationMode.POSITIVE, GenerationMode.NEGATIVE):

            @hypothesis_settings(
                max_examples=MAX_EXAMPLES,
                deadline=None,
                database=None,
                derandomize=True,
                suppress_health_check=list(HealthCheck),
                phases=[Phase.explicit, Phase.generate],
            )
            @given(case=operation.as_strategy(generation_mode=mode))
            def call(case: Any) -> None:
                names = set(case.path_parameters or {})
                for t in targets:
                    cases = [case]
                    if names and case.method.upper() not in DESTRUCTIVE:
                        missing = names - set(t.ids)
                        assert not missing, f"add a real id for {sorted(missing)} in _real_ids"
                        real = case.derive()
                        real.path_parameters = {
                            **case.path_parameters,
                            **{n: t.ids[n] for n in names},
                        }
                        cases.append(real)
                    for c in cases:
                        try:
                            response = c.call(app=t.app, headers=t.headers)
                        except Exception as exc:  # the in-process client re-raises a 500's error
                            failures.append(
                                f"[{t.kind}] {c.operation.label} -> {type(exc).__name__}: "
                                f"{str(exc).splitlines()[0][:300]}\n  {c.as_curl_command()}"
                            )
                            continue
                        if response.status_code >= 500:
                            failures.append(
                                f"[{t.kind}] {c.operation.label} -> {response.status_code}: "
                                f"{response.text[:300]}\n  {c.as_curl_command()}"
                            )

            try:
                call()
            except Unsatisfiable:  # no negative input exists (e.g. no parameters at all)
                assert mode is GenerationMode.NEGATIVE
    assert n_operations >= 15
    assert not failures, "\n".join(failures)
