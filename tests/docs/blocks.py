"""Fenced code blocks of the Markdown docs, and the two interpreters that run them.

:func:`code_blocks` extracts every fenced block (also indented ones inside list items) with its
file, line and info string. :class:`PythonSession` is one persistent Python interpreter that
executes blocks one after the other in a shared namespace; :class:`BashSession` runs each bash
block in a fresh ``bash -euo pipefail`` that first sources the variables the earlier blocks
exported.
"""

from __future__ import annotations

import json
import os
import re
import select
import signal
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Block", "BashSession", "PythonSession", "code_blocks"]

_FENCE = re.compile(r"^(\s*)(```+|~~~+)\s*(.*)$")


@dataclass(frozen=True)
class Block:
    """One fenced block: ``path`` (relative to the repo), 1-based ``line`` of its opening
    fence, ``info`` string (``python``, ``bash sketch`` …) and its ``code`` (dedented)."""

    path: str
    line: int
    info: str
    code: str

    @property
    def lang(self) -> str:
        return self.info.split()[0].lower() if self.info.split() else ""

    @property
    def sketch(self) -> bool:
        return "sketch" in self.info.split()

    @property
    def where(self) -> str:
        return f"{self.path}:{self.line}"


def code_blocks(path: Path, root: Path) -> list[Block]:
    """Every fenced code block of the Markdown file ``path``, in order."""
    blocks: list[Block] = []
    lines = path.read_text().splitlines()
    i = 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, fence, info = m.group(1), m.group(2), m.group(3).strip()
        start, body = i + 1, []
        i += 1
        while i < len(lines) and not lines[i].strip().startswith(fence):
            line = lines[i]
            body.append(line[len(indent) :] if line.startswith(indent) else line.lstrip())
            i += 1
        blocks.append(Block(str(path.relative_to(root)), start, info, "\n".join(body) + "\n"))
        i += 1
    return blocks


# The persistent interpreter: reads one JSON request per line ({"code", "where"}), runs it in
# one namespace with stdout/stderr captured, answers one JSON line on a private descriptor (what
# the code or its libraries write to the real fds 1/2 goes to a log file instead).
_DRIVER = r"""
import contextlib, io, json, os, sys, traceback
reply = os.fdopen(os.dup(1), "w")
log = os.open(sys.argv[1], os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
os.dup2(log, 1); os.dup2(log, 2)
ns = {"__name__": "__main__"}
for line in sys.stdin:
    req = json.loads(line)
    buf = io.StringIO()
    ok = True
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf):
        try:
            exec(compile(req["code"], req["where"], "exec"), ns)
        except BaseException:
            ok = False
            traceback.print_exc()
    reply.write(json.dumps({"ok": ok, "output": buf.getvalue()}) + "\n")
    reply.flush()
"""


class PythonSession:
    """One Python process for the python blocks of a document (started on first use)."""

    def __init__(self, cwd: Path, env: dict[str, str], log: Path) -> None:
        self.cwd, self.env, self.log = cwd, env, log
        self.proc: subprocess.Popen[str] | None = None

    def run(self, block: Block, timeout_s: float) -> tuple[bool, str]:
        if self.proc is None:
            self.proc = subprocess.Popen(
                [sys.executable, "-u", "-c", _DRIVER, str(self.log)],
                cwd=self.cwd, env=self.env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                text=True,
            )  # fmt: skip
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(json.dumps({"code": block.code, "where": block.where}) + "\n")
        self.proc.stdin.flush()
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout_s)
        if not ready:
            self.close()
            return False, f"timed out after {timeout_s:.0f} s"
        line = self.proc.stdout.readline()
        if not line:
            code = self.proc.wait()
            self.proc = None
            return False, f"the interpreter exited ({code}); see {self.log}"
        answer = json.loads(line)
        return bool(answer["ok"]), str(answer["output"])

    def close(self) -> None:
        if self.proc is not None:
            if self.proc.stdin is not None:
                self.proc.stdin.close()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
            self.proc = None


class BashSession:
    """Bash blocks of a document, in order; exported variables carry to the next block."""

    def __init__(self, cwd: Path, env: dict[str, str]) -> None:
        self.cwd, self.env = cwd, env
        self.state = cwd / ".docs-bash-state"

    def run(self, block: Block, timeout_s: float) -> tuple[bool, str]:
        script = (
            "set -euo pipefail\n"
            f'if [ -f "{self.state}" ]; then source "{self.state}"; fi\n'
            f"{block.code}\n"
            f'export -p > "{self.state}"\n'
        )
        proc = subprocess.Popen(
            ["bash", "-c", script], cwd=self.cwd, env=self.env, stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT, text=True, start_new_session=True,
        )  # fmt: skip
        try:
            out, _ = proc.communicate(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)  # the block's whole process group
            out, _ = proc.communicate()
            return False, f"timed out after {timeout_s:.0f} s\n{out}"
        return proc.returncode == 0, out


def venv_path(env: dict[str, str]) -> dict[str, str]:
    """``env`` with the interpreter's bin directory first on PATH (``legopt``, ``python3``)."""
    bindir = str(Path(sys.executable).parent)
    return dict(env, PATH=bindir + os.pathsep + env.get("PATH", ""))
