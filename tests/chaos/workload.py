"""Job specs and submission for the chaos suite.

The work unit is seed 003's quadruped gait with a small HKA (10 samples, 20-point survey) and a
16-sample gait cycle: about 5 ms of optimiser per generation, so a job's length is set by its
generation count (``generations=2``: a tiny job, well under a second on a worker with its
per-generation checkpoint; ``generations=80``: one to three seconds, long enough to be hit
mid-run). ``finalize_heavy_spec`` is seed 000's swing with a population of 10: its generations
take milliseconds but its finalisation (five baselines) takes seconds — the window in which a
paused worker has finished optimising but not yet written its artifacts (defect 6).

``submit`` POSTs with an ``Idempotency-Key`` and retries connection errors, 5xx and 429 until
a deadline, as a careful client does when the API dies under it.
"""

from __future__ import annotations

import copy
import time
import uuid
from dataclasses import dataclass
from functools import cache
from typing import Any

import httpx
import yaml

from tests.integration.stack import ROOT
from tests.patience import Patience, oversubscription

RETRY_STATUS = {429, 500, 502, 503, 504}


@cache
def _example(name: str) -> dict[str, Any]:
    return dict(yaml.safe_load((ROOT / "examples" / f"{name}.yaml").read_text()))


def job_spec(seed: int = 1, generations: int = 2, record: bool = False) -> dict[str, Any]:
    """The chaos work unit (see the module docstring)."""
    spec = copy.deepcopy(_example("003_quadruped_gait"))
    spec["problem"]["samples_per_cycle"] = 16
    spec["problem"]["table_positions"] = 12
    spec["optimizer"] = {
        "kind": "hka",
        "params": {"n_samples": 10, "n_best": 3, "survey_size": 20, "survey_best": 2},
    }
    spec["seed"] = seed
    spec["budget"] = {"generations": generations}
    spec["record"] = record
    return spec


def finalize_heavy_spec(seed: int = 1, generations: int = 3) -> dict[str, Any]:
    """A recorded job whose finalisation takes seconds (see the module docstring)."""
    spec = copy.deepcopy(_example("000_swing_energy_flat"))
    spec["optimizer"]["params"]["pop_size"] = 10
    spec["seed"] = seed
    spec["budget"] = {"generations": generations}
    spec["record"] = True
    return spec


@dataclass
class Submitted:
    """One logical submission: its idempotency key, the id the API answered, the attempts."""

    key: str
    resource_id: str
    attempts: int
    body: dict[str, Any]


def post(
    url: str,
    api_key: str,
    path: str,
    body: dict[str, Any],
    *,
    idem_key: str | None = None,
    deadline_s: float = 60.0,
    timeout_s: float = 10.0,
) -> tuple[dict[str, Any], int]:
    """POST ``body`` to ``/api/v1{path}``; retries (same ``Idempotency-Key``) on connection
    errors, 429 and 5xx until ``deadline_s`` quiet-machine seconds (``tests.patience``).
    Returns (the JSON answer, attempts)."""
    headers = {"X-API-Key": api_key}
    if idem_key is not None:
        headers["Idempotency-Key"] = idem_key
    patience = Patience(deadline_s)
    attempts = 0
    last: str = ""
    while not patience.expired():
        attempts += 1
        try:
            # one request's own bound stretches with the machine's load, as the deadline does
            wait_s = timeout_s * oversubscription()
            r = httpx.post(f"{url}/api/v1{path}", json=body, headers=headers, timeout=wait_s)
        except httpx.TransportError as exc:
            last = f"{type(exc).__name__}: {exc}"
            time.sleep(0.2)
            continue
        if r.status_code in RETRY_STATUS:
            last = f"HTTP {r.status_code}: {r.text[:300]}"
            retry_after = r.headers.get("Retry-After")
            time.sleep(min(float(retry_after), 2.0) if retry_after else 0.3)
            continue
        if r.status_code >= 400:
            raise AssertionError(f"POST {path} -> {r.status_code}: {r.text[:1000]}")
        return dict(r.json()), attempts
    raise AssertionError(f"POST {path} did not succeed in {patience}; last: {last}")


def submit(
    url: str, api_key: str, spec: dict[str, Any], *, idem_key: str | None = None, **kw: Any
) -> Submitted:
    """POST /jobs with a fresh (or the given) idempotency key; see ``post``."""
    key = idem_key or f"chaos-{uuid.uuid4()}"
    doc, attempts = post(url, api_key, "/jobs", spec, idem_key=key, **kw)
    return Submitted(key, str(doc["id"]), attempts, spec)


def submit_sweep(
    url: str, api_key: str, doc: dict[str, Any], *, idem_key: str | None = None, **kw: Any
) -> tuple[Submitted, list[str]]:
    """POST /sweeps; (the submission, the sweep's job ids)."""
    key = idem_key or f"chaos-{uuid.uuid4()}"
    out, attempts = post(url, api_key, "/sweeps", doc, idem_key=key, **kw)
    return Submitted(key, str(out["id"]), attempts, doc), [str(j) for j in out["job_ids"]]
