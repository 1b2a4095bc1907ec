"""Helpers shared by the API tests."""

from __future__ import annotations

from typing import Any

from sqlalchemy import func, select

from services.api.deps import ApiContext
from services.store.keys import generate_api_key
from services.store.repository import create_api_key
from services.store.tables import JOBS, ROBOTS, SWEEPS


def new_key(ctx: ApiContext, name: str) -> tuple[str, str]:
    """A stored API key: ``(raw key, key id)``."""
    raw, key_hash = generate_api_key()
    with ctx.write() as s:
        record = create_api_key(s, name=name, key_hash=key_hash)
    return raw, record.id


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
    from services.store.lifecycle import claim_job, finish_job, record_generation
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
