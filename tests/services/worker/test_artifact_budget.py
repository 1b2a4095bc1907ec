"""Artifacts sized to their content (issue 12): a tiny job through the worker stays within the
size budget documented in docs/recording.md §3 ("Size budget of a job's artifacts")."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from services.store import api_keys
from services.store import output_queries as oq
from services.store import repository as repo
from services.store.artifacts import ArtifactStore
from services.store.keys import generate_api_key
from services.store.session import session_scope
from services.store.settings import Settings
from services.worker import execute

#: The documented budget of a tiny job (docs/recording.md §3), bytes.
TINY_RECORDING_BYTES = 200 * 1024
TINY_RESULT_BYTES = 192 * 1024
TINY: dict[str, Any] = {  # the issue's 3-generation job: seed 002's study, its defaults
    "problem": {"kind": "hexapod_workspace"},
    "budget": {"generations": 3},
    "seed": 1,
    "record": True,
}


def test_a_tiny_jobs_artifacts_are_within_the_documented_budget(settings: Settings) -> None:
    with session_scope() as s:
        key = api_keys.create_api_key(s, name="t", key_hash=generate_api_key()[1])
        job_id = repo.create_job(s, owner_key_id=key.id, spec=TINY, total_generations=3).id
    assert execute.execute_job(job_id, settings, wid="w1").status == "succeeded"
    with session_scope() as s:
        arts = {a.kind: a for a in oq.list_artifacts(s, job_id)}
    assert set(arts) == {"result", "recording"}
    assert 0 < arts["recording"].size_bytes <= TINY_RECORDING_BYTES
    assert 0 < arts["result"].size_bytes <= TINY_RESULT_BYTES
    store = ArtifactStore.from_settings(settings)
    text = store.read(arts["result"].relative_path, arts["result"].sha256).decode()
    assert ", " not in text[:200] and ": " not in text[:200]  # compact JSON, no padding
    assert json.loads(text)["status"] == "succeeded"
    doc = (Path(__file__).parents[3] / "docs" / "recording.md").read_text()
    budget = doc[doc.index("### Size budget of a job's artifacts") :]
    assert "≤ **200 KiB**" in budget and "≤ **192 KiB**" in budget  # the documented budget
