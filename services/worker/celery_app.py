"""The Celery application, configured from the one settings object.

Broker: ``LEGOPT_BROKER_URL`` — Redis in compose, ``filesystem://`` (kombu's file transport
under ``<data_dir>/broker``) on the embedded default, so real worker processes run with nothing
installed. Results live in the database, so there is no result backend.

Long CPU-bound tasks: ``acks_late`` + ``reject_on_worker_lost`` (a killed worker's message is
redelivered), prefetch 1, a visibility timeout above the hard time limit (Redis), and the
worker is started with ``REMAP_SIGTERM=SIGQUIT`` so a stopped container hands its job back.
Brokers are not trusted for recovery: the reaper (``services.worker.reaper``) requeues jobs whose
lease expired, and the lease makes a duplicate delivery harmless.
"""

from __future__ import annotations

from pathlib import Path

from celery import Celery, signals

from services.store.settings import Settings, get_settings

TASK_SOFT_TIME_LIMIT_S = 6 * 3600
TASK_TIME_LIMIT_S = TASK_SOFT_TIME_LIMIT_S + 300
QUEUE = "legopt"


def broker_options(settings: Settings) -> dict[str, object]:
    """Transport options for the configured broker."""
    if settings.broker_url.startswith("filesystem"):
        root = Path(settings.data_dir) / "broker"
        queue_dir = root / "queue"
        processed = root / "processed"
        control = root / "control"
        for d in (queue_dir, processed, control):
            d.mkdir(parents=True, exist_ok=True)
        return {
            "data_folder_in": str(queue_dir),
            "data_folder_out": str(queue_dir),
            "processed_folder": str(processed),
            "store_processed": False,
            "control_folder": str(control),
            # an idle worker looks for a new message file every 0.1 s (default 1 s)
            "polling_interval": 0.1,
        }
    return {"visibility_timeout": TASK_TIME_LIMIT_S + 600}


def make_celery(settings: Settings | None = None) -> Celery:
    """A Celery app for ``settings`` (default: the process settings)."""
    settings = settings or get_settings()
    app = Celery("legopt", broker=settings.broker_url, include=["services.worker.tasks"])
    app.conf.update(
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
        worker_hijack_root_logger=False,
        worker_send_task_events=False,
        result_backend=settings.result_backend,
        timezone="UTC",
    )
    return app


app = make_celery()


@signals.worker_ready.connect
def _start_reaper(**_: object) -> None:
    """Every worker process also reaps expired leases (recovery never waits on the broker)."""
    from services.worker.reaper import Reaper
    from services.worker.tasks import enqueue

    Reaper(enqueue).start()
