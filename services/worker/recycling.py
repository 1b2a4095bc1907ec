"""Worker recycling: a solo worker that has grown past ``worker_max_memory_mb`` (MiB) stops
after its current job and is replaced by its supervisor (``legopt serve``, compose)."""

from __future__ import annotations

import logging
import os

from services.store.settings import Settings

log = logging.getLogger("legopt.worker")


def resident_mb() -> float:
    """Resident memory of this process (MiB), or 0 where it cannot be read."""
    try:
        with open("/proc/self/statm") as f:
            pages = int(f.read().split()[1])
        return pages * os.sysconf("SC_PAGE_SIZE") / 2**20
    except (OSError, ValueError, IndexError):
        return 0.0


def recycle_if_large(settings: Settings) -> None:
    """Worker recycling of a solo worker: past ``worker_max_memory_mb``, ask Celery for a warm
    shutdown after this task (its message is handled); ``legopt serve`` or compose starts a
    fresh worker. Nothing forks here, so nothing can deadlock. (Prefork pools recycle their
    children with Celery's ``worker_max_memory_per_child``, set from the same setting.)"""
    limit = settings.worker_max_memory_mb
    if limit <= 0:
        return
    from billiard import current_process

    if current_process().name != "MainProcess":
        return  # a prefork pool child: Celery's worker_max_memory_per_child replaces it
    rss = resident_mb()
    if rss > limit:
        from celery.worker import state

        log.warning("worker uses %.0f MiB > %d MiB: it stops after this job", rss, limit)
        state.should_stop = 0
