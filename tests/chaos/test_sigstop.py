"""SIGSTOP of a worker that has optimised a recorded job but not yet stored it, for longer than
two lease periods; another worker takes the job over and finishes it; then SIGCONT. The paused
worker resumes inside its finalisation and must not touch the winner's files: the committed
recording still matches its checksum and downloads (issue 8, defect 6: result files were
written at fixed paths before ``finish_job`` checked the lease, and the download answered 500
"corrupted" forever).
"""

from __future__ import annotations

import hashlib
import re
import time
from pathlib import Path

import httpx
import pytest

from tests.chaos.dbview import owner_pid
from tests.chaos.scenario import Scenario
from tests.chaos.workload import finalize_heavy_spec

pytestmark = [pytest.mark.integration, pytest.mark.chaos]


def _files(root: Path, job_id: str) -> dict[str, tuple[int, int, str]]:
    """Every file under the artifact root whose path names the job: (inode, mtime, sha256)."""
    out = {}
    for p in root.rglob("*"):
        if p.is_file() and job_id in str(p.relative_to(root)):
            st = p.stat()
            out[str(p.relative_to(root))] = (
                st.st_ino, st.st_mtime_ns, hashlib.sha256(p.read_bytes()).hexdigest()
            )  # fmt: skip
    return out


def test_sigstop_past_the_lease_then_sigcont(scenario: Scenario) -> None:
    sc = scenario
    w1, w2 = sc.start_workers(1, 1)
    job = sc.submit(finalize_heavy_spec(seed=700)).resource_id

    def optimised() -> bool:
        o = sc.monitor.state(job)
        rows = sc.view.job_rows([job])
        return bool(o and o.status == "running" and rows
                    and rows[0]["progress_generation"] >= rows[0]["total_generations"])  # fmt: skip

    sc.wait_until("the job optimised, in its finalisation", optimised, 90, 0.02)
    owner = owner_pid(sc.monitor.state(job).owner)  # type: ignore[union-attr]
    paused = w1 if owner == w1.pid else w2
    assert owner in (w1.pid, w2.pid), f"lease owner {owner} is not one of our workers"
    fault = sc.stack.pause_worker(paused)
    paused_at = time.monotonic()
    fault.victims = [job]
    sc.metrics["takeover_s"] = round(
        sc.wait_until("another worker finishes the job",
                      lambda: sc.status(job) == "succeeded", 2 * sc.lease_s + 60), 2)  # fmt: skip
    time.sleep(max(0.0, paused_at + 2 * sc.lease_s + 1 - time.monotonic()))  # past 2 leases
    root = Path(sc.stack.env["LEGOPT_ARTIFACT_DIR"])
    committed = _files(root, job)
    sc.stack.resume_worker(paused, fault)

    # the resumed worker finishes its finalisation, finds its lease gone and gives up
    log = sc.stack.worker(paused).log
    pattern = re.compile(rf"{job}.*(lease|not-claimed)|(lease|succeeded in).*{job}", re.I)
    mark = log.stat().st_size

    def stale_worker_done() -> bool:
        with open(log, errors="replace") as f:
            f.seek(mark)
            return bool(pattern.search(f.read()))

    try:
        sc.metrics["stale_worker_gave_up_s"] = round(
            sc.wait_until("the resumed worker gives the job up", stale_worker_done, 30), 2
        )
    except AssertionError:
        sc.metrics["stale_worker_gave_up_s"] = None  # checked below through the files anyway
    after = _files(root, job)
    touched = {p: (committed.get(p), v) for p, v in after.items() if committed.get(p) != v}
    r = httpx.get(f"{sc.stack.url}/api/v1/jobs/{job}/recording",
                  headers={"X-API-Key": sc.stack.key}, timeout=30)  # fmt: skip
    sc.metrics["recording_download_status"] = r.status_code
    sc.verify()  # includes: every artifact row's file matches its size and SHA-256
    assert r.status_code == 200, f"recording download: {r.status_code} {r.text[:300]}"
    committed_paths = {a["relative_path"] for a in sc.view.artifact_rows([job])}
    changed = sorted(set(touched) & committed_paths)
    assert not changed, (
        f"the paused worker rewrote the committed artifact(s) {changed} after the job had "
        f"succeeded (inode, mtime, sha256 before/after): {touched}"
    )
