"""A sweep's merged recording, made once per set of recordings and kept in the cache.

Merging reads and writes Rerun files through ``rerun-sdk``, whose recording streams keep
threads and native memory; done in the API process, every download grew it (issue 8). The merge
therefore runs in a short-lived child process, and its output is cached under
``<cache_dir>/merged/`` by a content key (the member recordings' SHA-256 and their names), so a
repeated download is a file read. The cache keeps the most recently used files up to
:data:`KEEP_BYTES` in all (and always the newest).

Bounds (issue 22): each child holds the member recordings in memory (~120 MB for a few jobs),
so at most :data:`MERGE_WORKERS` merges run at once per API process, at most
:data:`MAX_PENDING` distinct merges wait or run (beyond that: 429 with ``Retry-After``), and
parallel requests for the same merge share one child (``services.api.bounded_work``).

The members may be given as a function returning a context of local files (an S3 artifact
store downloads them to temporary files): it is entered only when the merge is made (not for a
cached one), inside the bounded work, and left when the child is done.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import AbstractContextManager, ExitStack, contextmanager
from pathlib import Path
from typing import Any

from services.api.bounded_work import BoundedWork
from services.store.artifacts import ArtifactStore
from services.store.errors import ArtifactMissingError

#: Bytes of merged files kept in the cache (least recently used removed first).
KEEP_BYTES = 1 << 30
#: Seconds a merge may take before it is abandoned.
TIMEOUT_S = 300.0
#: Merge children running at once per API process.
MERGE_WORKERS = 2
#: Distinct merges waiting or running at once per API process (beyond: 429).
MAX_PENDING = 6

_work = BoundedWork(
    "legopt-merge", workers=MERGE_WORKERS, max_pending=MAX_PENDING, wait_s=TIMEOUT_S + 30
)

_CHILD = (
    "import json, sys\n"
    "from pathlib import Path\n"
    "from services.recording.merge import merge_recordings\n"
    "a = json.loads(sys.argv[1])\n"
    "merge_recordings([Path(p) for p in a['paths']], Path(a['out']), a['names'])\n"
)


#: The member recordings: local files, or a function returning a context that holds them.
Members = Sequence[Path] | Callable[[], AbstractContextManager[Sequence[Path]]]


def stored_members(
    store: ArtifactStore, members: Sequence[tuple[str, Any]]
) -> Callable[[], AbstractContextManager[Sequence[Path]]]:
    """The ``Members`` of ``(job id, recording ArtifactRecord)`` pairs: local files verified
    against their SHA-256 (downloaded first from a remote store); one that is gone is an
    ``ArtifactMissingError`` (404) naming its job."""

    @contextmanager
    def local() -> Iterator[Sequence[Path]]:
        with ExitStack() as stack:
            paths = []
            for job_id, art in members:
                try:
                    copy = store.local_copy(art.relative_path, art.sha256)
                    paths.append(stack.enter_context(copy))
                except ArtifactMissingError:
                    raise ArtifactMissingError(
                        f"the recording of job {job_id} is missing from the artifact store "
                        f"(recorded as {art.relative_path}): choose the others with ?jobs=…"
                    ) from None
            yield paths

    return local


def merge_key(names: Sequence[str], digests: Sequence[str]) -> str:
    """Content key of a merge: the members' names and recording SHA-256, in order."""
    doc = json.dumps([list(names), list(digests)], separators=(",", ":"))
    return hashlib.sha256(doc.encode()).hexdigest()[:32]


def merged_recording(
    paths: Members, names: Sequence[str], digests: Sequence[str], cache_dir: Path
) -> Path:
    """Path of the merged recording of ``paths`` (made now in a child process unless cached;
    bounded and shared as the module docstring says).

    Raises:
        RuntimeError: the merge failed or timed out (its error output in the message).
        fastapi.HTTPException: 429 (too many merges queued) or 503 (still running).
    """
    folder = cache_dir / "merged"
    folder.mkdir(parents=True, exist_ok=True)
    key = merge_key(names, digests)
    out = folder / f"{key}.rrd"
    if out.is_file():
        os.utime(out)  # recently used: kept by the pruning below
        return out
    return _work.run(key, lambda: _merge(paths, names, out), f"the merged recording {key[:8]}")


def _merge(paths: Members, names: Sequence[str], out: Path) -> Path:
    """Merge in a child process into ``out`` (kept if another request made it meanwhile)."""
    if out.is_file():
        return out
    if callable(paths):
        with paths() as local:
            return _merge(local, names, out)
    arg = json.dumps({"paths": [str(p) for p in paths], "out": str(out), "names": list(names)})
    try:
        done = subprocess.run(
            [sys.executable, "-c", _CHILD, arg],
            capture_output=True, text=True, timeout=TIMEOUT_S, check=False,
        )  # fmt: skip
    except subprocess.TimeoutExpired:
        raise RuntimeError(f"the merge took more than {TIMEOUT_S:.0f} s") from None
    if done.returncode != 0 or not out.is_file():
        tail = (done.stderr or "").strip().splitlines()[-1:] or [f"exit {done.returncode}"]
        raise RuntimeError(tail[0])
    _prune(out.parent)
    return out


def _prune(folder: Path, keep_bytes: int = KEEP_BYTES) -> None:
    """Remove the least recently used merged files beyond ``keep_bytes`` in all (the newest
    one always stays)."""
    stamped = []
    for p in folder.glob("*.rrd"):
        try:
            st = p.stat()
        except FileNotFoundError:  # pruned meanwhile by another API process
            continue
        stamped.append((st.st_mtime, st.st_size, p))
    total = 0
    for i, (_, size, p) in enumerate(sorted(stamped, key=lambda t: t[0], reverse=True)):
        total += size
        if i > 0 and total > keep_bytes:
            p.unlink(missing_ok=True)
