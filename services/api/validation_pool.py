"""The heavy part of validating a submission, run in processes of their own, a bounded number of
submissions at a time: one API key cannot starve the API (issue 22 item 4).

Why: validating ``POST /jobs``, ``/sweeps`` and ``/robots`` builds the robot and prepares the
problem (``services.api.validation``): Pinocchio parsing a 1.7 MB URDF is ~0.75 s of CPU, much
of it in C++ holding the GIL. Run in the API process (sync routes run in its threadpool), six
such submissions pushed ``GET /health`` to ~1 s (``benchmarks/bench_health_under_load.py``).

What runs where. The API process reads the database (stored robots a spec names by id or name
are looked up into a table first, ``validation.stored_references``), admits the request and
waits; a validation process runs the check (a module-level function of this module: a job
spec, every point of a sweep in one call sharing its ``SpecCache``, a robot's build, summary
and capabilities) and sends back plain data (``CheckedJob``, ``RobotInfo``) or the errors of
its 422, which the API raises again unchanged. The routes call one function per kind of check:
:func:`check_job`, :func:`check_sweep`, :func:`check_robot`.

Admission, per API process:

- one submission being validated per API key: a second concurrent one gets 429 at once, with
  ``Retry-After`` (the mean validation time);
- at most ``WAITING_PER_PROCESS`` × processes submissions admitted (validated or waiting for a
  process) over all keys; beyond that, 503 with ``Retry-After``;
- a validation runs at most ``Settings.validation_timeout_s``: then its process is killed with
  its pool and the request gets a 422 at the robot (or the spec) saying the model could not be
  validated; so does a request whose process dies (a crash in Pinocchio). Never a 500: the
  next request gets a fresh pool. With more than one process a request whose pool broke is
  retried once, as another request's process may have been the one that died.

The pool (``Settings.validation_processes`` processes, default 1; 0 validates in the API
process itself) is created on first use, once per API process, like the point executor of
``services.api.points``. Its processes are forked by a forkserver that imported this module
once (not ``fork``: the API has threads; not ``spawn``: each process would import legcore,
several seconds), exit when the API process does (even on SIGKILL), and are replaced
every ``TASKS_PER_POOL`` validations to bound their memory: the pool is swapped for a new one
(``ProcessPoolExecutor``'s own ``max_tasks_per_child`` can deadlock on Python 3.11, CPython
gh-115634).
"""

from __future__ import annotations

import atexit
import logging
import multiprocessing
import os
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures import TimeoutError as FutureTimeout
from concurrent.futures.process import BrokenProcessPool
from multiprocessing.context import BaseContext
from typing import Any, TypeVar

from fastapi import HTTPException, status
from fastapi.exceptions import RequestValidationError

from services.api.errors import MAX_ERRORS, Loc, invalid, public_errors, validation_error
from services.api.rate_limit import retry_after_header
from services.api.robot_validation import RobotInfo, check_robot_doc
from services.api.sweeps import SweepPoint
from services.api.validation import CheckedJob, check_job_spec
from services.store.settings import Settings

log = logging.getLogger("legopt.api")

T = TypeVar("T")
Errors = list[dict[str, Any]]
Relocate = Callable[[Errors, SweepPoint], Errors]

#: Validations a pool's processes run before the pool is replaced by a fresh one (memory).
TASKS_PER_POOL = 100
#: Submissions admitted at once per validation process (validated or waiting), over all keys.
WAITING_PER_PROCESS = 4

# --------------------------------------------------------------------------- in the process


def _child_init() -> None:
    """First thing in a validation process: a thread that ends it as soon as the API process
    that asked for it is gone, however it ended (the process holds the forkserver's liveness
    pipe, so the forkserver exits only once its validation processes have)."""
    parent = multiprocessing.parent_process()  # the API process, not the forkserver
    if parent is None:
        return

    def watch() -> None:
        parent.join()  # returns when the API's end of its sentinel pipe closes
        os._exit(0)

    threading.Thread(target=watch, name="legopt-validation-watchdog", daemon=True).start()


def _outcome(fn: Callable[..., T], *args: Any) -> tuple[T | None, Errors | None]:
    """``(fn(*args), None)``, or ``(None, errors)`` of the 422 it raised: plain JSON-safe
    entries (``public_errors``: no input, context made JSON), so they always pickle."""
    try:
        return fn(*args), None
    except RequestValidationError as exc:
        return None, public_errors(exc.errors())


def _check_job(doc: Any, table: dict[str, Any], settings: Settings) -> CheckedJob:
    """``check_job_spec`` with stored robots resolved through ``table``."""
    return check_job_spec(doc, settings=settings, lookup=table.get)


def _check_sweep(
    points: Sequence[SweepPoint],
    table: dict[str, Any],
    settings: Settings,
    relocate: Relocate,
    prefix: Loc,
) -> list[CheckedJob]:
    """Every point's ``check_job_spec`` sharing one cache; a 422 listing each distinct error
    (at most ``MAX_ERRORS``) at the override that caused it (``relocate``)."""
    checked: list[CheckedJob] = []
    errors: Errors = []
    seen: set[tuple[str, str]] = set()
    cache: dict[str, Any] = {}
    for point in points:
        try:
            checked.append(
                check_job_spec(
                    point.spec, settings=settings, lookup=table.get, prefix=prefix, cache=cache
                )
            )
        except RequestValidationError as exc:
            for err in relocate(list(exc.errors()), point):
                ident = (repr(err["loc"]), err["msg"])
                if ident not in seen:
                    seen.add(ident)
                    errors.append(err)
            if len(errors) >= MAX_ERRORS:
                break
    if errors:
        raise validation_error(errors)
    return checked


def _check_robot(catalog_name: str | None, spec: Any) -> RobotInfo:
    """``check_robot_doc``: the robot of ``POST /robots`` built and described."""
    return check_robot_doc(catalog_name, spec)


# --------------------------------------------------------------------------- in the API


def _context() -> BaseContext:
    """The forkserver context, the server importing this module (and so legcore) once."""
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload([__name__])
    return ctx


class ValidationPool:
    """``processes`` validation processes (0: validate in the calling thread) and the
    admission rules of the module docstring."""

    def __init__(self, processes: int) -> None:
        if processes < 0:
            raise ValueError("processes must be >= 0")
        self.processes = processes
        self.max_admitted = WAITING_PER_PROCESS * max(1, processes)
        self._keys: set[str] = set()
        self._lock = threading.Lock()  # admission
        self._pool_lock = threading.Lock()  # the executor
        self._slots = threading.BoundedSemaphore(max(1, processes))
        self._executor: ProcessPoolExecutor | None = None
        self._tasks = 0
        self._mean_s = 1.0

    def run(self, key_id: str, settings: Settings, loc: Loc, fn: Callable[..., T], *args: Any) -> T:
        """``fn(*args)`` in a validation process for API key ``key_id``; its 422 raised here.
        429 / 503 when not admitted; 422 at ``loc`` when the process dies or times out."""
        self.admit(key_id)
        try:
            if self.processes == 0:
                result, errors = _outcome(fn, *args)
            else:
                result, errors = self._in_process(settings, loc, fn, args)
        finally:
            self.release(key_id)
        if errors is not None:
            raise validation_error(errors)
        return result  # type: ignore[return-value]

    def admit(self, key_id: str) -> None:
        """Count a validation of ``key_id`` in (undone by :meth:`release`); 429 when that key
        has one already, 503 when ``max_admitted`` are in."""
        with self._lock:
            wait = retry_after_header(self._mean_s)
            if key_id in self._keys:
                raise HTTPException(
                    status.HTTP_429_TOO_MANY_REQUESTS,
                    "this API key already has a submission being validated in this API process: "
                    "one at a time per key (validation builds the robot and prepares the "
                    f"problem, the costly part of a submission); retry in {wait} s",
                    headers={"Retry-After": wait},
                )
            if len(self._keys) >= self.max_admitted:
                wait = retry_after_header(self._mean_s * len(self._keys) / max(1, self.processes))
                raise HTTPException(
                    status.HTTP_503_SERVICE_UNAVAILABLE,
                    f"{len(self._keys)} submissions are being validated or waiting for it in "
                    f"this API process (at most {self.max_admitted}); retry in {wait} s",
                    headers={"Retry-After": wait},
                )
            self._keys.add(key_id)

    def release(self, key_id: str) -> None:
        """The validation of ``key_id`` is over."""
        with self._lock:
            self._keys.discard(key_id)

    def _in_process(
        self, settings: Settings, loc: Loc, fn: Callable[..., T], args: tuple[Any, ...]
    ) -> tuple[T | None, Errors | None]:
        timeout = settings.validation_timeout_s
        if not self._slots.acquire(timeout=timeout):
            wait = retry_after_header(self._mean_s)
            raise HTTPException(
                status.HTTP_503_SERVICE_UNAVAILABLE,
                f"every validation process of this API process stayed busy for {timeout:g} s; "
                f"retry in {wait} s",
                headers={"Retry-After": wait},
            )
        try:
            for _attempt in range(2 if self.processes > 1 else 1):
                start = time.monotonic()
                try:
                    executor, future = self._submit(fn, args)
                except BrokenProcessPool:
                    log.warning("validation processes die on start", exc_info=True)
                    continue
                try:
                    outcome: tuple[T | None, Errors | None] = future.result(timeout=timeout)
                except FutureTimeout:
                    self._discard(executor, kill=True)
                    log.warning("validation took over %g s: its process was killed", timeout)
                    raise _not_validated(
                        loc,
                        f"its validation took longer than {timeout:g} s "
                        "(LEGOPT_VALIDATION_TIMEOUT_S) and was stopped; simplify it (fewer "
                        "links or joints, a shorter path)",
                    ) from None
                except BrokenProcessPool:
                    log.warning("a validation process died", exc_info=True)
                    self._discard(executor, kill=False)
                    continue
                with self._lock:
                    self._mean_s = 0.8 * self._mean_s + 0.2 * (time.monotonic() - start)
                return outcome
            raise _not_validated(
                loc,
                "its validation process died (a crash of the robot library on this model); "
                "check the model, e.g. with `legopt robots validate`",
            )
        finally:
            self._slots.release()

    def _submit(
        self, fn: Callable[..., T], args: tuple[Any, ...]
    ) -> tuple[ProcessPoolExecutor, Future[tuple[T | None, Errors | None]]]:
        """Submit to the current pool (made first; replaced after ``TASKS_PER_POOL`` tasks or
        when broken)."""
        with self._pool_lock:
            if self._executor is not None and self._tasks >= TASKS_PER_POOL:
                self._executor.shutdown(wait=False)  # its processes exit once idle
                self._executor = None
            for _attempt in range(2):
                if self._executor is None:
                    self._executor = ProcessPoolExecutor(
                        self.processes, mp_context=_context(), initializer=_child_init
                    )
                    self._tasks = 0
                self._tasks += 1
                try:
                    return self._executor, self._executor.submit(_outcome, fn, *args)
                except BrokenProcessPool:  # a process died since the last result
                    self._executor.shutdown(wait=False, cancel_futures=True)
                    self._executor = None
            raise BrokenProcessPool("validation processes die as soon as they start")

    def close(self) -> None:
        """Stop the validation processes and wait for them (the next request makes new ones)."""
        with self._pool_lock:
            if self._executor is not None:
                self._executor.shutdown(wait=True, cancel_futures=True)
                self._executor = None

    def _discard(self, executor: ProcessPoolExecutor, *, kill: bool) -> None:
        """Stop using ``executor``, killing its processes first when ``kill``; the next
        request makes a new pool."""
        with self._pool_lock:
            if kill:
                for proc in list((executor._processes or {}).values()):
                    proc.kill()
            executor.shutdown(wait=False, cancel_futures=True)
            if self._executor is executor:
                self._executor = None


def _not_validated(loc: Loc, reason: str) -> RequestValidationError:
    return invalid(loc, f"the model could not be validated: {reason}", "model_not_validated")


_pools: dict[int, ValidationPool] = {}
_pools_lock = threading.Lock()


def shutdown() -> None:
    """Stop this process's validation processes, the forkserver and the resource tracker, and
    wait for them: the API's shutdown (``services.api.app``'s lifespan) and, for other users,
    ``atexit``, so an API that stops (SIGTERM, Ctrl-C) exits with no process left behind. After
    a kill -9 of the API they exit on their own (end of file on the pipes from the API; the
    children's watchdog)."""
    from multiprocessing import forkserver, resource_tracker

    with _pools_lock:
        pools = list(_pools.values())
        _pools.clear()
    for p in pools:
        p.close()
    servers: list[Any] = [forkserver._forkserver, resource_tracker._resource_tracker]
    for server in servers:  # their private _stop: close the pipe, wait for the process
        try:
            server._stop()
        except Exception:  # noqa: BLE001 - shutting down: nothing left to protect
            log.warning("could not stop %s", type(server).__name__, exc_info=True)


def pool(settings: Settings) -> ValidationPool:
    """This process's pool of ``settings.validation_processes`` processes, made on first use
    (one per process; tests may also use another size)."""
    with _pools_lock:
        found = _pools.get(settings.validation_processes)
        if found is None:
            if not _pools:
                atexit.register(shutdown)
            found = _pools[settings.validation_processes] = ValidationPool(
                settings.validation_processes
            )
        return found


def _robot_loc(doc: Any, prefix: Loc) -> Loc:
    """Where a dead or slow validation is reported: the robot of a spec that has one."""
    has_robot = isinstance(doc, dict) and doc.get("robot") is not None
    return (*prefix, "robot") if has_robot else prefix


# --------------------------------------------------------------------------- the routes' calls


def check_job(
    doc: Any, *, settings: Settings, key_id: str, references: dict[str, Any]
) -> CheckedJob:
    """``POST /jobs``: ``check_job_spec(doc)`` in a validation process; ``references``: the
    stored robots it names (``validation.stored_references``, read by the caller before, so no
    database transaction stays open while the process validates)."""
    loc = _robot_loc(doc, ("body",))
    return pool(settings).run(key_id, settings, loc, _check_job, doc, references, settings)


def check_sweep(
    points: Sequence[SweepPoint],
    *,
    relocate: Relocate,
    settings: Settings,
    key_id: str,
    references: dict[str, Any],
    prefix: Loc,
) -> list[CheckedJob]:
    """``POST /sweeps``: every point checked in ONE validation process call (one cache: each
    distinct robot built once); errors moved by ``relocate`` (a module-level function) to the
    override that caused them, each distinct one once; ``references`` as for ``check_job``."""
    table = references
    loc = _robot_loc(points[0].spec if points else None, prefix)
    return pool(settings).run(
        key_id, settings, loc, _check_sweep, list(points), table, settings, relocate, prefix
    )


def check_robot(
    catalog_name: str | None, spec: Any, *, settings: Settings, key_id: str
) -> RobotInfo:
    """``POST /robots`` and ``/robots/validate``: the model built and described in a
    validation process (``robot_validation.check_robot_doc``)."""
    loc: Loc = ("body", "catalog") if catalog_name is not None else ("body", "spec")
    return pool(settings).run(key_id, settings, loc, _check_robot, catalog_name, spec)


__all__ = [
    "TASKS_PER_POOL",
    "WAITING_PER_PROCESS",
    "ValidationPool",
    "check_job",
    "check_robot",
    "check_sweep",
    "pool",
]
