"""How much one API key's heavy submissions slow everybody else: ``GET /health`` latency while
one key sends N concurrent ``POST /jobs`` with ~1.7 MB inline URDF robots (issue 22 item 4),
retrying each after ``Retry-After`` when answered 429 / 503.

A real embedded stack (uvicorn API + one worker, SQLite + filesystem broker). The robot: a
6-joint arm whose URDF is padded to ``--urdf-mb`` with fixed links that carry inertia and
geometry (what makes a large real URDF slow to parse and build: Pinocchio frames), submitted as
a ``swing_energy`` job between two given configurations (the API builds the robot and prepares
the problem before it stores anything; the job is accepted, and the worker runs it).
``/health`` is polled every 20 ms by another client through the whole burst, and before it
(quiet); the table gives p50 / p95 / max of each, the submissions' own outcomes (status codes)
and the burst's wall time.

    python benchmarks/bench_health_under_load.py [--submissions 6] [--urdf-mb 1.7] [--rounds 2]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path

import httpx

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.integration.stack import embedded_stack  # noqa: E402

ARM = (ROOT / "examples" / "robots" / "arm3.urdf").read_text()


def heavy_urdf(megabytes: float) -> str:
    """``arm3.urdf`` with fixed, massive links hung off its base until it is ``megabytes`` MB."""
    pad = []
    size, i = len(ARM), 0
    while size < megabytes * 1e6:
        block = (
            f'  <link name="pad{i}"><inertial><origin xyz="0 0 0.01"/><mass value="0.001"/>'
            f'<inertia ixx="1e-7" ixy="0" ixz="0" iyy="1e-7" iyz="0" izz="1e-7"/></inertial>'
            f'<visual><geometry><box size="0.01 0.01 0.01"/></geometry></visual></link>\n'
            f'  <joint name="padj{i}" type="fixed"><parent link="base"/><child link="pad{i}"/>'
            f'<origin xyz="0 0 {0.001 * (i % 50):.3f}"/></joint>\n'
        )
        pad.append(block)
        size += len(block)
        i += 1
    return ARM.replace("</robot>", "".join(pad) + "</robot>")


#: Attempts of one submission answered 429 / 503 (each after its ``Retry-After``).
MAX_ATTEMPTS = 30


def pct(values: list[float], q: float) -> float:
    values = sorted(values)
    return values[min(len(values) - 1, int(q * (len(values) - 1) + 0.5))]


def poll_health(url: str, stop: threading.Event, out: list[float]) -> None:
    with httpx.Client(timeout=30) as c:
        while not stop.is_set():
            t = time.perf_counter()
            c.get(f"{url}/api/v1/health")
            out.append(1e3 * (time.perf_counter() - t))
            stop.wait(0.02)


def burst(url: str, key: str, spec: dict[str, object], n: int) -> tuple[Counter[str], float]:
    """``n`` concurrent submissions, each retried after ``Retry-After`` on 429 / 503 (a
    well-behaved client): the status codes of every answer (``429``) and of the last one."""
    codes: Counter[str] = Counter()
    lock = threading.Lock()

    def one() -> None:
        with httpx.Client(timeout=300) as c:
            for _ in range(MAX_ATTEMPTS):
                r = c.post(f"{url}/api/v1/jobs", json=spec, headers={"X-API-Key": key})
                if r.status_code not in (429, 503):
                    break
                with lock:
                    codes[f"{r.status_code} (retried)"] += 1
                time.sleep(float(r.headers.get("Retry-After", "1")))
        with lock:
            codes[str(r.status_code)] += 1

    t = time.perf_counter()
    threads = [threading.Thread(target=one) for _ in range(n)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    return codes, time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--submissions", type=int, default=6)
    ap.add_argument("--urdf-mb", type=float, default=1.7)
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    urdf = heavy_urdf(args.urdf_mb)
    spec = {  # a swing of the arm as a 3-joint leg: accepted, so the worker runs it too
        "robot": {"kind": "urdf", "name": "padded_arm", "urdf": urdf},
        "problem": {
            "kind": "swing_energy",
            "q_start": [0.0, 0.6, -1.2],
            "q_end": [0.0, -0.3, -0.9],
        },
        "budget": {"generations": 1},
        "record": False,
    }
    print(
        f"URDF {len(urdf) / 1e6:.2f} MB, {urdf.count('<link')} links; "
        f"{args.submissions} concurrent submissions by one key, {args.rounds} rounds"
    )
    env = {"LEGOPT_RATE_LIMIT_BURST": "1000", "LEGOPT_QUOTA_ACTIVE_JOBS": "1000"}
    with tempfile.TemporaryDirectory() as tmp, embedded_stack(Path(tmp), env) as st:
        quiet: list[float] = []
        stop = threading.Event()
        th = threading.Thread(target=poll_health, args=(st.url, stop, quiet))
        th.start()
        time.sleep(3)
        stop.set()
        th.join()
        rows: list[tuple[str, list[float], Counter[str], float]] = [
            ("quiet", quiet, Counter(), 0.0)
        ]
        for r in range(args.rounds):
            loaded: list[float] = []
            stop = threading.Event()
            th = threading.Thread(target=poll_health, args=(st.url, stop, loaded))
            th.start()
            codes, wall = burst(st.url, st.key, spec, args.submissions)
            stop.set()
            th.join()
            rows.append((f"burst {r + 1}", loaded, codes, wall))
    print(
        "| phase | /health polls | p50 ms | p95 ms | max ms | submissions (status: n) | burst s |"
    )
    print("|---|---|---|---|---|---|---|")
    for name, lat, codes, wall in rows:
        print(f"| {name} | {len(lat)} | {statistics.median(lat):.1f} | {pct(lat, 0.95):.1f} | "
              f"{max(lat):.1f} | {dict(sorted(codes.items())) or '-'} | "
              f"{wall:.1f} |")  # fmt: skip


if __name__ == "__main__":
    main()
