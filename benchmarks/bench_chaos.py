"""Recovery numbers of the chaos suite (issue 8): runs ``tests/chaos`` (both stacks where
available) and prints, per scenario and stack, the time to recover after each fault, messages
per job, queue waits and thread / RSS growth per job, as measured by the scenarios themselves
(``tests/chaos/scenario.py`` writes one JSON line per scenario to ``$LEGOPT_CHAOS_METRICS``).

    python benchmarks/bench_chaos.py [-k EXPR] [--runs N]

A failing scenario still reports what it measured (marked FAIL). Numbers depend on the load
of the machine: record them in benchmarks/RESULTS.md with ``nproc`` and the load average.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]

#: (column title, metric keys to look for in order). Times in seconds unless stated.
COLUMNS: list[tuple[str, tuple[str, ...]]] = [
    ("reclaim after kill", ("prefork_parent_reclaim_s", "solo_reclaim_s",
                            "victim_reclaim_after_restart_s", "takeover_s")),
    ("drain after fault", ("drain_after_last_fault_s", "drain_after_restart_s", "drain_s",
                           "round0_drain_s")),
    ("pool respawn", ("round0_replacement_s",)),
    ("max idle queue wait", ("max_idle_queue_wait_s",)),
    ("msgs/job mean", ("messages_per_job_mean",)),
    ("msgs/job max", ("messages_per_job_max",)),
    ("threads +", ("worker_thread_growth", "api_thread_growth")),
    ("RSS MB/job", ("worker_rss_mb_per_job", "api_rss_mb_per_call")),
]  # fmt: skip


def _cell(m: dict[str, Any], keys: tuple[str, ...]) -> str:
    vals = [f"{m[k]}" for k in keys if m.get(k) is not None]
    return " / ".join(vals) if vals else "-"


def table(rows: list[dict[str, Any]]) -> str:
    """A markdown table: one line per scenario run."""
    head = ["scenario", "stack", "ok", *[c for c, _ in COLUMNS]]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for m in rows:
        name = str(m.get("scenario", "?")).split("[")[0].removeprefix("test_")
        ok = "ok" if not m.get("failures") else f"FAIL({m['failures']})"
        cells = [name, str(m.get("stack", "?")), ok, *[_cell(m, keys) for _, keys in COLUMNS]]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def run(pytest_args: list[str]) -> tuple[int, list[dict[str, Any]], float]:
    with tempfile.TemporaryDirectory(prefix="legopt-chaos-bench-") as tmp:
        sink = Path(tmp) / "metrics.jsonl"
        env = dict(os.environ, LEGOPT_CHAOS_METRICS=str(sink))
        cmd = [sys.executable, "-m", "pytest", "tests/chaos", "-q", "-p", "no:cacheprovider",
               "-m", "chaos", *pytest_args]  # fmt: skip
        t0 = time.perf_counter()
        rc = subprocess.run(cmd, cwd=ROOT, env=env).returncode
        wall = time.perf_counter() - t0
        rows = [json.loads(line) for line in sink.read_text().splitlines()] if sink.exists() else []
    return rc, rows, wall


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-k", default=None, help="pytest -k expression (scenarios / stacks)")
    ap.add_argument("--runs", type=int, default=1, help="repeat the suite N times")
    args = ap.parse_args(argv)
    extra = ["-k", args.k] if args.k else []
    all_rows: list[dict[str, Any]] = []
    worst = 0
    for i in range(args.runs):
        rc, rows, wall = run(extra)
        worst = max(worst, rc)
        all_rows += rows
        load = os.getloadavg()
        print(f"\nrun {i + 1}: pytest exit {rc}, {wall:.0f} s wall, nproc {os.cpu_count()}, "
              f"load {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}")  # fmt: skip
    print()
    print(table(all_rows))
    print(
        "\nreclaim: fault -> the hit jobs claimed again (takeover: a paused worker's job "
        "finished elsewhere); drain: fault over -> every job terminal; msgs/job: "
        "'dispatched' events (or estimated from worker logs before job_events existed)."
    )
    return worst


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
