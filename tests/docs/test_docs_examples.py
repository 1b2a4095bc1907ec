"""Every fenced code block of README.md and docs/*.md runs, or says it is a sketch.

The rules, per document (one test each), blocks in the order they appear:

1. A block whose info string contains ``sketch`` (```` ```python sketch ````) is not run: a
   fragment, a long-running command (``legopt serve``, ``docker compose``, ``python3 run.py
   demo``), a diagram or a formula. Every other block must have one of the languages below.
2. A block's output must not print an empty value (a line that is or ends in ``None`` or
   ``nan``): the sign of an example reading a name that does not exist.
3. ``python`` blocks of a document run in ONE interpreter, in order, sharing their namespace: a
   later block continues the earlier ones (define a name before the block that uses it).
4. ``bash`` blocks run each in ``bash -euo pipefail``, in order; variables a block ``export``s
   are set in the following ones. ``legopt`` and ``python3`` are this environment's.
5. ``json`` and ``yaml`` blocks must parse.
6. Python and bash blocks run in a fresh working directory holding ``examples/`` (the
   repository's) and an empty ``out/``, with the repository importable. A document whose
   runnable blocks talk to the service (``curl``,
   ``legopt submit|status|results|cancel|sweep|replay|keys``, ``$API``, ``os.environ["API"]``)
   gets ``API`` (…/api/v1), ``KEY``, ``LEGOPT_API_URL``,
   ``LEGOPT_API_KEY`` and ``LEGOPT_DATA_DIR`` of a real embedded service (API + 1 worker,
   `tests/integration/stack.py`), started once for this module.
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

from tests.docs.blocks import BashSession, Block, PythonSession, code_blocks, venv_path
from tests.integration.stack import Stack, embedded_stack

ROOT = Path(__file__).resolve().parents[2]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
RUNNABLE = {"python", "bash", "json", "yaml"}
#: Seconds one block may take: a hang guard (the slowest run a short optimisation or a service
#: round trip, but on a cold numba cache the IK block compiles the numerical IK first, ~1.5 min).
BLOCK_TIMEOUT_S = 600.0
_NEEDS_SERVICE = re.compile(
    r"\bcurl\b|\blegopt (submit|status|results|cancel|sweep|replay|keys)\b|\$API\b|\$\{API\}"
    r"|environ\[.API.\]"
)

#: A printed line that is, or ends in, an empty value: a block whose example looks up a name
#: that is not there prints it (``print(metrics.get("energy"))`` -> ``None``).
_EMPTY_VALUE = re.compile(r"(^|[\s:=])(None|nan)\s*$", re.MULTILINE)

pytestmark = pytest.mark.integration


@pytest.fixture(scope="module")
def service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Stack]:
    tmp = tmp_path_factory.mktemp("docs-stack")
    with embedded_stack(tmp) as st:
        yield st


def _runnable(blocks: list[Block]) -> list[Block]:
    return [b for b in blocks if not b.sketch]


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_block_runs_or_is_a_sketch(
    doc: Path, tmp_path: Path, request: pytest.FixtureRequest
) -> None:
    blocks = _runnable(code_blocks(doc, ROOT))
    unmarked = [f"{b.where} (```{b.info})" for b in blocks if b.lang not in RUNNABLE]
    assert not unmarked, f"blocks neither runnable nor marked sketch: {unmarked}"
    if not blocks:
        return
    work = tmp_path / "work"
    work.mkdir()
    (work / "examples").symlink_to(ROOT / "examples")
    (work / "out").mkdir()
    env = venv_path(dict(os.environ))
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    env["LEGOPT_DATA_DIR"] = str(tmp_path / "data")
    for var in ("LEGOPT_DATABASE_URL", "LEGOPT_BROKER_URL", "LEGOPT_ARTIFACT_DIR"):
        env.pop(var, None)
    if any(_NEEDS_SERVICE.search(b.code) for b in blocks if b.lang in {"python", "bash"}):
        st: Stack = request.getfixturevalue("service")
        env.update({k: v for k, v in st.env.items() if k.startswith("LEGOPT_")})
        env.update(API=f"{st.url}/api/v1", KEY=st.key, LEGOPT_API_URL=st.url,
                   LEGOPT_API_KEY=st.key)  # fmt: skip
    python = PythonSession(work, env, tmp_path / "python.log")
    bash = BashSession(work, env)
    failures: list[str] = []
    try:
        for b in blocks:
            if b.lang == "json":
                ok, out = _parses(json.loads, b)
            elif b.lang == "yaml":
                ok, out = _parses(yaml.safe_load, b)
            elif b.lang == "python":
                ok, out = python.run(b, BLOCK_TIMEOUT_S)
            else:
                ok, out = bash.run(b, BLOCK_TIMEOUT_S)
            if ok and _EMPTY_VALUE.search(out):  # the review's sweep loop printed `None`
                ok, out = False, f"a printed value is empty (None/nan):\n{out}"
            if not ok:
                failures.append(f"--- {b.where} (```{b.info})\n{b.code}--- output:\n{out[-3000:]}")
    finally:
        python.close()
    assert not failures, "\n".join(failures)


def _parses(parse: object, block: Block) -> tuple[bool, str]:
    try:
        parse(block.code)  # type: ignore[operator]
    except Exception as exc:
        return False, f"{type(exc).__name__}: {exc}"
    return True, ""


def test_blocks_are_found_with_their_lines() -> None:
    """The extraction itself: an indented fence inside a list item, an info string."""
    blocks = code_blocks(ROOT / "docs" / "api.md", ROOT)
    assert any(b.lang == "json" and b.code.startswith('{"detail"') for b in blocks)
    first = blocks[0]
    assert first.line > 1 and first.where.startswith("docs/api.md:")
