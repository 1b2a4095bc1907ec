"""The dashboard's pages at scale, in Chromium: the jobs page at 10^3 and 10^5 jobs and a job
page with 10^4 stored evaluations (issue 21, item 8: each drawn within 1 s).

A fresh embedded data directory (SQLite) holds one API key with N jobs (``bench_dashboard.fill``:
a mix of studies, optimizers and statuses) and one real succeeded job (a small NSGA-II run,
``services.worker.execute``) whose stored evaluations are then replaced by E solutions of the
same problem, spread over its generations (``record_evaluations``; the real objectives and
constraint violations of uniform samples of its box). The API runs under uvicorn; Debian's
Chromium (headless, driven by Playwright, as ``tests/web/conftest.py``) logs in and then loads
each page ``--repeat`` times, every time a full navigation (``about:blank``, then the page's
address with its ``#/…`` route), with the HTTP cache disabled (``cold``: a first visit, every
file fetched again) and enabled (``warm``: a return visit; the files are revalidated).

Measured in the page, in ms from the navigation's start (``performance.now()``):

- ``first contentful paint``: the browser's ``paint`` entry of the navigation;
- ``data drawn``: the first frame after the page's data is in the document: the jobs table's
  first row (``#jobs-table tbody tr``); on the job page, the trial table's rows
  (``#trial-table tbody tr``) and its parallel-coordinates lines (``#trial-parallel .pc-line``),
  the later of the two; and (apart) the parameter importance (``#importance-body`` drawn).

The first load of the job page is reported on its own: it reads and decodes the evaluations
and fits the importance forests, which the API then caches for a finished job; the medians are
of the ``--repeat`` loads after it.

    python benchmarks/bench_dashboard_browser.py [--sizes 1000,100000] [--evaluations 10000]
        [--repeat 5] [--cache cold,warm]
"""

from __future__ import annotations

import argparse
import importlib
import os
import platform
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

GOAL_MS = 1000.0
TIMEOUT_MS = 120_000
#: As tests/web/conftest.py: the system Chromium, headless, by path.
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--no-first-run", "--disable-sync"]  # fmt: skip
#: The real job whose evaluations the job page shows (seconds of the worker).
TRIALS_SPEC: dict[str, Any] = {
    "name": "bench trials",
    "problem": {"kind": "path_tracking", "objective": "energy_time"},
    "optimizer": {"kind": "nsga2", "params": {"pop_size": 24}},
    "budget": {"generations": 4},
    "seed": 1,
    "record": False,
}
#: What "drawn" means, per mark: a selector; the init script below records, for each, the
#: time of the first animation frame after it matched (the frame that paints it).
MARKS = {
    "jobs": "#jobs-table tbody tr",
    "trials": "#trial-table tbody tr",
    "lines": "#trial-parallel .pc-line",
    "importance": "#importance-body[data-state=ok], #importance-body[data-state=few-feasible], "
    "#importance-body[data-state=empty], #importance-body[data-state=error]",
}
MARKER = """(() => {
  const want = %s, seen = {}, drawn = (window.__benchDrawn = {});
  const check = () => {
    for (const [k, sel] of Object.entries(want)) {
      if (k in seen || !document.querySelector(sel)) continue;
      seen[k] = performance.now();
      requestAnimationFrame(() => setTimeout(() => { drawn[k] = performance.now(); }, 0));
    }
  };
  const all = { childList: true, subtree: true, attributes: true };
  new MutationObserver(check).observe(document, all);
})();"""
READ = """() => ({ drawn: window.__benchDrawn || {},
  fcp: (performance.getEntriesByName("first-contentful-paint")[0] || {}).startTime ?? null,
  fp: (performance.getEntriesByName("first-paint")[0] || {}).startTime ?? null })"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def environment(data: Path) -> dict[str, str]:
    """The ``LEGOPT_*`` variables of this process and of the API: the embedded service on
    ``data``, no warm-ups, no rate limit in the way of repeated loads."""
    return {
        "LEGOPT_DATA_DIR": str(data),
        "LEGOPT_DATABASE_URL": f"sqlite:///{data / 'legopt.db'}",
        "LEGOPT_ARTIFACT_DIR": str(data / "artifacts"),
        "LEGOPT_BROKER_URL": "filesystem://",
        "LEGOPT_WORKER_WARMUP": "false",
        "LEGOPT_API_WARMUP": "false",
        "LEGOPT_RATE_LIMIT_PER_S": "1000000",
        "LEGOPT_RATE_LIMIT_BURST": "1000000",
        "NUMBA_NUM_THREADS": "1",
    }


def setup(data: Path) -> tuple[Any, str, str]:
    """Migrate, create the key; the API context, the key's id and its raw key."""
    from services.api.deps import ApiContext
    from services.store import api_keys
    from services.store.keys import generate_api_key
    from services.store.migrate import upgrade
    from services.store.settings import Settings, get_settings

    data.mkdir(parents=True, exist_ok=True)
    os.environ.update(environment(data))
    get_settings.cache_clear()
    upgrade(os.environ["LEGOPT_DATABASE_URL"])
    ctx = ApiContext(settings=Settings.from_env())
    raw, key_hash = generate_api_key()
    with ctx.write() as s:
        key_id = api_keys.create_api_key(s, name="bench", key_hash=key_hash).id
    return ctx, key_id, raw


def trials_job(ctx: Any, key_id: str, evaluations: int) -> str:
    """A real succeeded job whose stored evaluations are ``evaluations`` solutions of its
    problem (uniform in its box, really evaluated), spread over its generations."""
    import numpy as np
    from sqlalchemy import delete

    from legcore.problems.base import constraint_violation
    from legcore.runner import prepare
    from services.store import repository as repo
    from services.store.evaluations import EvaluationsIn, record_evaluations
    from services.store.tables import EVALUATIONS
    from services.worker import execute

    gens = int(TRIALS_SPEC["budget"]["generations"])
    with ctx.write() as s:
        job = repo.create_job(s, owner_key_id=key_id, spec=TRIALS_SPEC, total_generations=gens)
        job_id = job.id
    outcome = execute.execute_job(job_id, wid="bench")
    assert outcome.status == "succeeded", outcome
    problem = prepare(TRIALS_SPEC).problem
    rng = np.random.default_rng(0)
    X = problem.xl + (problem.xu - problem.xl) * rng.random((evaluations, problem.n_var))
    F, G = problem.evaluate(X)
    cv = constraint_violation(G)
    parts = np.array_split(np.arange(evaluations), gens)
    with ctx.write() as s:
        s.execute(delete(EVALUATIONS).where(EVALUATIONS.c.job_id == job_id))
        record_evaluations(s, job_id, [EvaluationsIn(g + 1, X[i], F[i], cv[i])
                                       for g, i in enumerate(parts)])  # fmt: skip
    return str(job_id)


def add_jobs(ctx: Any, key_id: str, n: int, have: int) -> None:
    """Fill the key up to ``n`` jobs (``bench_dashboard.fill``) and write their labels, as the
    API's first listing would."""
    # Imported by name, not followed by mypy (bench_dashboard.py is not under its check).
    fill = importlib.import_module("bench_dashboard").fill
    from services.api.lookups import study_defaults
    from services.store import dashboard_queries as dq

    fill(ctx, key_id, n, have)
    with ctx.write() as s:
        dq.sync_labels(s, key_id, study_defaults, full=True)


@contextmanager
def api_server(data: Path) -> Iterator[str]:
    """``uvicorn services.api.app:app`` on a free port (no worker); yields its URL."""
    import httpx

    port = free_port()
    env = {**os.environ, **environment(data)}
    log = open(data / "api.log", "ab")  # noqa: SIM115 - closed below
    cmd = [sys.executable, "-m", "uvicorn", "services.api.app:app", "--host", "127.0.0.1",
           "--port", str(port), "--log-level", "warning"]  # fmt: skip
    proc = subprocess.Popen(cmd, env=env, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT)
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 120
        while True:
            if proc.poll() is not None:
                raise RuntimeError((data / "api.log").read_text()[-2000:])
            try:
                if httpx.get(f"{url}/api/v1/health", timeout=1).status_code == 200:
                    break
            except httpx.HTTPError:
                pass
            if time.monotonic() > deadline:
                raise RuntimeError("the API did not start in 120 s")
            time.sleep(0.2)
        yield url
    finally:
        proc.terminate()
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        log.close()


@contextmanager
def browser_page(url: str, key: str) -> Iterator[tuple[Any, Any]]:
    """A logged-in dashboard page (the login dialog, as ``tests/web/dashboard_session.py``)
    and its DevTools session (to switch the HTTP cache)."""
    from playwright.sync_api import sync_playwright

    executable = shutil.which("chromium") or shutil.which("chromium-browser")
    if executable is None:
        raise SystemExit("chromium is not installed (apt-get install -y chromium)")
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=executable, args=CHROMIUM_ARGS)
        try:
            context = browser.new_context(viewport={"width": 1400, "height": 1000})
            context.add_init_script(MARKER % repr(MARKS).replace("'", '"'))
            page = context.new_page()
            page.set_default_timeout(TIMEOUT_MS)
            page.goto(url + "/")
            page.wait_for_selector("#login[open]")
            page.fill("#login-key", key)
            page.click("#login-submit")
            page.wait_for_selector("#who:text('bench')")
            cdp = context.new_cdp_session(page)
            cdp.send("Network.enable")  # Network.setCacheDisabled acts only once it is on
            yield page, cdp
        finally:
            browser.close()


def load(page: Any, address: str, marks: list[str]) -> dict[str, float]:
    """One full load of ``address``: ms from navigation start to first paint (``fp``), first
    contentful paint (``fcp``) and each of ``marks`` drawn."""
    page.goto("about:blank")
    page.goto(address)
    wanted = "[" + ",".join(f'"{m}"' for m in marks) + "]"
    page.wait_for_function(f"() => {wanted}.every((k) => k in (window.__benchDrawn || {{}}))")
    got = page.evaluate(READ)
    out = {"fp": float(got["fp"] or "nan"), "fcp": float(got["fcp"] or "nan")}
    out.update({m: float(got["drawn"][m]) for m in marks})
    return out


def measure(page: Any, address: str, marks: list[str], repeat: int) -> dict[str, float]:
    """The median over ``repeat`` loads of each measure of :func:`load`."""
    runs = [load(page, address, marks) for _ in range(repeat)]
    return {k: statistics.median(r[k] for r in runs) for k in runs[0]}


Row = tuple[str, str, str, float, float, float | None]


def bench(data: Path, sizes: list[int], evaluations: int, repeat: int,
          caches: list[str]) -> list[Row]:  # fmt: skip
    """Rows (page, N, cache, first contentful paint ms, data drawn ms, importance drawn ms)."""
    ctx, key_id, raw = setup(data)
    t0 = time.perf_counter()
    job_id = trials_job(ctx, key_id, evaluations)
    print(f"  trials job {job_id}: {evaluations} evaluations, {time.perf_counter() - t0:.1f} s",
          file=sys.stderr)  # fmt: skip
    rows: list[Row] = []
    have = 0
    with api_server(data) as url, browser_page(url, raw) as (page, cdp):
        job_page = f"{url}/#/job/{job_id}"
        trial_marks = ["trials", "lines", "importance"]
        cdp.send("Network.setCacheDisabled", {"cacheDisabled": True})
        first = load(page, job_page, trial_marks)  # the API's caches cold too
        drawn = max(first["trials"], first["lines"])
        what = f"{evaluations:,} evaluations"
        rows.append(
            ("job page, first load", what, "cold", first["fcp"], drawn, first["importance"])
        )
        for cache in caches:
            cdp.send("Network.setCacheDisabled", {"cacheDisabled": cache == "cold"})
            m = measure(page, job_page, trial_marks, repeat)
            rows.append(("job page", f"{evaluations:,} evaluations", cache, m["fcp"],
                         max(m["trials"], m["lines"]), m["importance"]))  # fmt: skip
        for n in sizes:
            page.goto("about:blank")  # no listing polls while the jobs are written
            t0 = time.perf_counter()
            add_jobs(ctx, key_id, n, have)
            have = n
            print(f"  {n} jobs: {time.perf_counter() - t0:.1f} s", file=sys.stderr)
            for cache in caches:
                cdp.send("Network.setCacheDisabled", {"cacheDisabled": cache == "cold"})
                m = measure(page, f"{url}/#/jobs", ["jobs"], repeat)
                rows.append(("jobs page", f"{n:,} jobs", cache, m["fcp"], m["jobs"], None))
            for what, size, cache, fcp, drawn, _ in rows[len(rows) - len(caches) :]:
                print(f"  {what} {size} ({cache}): first contentful paint {fcp:.0f} ms, "
                      f"drawn {drawn:.0f} ms", file=sys.stderr)  # fmt: skip
    ctx.close()
    return rows


def markdown(rows: list[Row], repeat: int) -> str:
    """The table: ms from navigation start, medians of ``repeat`` loads."""
    out = [f"| page | N | HTTP cache | first contentful paint (ms) | data drawn (ms) | "
           f"importance drawn (ms) | goal ≤ {GOAL_MS:.0f} ms |", "|---" * 7 + "|"]  # fmt: skip
    for what, n, cache, fcp, drawn, imp in rows:
        ok = "yes" if max(fcp, drawn) <= GOAL_MS else "**no**"
        out.append(f"| {what} | {n} | {cache} | {fcp:.0f} | {drawn:.0f} | "
                   f"{'—' if imp is None else f'{imp:.0f}'} | {ok} |")  # fmt: skip
    out.append(f"\nMedians of {repeat} full loads each (the first load of the job page: one).")
    return "\n".join(out)


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def chromium_version() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        return "no chromium"
    out = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=60)
    return out.stdout.strip() or "chromium"


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--sizes", default="1000,100000", help="jobs of the key, comma-separated")
    ap.add_argument("--evaluations", type=int, default=10_000, help="the job page's trials")
    ap.add_argument("--repeat", type=int, default=5, help="loads per measure (median)")
    ap.add_argument("--cache", default="cold,warm", help="cold and/or warm HTTP cache")
    args = ap.parse_args()
    from services.store.evaluations import MAX_STORED_EVALUATIONS

    if not 1 <= args.evaluations <= MAX_STORED_EVALUATIONS:
        ap.error(f"--evaluations: 1 … {MAX_STORED_EVALUATIONS}")
    sizes = sorted(int(s) for s in args.sizes.split(","))
    caches = [c for c in args.cache.split(",") if c in ("cold", "warm")] or ["cold"]
    load_start = os.getloadavg()
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="legopt-bench-browser-") as tmp:
        rows = bench(Path(tmp) / "data", sizes, args.evaluations, args.repeat, caches)
    load_end = os.getloadavg()
    print(markdown(rows, args.repeat))
    print(f"\nmachine: {cpu_model()}, {os.cpu_count()} cores, {chromium_version()}, "
          f"Python {platform.python_version()}; load (1 min) {load_start[0]:.2f} at the start, "
          f"{load_end[0]:.2f} at the end; {time.perf_counter() - t0:.0f} s in all")  # fmt: skip
    cmd = " ".join(["python benchmarks/bench_dashboard_browser.py", f"--sizes {args.sizes}",
                    f"--evaluations {args.evaluations}", f"--repeat {args.repeat}",
                    f"--cache {args.cache}"])  # fmt: skip
    print(f"reproduce: {cmd}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
