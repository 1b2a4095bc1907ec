"""A fresh API warms its validation processes before it says it is ready (issue 21 item 6,
issue 23: the first ``POST /jobs`` of a fresh API took 126 s, compiling inside the request).

A real ``uvicorn`` on the embedded store with ``LEGOPT_API_WARMUP`` on (the default, which the
other integration tests turn off): ``/health`` answers at once, ``/ready`` answers 503 "warming
up" until every study kind's minimal job has been validated in the validation process, then
200 with the warm-up's duration; then a submission of every study kind is accepted. How long
that first submission takes is a benchmark figure (``benchmarks/bench_first_run.py``), not an
assertion here.
"""

from __future__ import annotations

import time
from pathlib import Path

import httpx
import pytest

from services.api.validation import example_specs
from tests.integration.stack import Stack
from tests.patience import Patience

pytestmark = pytest.mark.integration


def test_a_fresh_api_is_ready_once_its_validation_is_warm(tmp_path: Path) -> None:
    (tmp_path / "data").mkdir()
    st = Stack(
        "embedded", tmp_path, f"sqlite:///{tmp_path / 'data' / 'legopt.db'}", "filesystem://"
    )
    st.env["LEGOPT_API_WARMUP"] = "true"
    st.migrate_and_key()
    st.start_api()  # returns once /health answers
    try:
        seen: set[int] = set()
        patience = Patience(180)
        while True:
            r = httpx.get(f"{st.url}/api/v1/ready", timeout=30)
            seen.add(r.status_code)
            if r.status_code == 200:
                break
            assert r.status_code == 503 and "warming up" in r.json()["detail"], r.text
            assert r.headers.get("retry-after") == "1"
            assert not patience.expired(), f"not ready in {patience}:\n{st.log_tail()}"
            time.sleep(0.1)
        warmup_s = r.json()["warmup_s"]
        assert warmup_s is not None and warmup_s > 0, r.json()
        with st.client() as c:
            for kind, spec in example_specs().items():
                job = c.submit({**spec, "budget": {"generations": 1}})
                assert job["kind"] == kind and job["status"] == "queued", job
    finally:
        st.stop()
