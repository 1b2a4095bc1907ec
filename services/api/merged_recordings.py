"""A sweep's merged recording, made once per set of recordings and kept in the cache.

Merging reads and writes Rerun files through ``rerun-sdk``, whose recording streams keep
threads and native memory; done in the API process, every download grew it (issue 8). The merge
therefore runs in a short-lived child process, and its output is cached under
``<cache_dir>/merged/`` by a content key (the member recordings' SHA-256 and their names), so a
repeated download is a file read. The cache keeps the newest :data:`KEEP` files.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

#: Merged files kept in the cache (oldest removed first).
KEEP = 32
#: Seconds a merge may take before it is abandoned.
TIMEOUT_S = 300.0

_CHILD = (
    "import json, sys\n"
    "from pathlib import Path\n"
    "from services.worker.rerun_merge import merge_recordings\n"
    "a = json.loads(sys.argv[1])\n"
    "merge_recordings([Path(p) for p in a['paths']], Path(a['out']), a['names'])\n"
)


def merge_key(names: Sequence[str], digests: Sequence[str]) -> str:
    """Content key of a merge: the members' names and recording SHA-256, in order."""
    doc = json.dumps([list(names), list(digests)], separators=(",", ":"))
    return hashlib.sha256(doc.encode()).hexdigest()[:32]


def merged_recording(
    paths: Sequence[Path], names: Sequence[str], digests: Sequence[str], cache_dir: Path
) -> Path:
    """Path of the merged recording of ``paths`` (made now in a child process unless cached).

    Raises:
        RuntimeError: the merge failed or timed out (its error output in the message).
    """
    folder = cache_dir / "merged"
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / f"{merge_key(names, digests)}.rrd"
    if out.is_file():
        os.utime(out)  # recently used: kept by the pruning below
        return out
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
    _prune(folder)
    return out


def _prune(folder: Path) -> None:
    """Remove all but the :data:`KEEP` most recently used merged files."""
    stamped = []
    for p in folder.glob("*.rrd"):
        try:
            stamped.append((p.stat().st_mtime, p))
        except FileNotFoundError:  # pruned meanwhile by another API process
            continue
    for _, old in sorted(stamped, reverse=True)[KEEP:]:
        old.unlink(missing_ok=True)
