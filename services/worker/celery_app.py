"""The Celery application, configured from the one settings object.

Broker: ``LEGOPT_BROKER_URL`` — Redis in compose, ``filesystem://`` on the embedded default
(under ``<data_dir>/broker``), so real worker processes run with nothing installed. A
``filesystem://`` URL uses ``services.worker.fs_broker`` (kombu's file transport with atomic
publish and claim; kombu's own can hand a consumer a half-written message) through Celery's
``broker_transport`` setting, in every process that builds this app (API, workers, CLI).
Results live in the database, so there is no result backend.

Long CPU-bound tasks: ``acks_late`` + ``reject_on_worker_lost`` (a killed worker's message is
redelivered), prefetch 1, a visibility timeout above the hard time limit (Redis), and the
worker is started with ``REMAP_SIGTERM=SIGQUIT`` so a stopped container hands its job back.
Brokers are not trusted for recovery: the elected dispatcher (``services.store.dispatcher``)
requeues jobs whose lease expired and re-sends lost messages, and the lease makes a duplicate
delivery harmless.
"""

from __future__ import annotations

import os
from pathlib import Path

from celery import Celery, signals

from services.store.settings import Settings, get_settings
from services.worker import fs_broker

TASK_SOFT_TIME_LIMIT_S = 6 * 3600
TASK_TIME_LIMIT_S = TASK_SOFT_TIME_LIMIT_S + 300
QUEUE = "legopt"


def _is_filesystem(settings: Settings) -> bool:
    return settings.broker_url.startswith("filesystem")


def broker_transport(settings: Settings) -> str | None:
    """Celery's ``broker_transport`` for the configured broker: our filesystem transport for
    ``filesystem://`` (an explicit transport overrides the URL's scheme in kombu, so it is set
    for that URL only); None (the URL's scheme decides) otherwise."""
    return fs_broker.TRANSPORT if _is_filesystem(settings) else None


def broker_options(settings: Settings) -> dict[str, object]:
    """Transport options for the configured broker."""
    if _is_filesystem(settings):
        root = Path(settings.data_dir) / "broker"
        folders = {
            "data_folder_in": root / "queue",  # messages, <ms>_<uuid>.<queue>.msg
            "data_folder_out": root / "queue",
            "processing_folder": root / "processing",  # claimed by one consumer, being read
            "corrupt_folder": root / "corrupt",  # files that were not a message
            "control_folder": root / "control",  # exchange bindings
        }
        for d in folders.values():
            d.mkdir(parents=True, exist_ok=True)
        return {
            **{k: str(v) for k, v in folders.items()},
            # an idle worker looks for a new message file every 0.1 s (default 1 s)
            "polling_interval": 0.1,
        }
    return {"visibility_timeout": TASK_TIME_LIMIT_S + 600}


def make_celery(settings: Settings | None = None) -> Celery:
    """A Celery app for ``settings`` (default: the process settings)."""
    settings = settings or get_settings()
    app = Celery("legopt", broker=settings.broker_url, include=["services.worker.tasks"])
    app.conf.update(
        broker_transport=broker_transport(settings),
        broker_transport_options=broker_options(settings),
        broker_connection_retry_on_startup=True,
        task_default_queue=QUEUE,
        task_acks_late=True,
        task_reject_on_worker_lost=True,
        task_ignore_result=True,
        task_serializer="json",
        accept_content=["json"],
        task_soft_time_limit=TASK_SOFT_TIME_LIMIT_S,
        task_time_limit=TASK_TIME_LIMIT_S,
        worker_prefetch_multiplier=1,
        worker_max_tasks_per_child=200,
        # prefork children past this resident size (KiB) are replaced after their task
        worker_max_memory_per_child=settings.worker_max_memory_mb * 1024 or None,
        worker_hijack_root_logger=False,
        worker_send_task_events=False,
        result_backend=settings.result_backend,
        timezone="UTC",
    )
    return app


app = make_celery()


EMBEDDED_PREFORK_REFUSED = (
    "the embedded filesystem broker runs one job per worker process: with it, billiard's "
    "prefork pool shares one lock among its children, and a killed child holding it wedges "
    "all the others. Start several worker processes instead (`legopt serve --workers N`, or "
    "N × `legopt worker`), or use Redis (LEGOPT_BROKER_URL=redis://...) for --concurrency > 1"
)


def prefork_refused(broker_url: str, pool: object, concurrency: int | None) -> bool:
    """True for a prefork pool of several processes on the filesystem broker (refused)."""
    if not broker_url.startswith("filesystem"):
        return False
    name = pool if isinstance(pool, str) else getattr(pool, "__module__", "")
    return "prefork" in str(name) and (concurrency or 0) > 1


@signals.worker_init.connect
def _one_job_per_process_on_the_embedded_broker(sender: object = None, **_: object) -> None:
    """Refuse to start a prefork pool on the filesystem broker (see EMBEDDED_PREFORK_REFUSED)."""
    pool = getattr(sender, "pool_cls", None)
    concurrency = getattr(sender, "concurrency", None)
    if prefork_refused(get_settings().broker_url, pool, concurrency):
        raise SystemExit(f"legopt worker: {EMBEDDED_PREFORK_REFUSED}")


@signals.worker_init.connect
def _import_database_driver(**_: object) -> None:
    """Import the database driver (psycopg for PostgreSQL) in the main process before any
    thread starts or pool child is forked. Imported lazily instead, by the dispatcher thread
    building its engine, a child forked mid-import inherits the module half-initialised with its
    import lock held by a thread that does not exist in the child: the child's first
    ``session_scope`` then blocks forever (seen in the pool-child chaos test)."""
    from sqlalchemy.engine import make_url

    url = make_url(get_settings().database_url)
    url.get_dialect().import_dbapi()


@signals.worker_init.connect
def _cache_environment(**_: object) -> None:
    """Warm starts (issue 12): seed 000's baselines cached under the data directory
    (``LEGOPT_CACHE_DIR``, read when a job computes them). ``NUMBA_CACHE_DIR`` only counts
    before numba is imported — the tasks already are — so the launcher sets it:
    ``services.embedded.worker_env`` or the image's ``ENV``."""
    for name, value in get_settings().cache_environment().items():
        os.environ.setdefault(name, value)


@signals.worker_init.connect
def _warm_up(**_: object) -> None:
    """Load every compiled kernel before the first job (``Settings.worker_warmup``): in the
    main process, so a solo worker and the children of a prefork pool start warm."""
    if not get_settings().worker_warmup:
        return
    import logging

    from legcore.warmup import warm_up

    log = logging.getLogger(__name__)
    try:
        times = warm_up(verbose=False)
    except Exception:  # noqa: BLE001 - a cold first job is slower, not wrong
        log.warning("worker warm-up failed", exc_info=True)
        return
    log.info("worker warm-up: %s", ", ".join(f"{k} {v:.1f} s" for k, v in times.items()))
