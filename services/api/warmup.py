"""Warm the API's validation processes at start, so that no submission waits for a cold one.

Validating a job prepares its problem (``services.api.validation``): the first time in a
process that starts the validation process (a forkserver that imports legcore), loads every
numba kernel the study uses from the cache and builds the study's robot — seconds, where a warm
validation takes milliseconds (issue 21: the first ``POST /jobs`` of a fresh API took 126 s).
A server therefore validates one minimal job of every study kind (``example_specs``) in its
validation processes right after it starts, in a background thread: ``/health`` answers at
once, ``/ready`` answers 503 "warming up" until this is done (``Settings.api_warmup``; off:
ready at once, the first submission pays instead).
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Any

from services.store.settings import Settings

log = logging.getLogger("legopt.api")

#: The key the warm-up is admitted under in the validation pool (never an API key's id).
WARMUP_KEY = "legopt-warmup"


def validate_examples() -> dict[str, float]:
    """In a validation process: validate one minimal job of every study kind; seconds each
    (a kind whose example does not validate is logged and skipped: the warm-up never fails)."""
    from services.api.validation import check_job_spec, example_specs
    from services.store.settings import get_settings

    settings = get_settings()
    times: dict[str, float] = {}
    for kind, spec in example_specs().items():
        t0 = time.monotonic()
        try:
            check_job_spec(spec, settings=settings, lookup=lambda _ref: None)
        except Exception as exc:  # noqa: BLE001 - a warm-up is best effort
            log.warning("warm-up of %s: %s", kind, exc)
        times[kind] = time.monotonic() - t0
    return times


class Warmup:
    """The state of one API process's warm-up: ``done`` once it ended (also when it failed or
    is off), ``seconds`` what it took."""

    def __init__(self) -> None:
        self.done = threading.Event()
        self.seconds: float | None = None

    def start(self, settings: Settings) -> None:
        """Warm in a daemon thread (``settings.api_warmup`` and validation processes on), or
        mark done at once."""
        if not settings.api_warmup or settings.validation_processes == 0:
            self.done.set()
            return
        threading.Thread(
            target=self._run, args=(settings,), name="legopt-warmup", daemon=True
        ).start()

    def _run(self, settings: Settings) -> None:
        from services.api.validation_pool import pool

        t0 = time.monotonic()
        try:
            times: Any = pool(settings).run(WARMUP_KEY, settings, ("warmup",), validate_examples)
            log.info(
                "validation warm-up: %s",
                ", ".join(f"{k} {v:.1f} s" for k, v in dict(times).items()),
            )
        except Exception:  # noqa: BLE001 - a cold first submission is slower, not wrong
            log.warning("validation warm-up failed", exc_info=True)
        finally:
            self.seconds = time.monotonic() - t0
            self.done.set()


__all__ = ["WARMUP_KEY", "Warmup", "validate_examples"]
