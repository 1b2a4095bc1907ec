"""Helpers shared by the API tests."""

from __future__ import annotations

import json
import queue
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import func, select

from services.api.app import create_app
from services.api.deps import ApiContext
from services.store.api_keys import create_api_key
from services.store.keys import generate_api_key
from services.store.migrate import upgrade
from services.store.session import reset_engine
from services.store.settings import Settings, get_settings
from services.store.tables import JOBS, ROBOTS, SWEEPS

API = "/api/v1"


def new_key(ctx: ApiContext, name: str) -> tuple[str, str]:
    """A stored API key: ``(raw key, key id)``."""
    raw, key_hash = generate_api_key()
    with ctx.write() as s:
        record = create_api_key(s, name=name, key_hash=key_hash)
    return raw, record.id


@dataclass(frozen=True)
class FreshApp:
    """An app of :func:`fresh_app`: its started test client, its context and settings, the
    headers of each of its API keys by name, and the monkeypatch holding its environment
    (undone when ``fresh_app`` ends)."""

    client: TestClient
    ctx: ApiContext
    settings: Settings
    keys: dict[str, dict[str, str]]
    mp: pytest.MonkeyPatch


@contextmanager
def fresh_app(tmp: Path, *names: str) -> Iterator[FreshApp]:
    """An app on a fresh migrated SQLite database in ``tmp`` (also its data directory, set as
    ``LEGOPT_DATA_DIR`` and ``LEGOPT_DATABASE_URL``) that enqueues nothing, with an API key
    per name in ``names``; for a module's fixture whose jobs a test runs itself. The
    environment, the settings' cache and the engine are reset at the end."""
    mp = pytest.MonkeyPatch()
    url = f"sqlite:///{tmp / 'legopt.db'}"
    mp.setenv("LEGOPT_DATA_DIR", str(tmp))
    mp.setenv("LEGOPT_DATABASE_URL", url)
    get_settings.cache_clear()
    reset_engine()
    try:
        upgrade(url)
        settings = get_settings()
        app = create_app(settings, enqueue=lambda _j: None)
        ctx: ApiContext = app.state.context
        keys = {name: {"X-API-Key": new_key(ctx, name)[0]} for name in names}
        with TestClient(app) as client:
            yield FreshApp(client, ctx, settings, keys, mp)
    finally:
        mp.undo()
        get_settings.cache_clear()
        reset_engine()


def row_counts(ctx: ApiContext) -> dict[str, int]:
    """Rows in the tables a request could write (robots, sweeps, jobs)."""
    with ctx.read() as s:
        return {
            t.name: s.execute(select(func.count()).select_from(t)).scalar_one()
            for t in (ROBOTS, SWEEPS, JOBS)
        }


def locs(response: Any) -> list[list[Any]]:
    """The ``loc`` of every validation error of a 422 response."""
    assert response.status_code == 422, response.text
    return [e["loc"] for e in response.json()["detail"]]


def dh_spec(**joint1: Any) -> dict[str, Any]:
    """A valid 2-joint DH arm; ``joint1`` overrides fields of its second joint."""
    return {
        "kind": "dh",
        "name": "two_link",
        "joints": [
            {
                "a": 0.3,
                "mass": 1.0,
                "com": [-0.15, 0.0, 0.0],
                "inertia": [[0.001, 0, 0], [0, 0.008, 0], [0, 0, 0.008]],
            },
            {
                "a": 0.25,
                "mass": 0.8,
                "com": [-0.125, 0.0, 0.0],
                "inertia": [[0.001, 0, 0], [0, 0.005, 0], [0, 0, 0.005]],
                **joint1,
            },
        ],
    }


def urdf_text(izz: float = 0.01, lower: float = -1.5) -> str:
    """A 2-joint URDF arm (``izz`` of link 1; ``lower`` limit of joint 1)."""

    def link(name: str, izz_value: float) -> str:
        return (
            f'<link name="{name}"><inertial><mass value="1.0"/><origin xyz="0.1 0 0"/>'
            f'<inertia ixx="0.001" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="{izz_value}"/>'
            "</inertial></link>"
        )

    def joint(name: str, parent: str, child: str, x: float, lo: float) -> str:
        return (
            f'<joint name="{name}" type="revolute"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{x} 0 0"/><axis xyz="0 0 1"/>'
            f'<limit lower="{lo}" upper="1.5" effort="10" velocity="3"/></joint>'
        )

    return (
        '<?xml version="1.0"?><robot name="arm2"><link name="base"/>'
        + link("link1", izz)
        + link("link2", 0.01)
        + joint("j1", "base", "link1", 0.0, lower)
        + joint("j2", "link1", "link2", 0.2, -1.5)
        + "</robot>"
    )


def finish_like_a_worker(
    ctx: ApiContext,
    job_id: str,
    *,
    generations: int = 3,
    n_pareto: int = 300,
    recording: bytes | None = b"RRF2-fake-recording",
    worker: str = "test-worker",
) -> None:
    """Drive a job through the store as a worker would: claim, record generations, finish
    with a result, a Pareto front, a baseline and (optionally) a recording artifact."""
    from services.store.lifecycle import claim_job, finish_job
    from services.store.progress import record_generation
    from services.store.records import ArtifactIn, BaselineIn, ParetoPointIn, ResultIn

    with ctx.write() as s:
        assert claim_job(s, job_id, worker, 60.0) is not None
    for g in range(generations + 1):
        with ctx.write() as s:
            record_generation(
                s,
                job_id,
                worker,
                generation=g,
                n_evals=10 * (g + 1),
                best=[1.0 / (g + 1), 2.0],
                wall_time_s=0.01,
            )
    from services.store.evaluations import EvaluationsIn, record_evaluations

    with ctx.write() as s:  # the trials: one generation of four evaluated solutions
        X = [[0.1 * i, 0.2] for i in range(4)]
        F = [[float(i), float(4 - i)] for i in range(4)]
        record_evaluations(s, job_id, [EvaluationsIn(1, X, F, [0.0, 0.0, 0.5, 0.0])])  # type: ignore[arg-type]
    artifacts = []
    if recording is not None:
        stored = ctx.artifacts.put(job_id, "recording", recording)
        artifacts.append(ArtifactIn("recording", *stored))
    with ctx.write() as s:
        finish_job(
            s,
            job_id,
            worker,
            result=ResultIn(
                best_x=[0.1, 0.2],
                objectives={"names": ["energy", "time"], "values": {"energy": 1.5, "time": 2.0}},
                metrics={"energy_J": 1.5, "path_length_m": 0.3},
                summary={"table": [], "optimizer": {"n_gen": generations}},
            ),
            pareto=[
                ParetoPointIn(i, [i * 0.01, 1.0], [float(i), float(n_pareto - i)])
                for i in range(n_pareto)
            ],
            baselines=[BaselineIn("parabolic", {"energy_J": 3.0})],
            artifacts=artifacts,
        )


#: The single job of :func:`dashboard_env` (its sweep's base too).
DASHBOARD_SPEC: dict[str, Any] = {
    "name": "front demo",
    "tags": ["demo", "energy-time"],
    "problem": {"kind": "path_tracking", "objective": "energy_time"},
    "optimizer": {"kind": "nsga2", "params": {"pop_size": 24}},
    "budget": {"generations": 8},
    "seed": 2,
}


@contextmanager
def dashboard_env(tmp: Path) -> Iterator[dict[str, Any]]:
    """The dashboard tests' app (:func:`fresh_app` in ``tmp``): Alice's single job
    (``DASHBOARD_SPEC``) and her sweep of 2 cells x 2 seeds, all run to the end by the real
    executor; Bob's and Carol's keys."""
    from services.worker.execute import execute_job

    with fresh_app(tmp, "alice", "bob", "carol") as app:
        client, alice = app.client, app.keys["alice"]
        r = client.post(f"{API}/jobs", json=DASHBOARD_SPEC, headers=alice)
        assert r.status_code == 202, r.text
        job_id = r.json()["id"]
        sweep = {
            "base": {**DASHBOARD_SPEC, "name": "sweep demo", "record": False},
            "grid": {"optimizer.params.pop_size": [24, 32]},
            "seeds": [1, 2],
        }
        r = client.post(f"{API}/sweeps", json=sweep, headers=alice)
        assert r.status_code == 202, r.text
        sweep_id, sweep_jobs = r.json()["id"], r.json()["job_ids"]
        for j in [job_id, *sweep_jobs]:
            assert execute_job(j, app.settings).status == "succeeded"
        yield {"client": client, "ctx": app.ctx, "job": job_id, "sweep": sweep_id,
               "sweep_jobs": sweep_jobs, **app.keys}  # fmt: skip


#: Seed 000's swing of a leg, its score maximised (the optimiser minimises ``neg_score``): a
#: quantity exported and shown once, in its own sign. Three generations of 12.
SCORE_SPEC: dict[str, Any] = {
    "robot": "calderon_leg",
    "problem": {"kind": "swing_energy", "n_via": 3},
    "optimizer": {"kind": "ga", "params": {"pop_size": 12, "fitness": "negated"}},
    "budget": {"generations": 3},
    "seed": 1,
    "record": False,
}


def listen_events(client: TestClient, url: str, headers: dict[str, str]) -> queue.Queue[Any]:
    """Follow a Server-Sent Events stream in a thread: its ``(event, data)``, then
    ``("closed", None)``."""
    events: queue.Queue[tuple[str, Any]] = queue.Queue()

    def run() -> None:
        with client.stream("GET", url, headers=headers) as r:
            assert r.status_code == 200
            assert r.headers["content-type"].startswith("text/event-stream")
            name = None
            for line in r.iter_lines():
                if line.startswith("event:"):
                    name = line[6:].strip()
                elif line.startswith("data:") and name:
                    events.put((name, json.loads(line[5:])))
        events.put(("closed", None))

    threading.Thread(target=run, daemon=True).start()
    return events
