"""Defect 3: no lock is held across a fork.

A prefork worker's main process runs the dispatcher thread; when billiard forked a pool child
while that thread held the process engine's lock, the child blocked forever in
``session_scope``. Here a thread holds the lock while the test forks: the child must still
open a session and finish.
"""

from __future__ import annotations

import os
import signal
import threading
import time
from pathlib import Path

import pytest
from sqlalchemy import text

from services.store import session as session_mod
from services.store.session import reset_engine, session_scope
from services.store.settings import get_settings

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="needs os.fork")


def test_child_forked_while_another_thread_holds_the_engine_lock(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("LEGOPT_DATA_DIR", str(tmp_path))
    monkeypatch.delenv("LEGOPT_DATABASE_URL", raising=False)
    get_settings.cache_clear()
    reset_engine()
    try:
        with session_scope() as s:  # the parent has an engine
            s.execute(text("SELECT 1"))
        held, release = threading.Event(), threading.Event()

        def hold() -> None:
            with session_mod._PROCESS._lock:  # e.g. the dispatcher building its engine
                held.set()
                release.wait(30)

        holder = threading.Thread(target=hold, daemon=True)
        holder.start()
        assert held.wait(10)
        pid = os.fork()
        if pid == 0:  # the child: only this thread exists; the lock's holder does not
            code = 1
            try:
                with session_scope() as s:
                    s.execute(text("SELECT 1"))
                code = 0
            finally:
                os._exit(code)
        release.set()
        holder.join(10)
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                assert os.waitstatus_to_exitcode(status) == 0
                return
            time.sleep(0.05)
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        pytest.fail("the forked child deadlocked on the engine lock held by a parent thread")
    finally:
        get_settings.cache_clear()
        reset_engine()
