"""The embedded broker: kombu's filesystem transport with atomic publish and claim.

kombu's stock ``filesystem`` transport (``kombu.transport.filesystem``) creates the final
``<ms>_<uuid>.<queue>.msg`` file and then writes it, while a consumer lists the folder, moves
whatever matching file it finds and parses it: a consumer can take a file that is still empty
or half written, ``json.loads`` raises, Celery calls that an "Unrecoverable error", the worker
exits and the message is gone (about 4 % of messages with aggressive polling). It also moves a
claimed file to ``tempfile.gettempdir()``, usually another filesystem, where ``shutil.move`` is
a copy + delete that two consumers can both perform.

This transport keeps the stock folder layout and message format (plain kombu JSON payloads in
``<ms>_<uuid>.<queue>.msg`` files; an existing queue folder keeps working) and changes how a
file is published and claimed:

- **publish**: the payload goes to ``.<name>.tmp`` in the queue folder (a dot-file with another
  suffix, which no consumer, ours or kombu's, ever matches), is fsynced, then ``os.rename``-d to
  ``<name>``: consumers see a complete message or none (rename is atomic on POSIX).
- **claim**: a consumer ``os.rename``-s a message into its ``processing_folder`` (same
  filesystem, checked): only one consumer can win; the others get ``FileNotFoundError`` and try
  the next file. The winner reads the file (under a shared ``flock``: a stock kombu producer
  writes under an exclusive one) and removes it.
- **never dies on a file**: a message that does not parse into a kombu message (torn, empty,
  foreign) is logged and moved to ``corrupt_folder``; the consumer goes on with the next one.
- **exchange tables** (``control_folder/<exchange>.exchange``, the queue bindings): kombu
  creates the file, then writes it, so a second process binding or publishing at that moment
  reads it empty (two workers starting on a fresh folder); here it is created complete.

Transport options (besides kombu's ``data_folder_in``/``data_folder_out``/``control_folder``):
``processing_folder`` (default ``<data_folder_in>/.processing``) and ``corrupt_folder``
(default ``<data_folder_in>/.corrupt``); kombu's ``store_processed``/``processed_folder`` are
not used. A consumer killed between its claim and the removal (microseconds) leaves the file in
``processing_folder``; like any message of a killed worker on this broker it is not redelivered
(the dispatcher re-sends jobs whose message was lost).

Use it as Celery's ``broker_transport = "services.worker.fs_broker:Transport"`` with a
``filesystem://`` URL (``services.worker.celery_app`` does).
"""

from __future__ import annotations

import logging
import os
import time
import uuid
from pathlib import Path
from queue import Empty
from typing import Any

from kombu.exceptions import ChannelError
from kombu.transport import filesystem, virtual
from kombu.utils.encoding import bytes_to_str, str_to_bytes
from kombu.utils.json import dumps, loads

log = logging.getLogger(__name__)

__all__ = ["TRANSPORT", "Channel", "Transport", "message_name", "temp_name"]

#: Import path of :class:`Transport` (Celery's ``broker_transport`` setting).
TRANSPORT = "services.worker.fs_broker:Transport"

#: How long (s) a claimed file that does not parse is re-read before it counts as corrupt:
#: covers a stock kombu producer that created the file but has not locked/written it yet.
TORN_GRACE_S = 0.5
_RETRY_S = 0.02


def message_name(queue: str) -> str:
    """Final file name of a new message on ``queue`` (kombu's: ``<ms>_<uuid>.<queue>.msg``,
    ``ms`` the monotonic clock in ms, so names sort in publish order on one machine)."""
    return f"{round(time.monotonic() * 1000)}_{uuid.uuid4()}.{queue}.msg"


def temp_name(name: str) -> str:
    """Name a message is written under before it is renamed to ``name``: a dot-file ending in
    ``.tmp``, which matches no queue (kombu matches ``name.partition('.')[2] == '<q>.msg'``)."""
    return f".{name}.tmp"


def _create_table(file: Path) -> None:
    """Create the exchange table ``file`` holding an empty table (``[]``) unless it exists,
    atomically: a complete temp file is hard-linked to the name (``os.link`` fails if it
    exists), so no process ever opens it empty."""
    if file.exists():
        return
    tmp = file.with_name(f".{file.name}.{uuid.uuid4().hex}.tmp")
    tmp.write_bytes(b"[]")
    try:
        os.link(tmp, file)
    except FileExistsError:
        pass
    finally:
        tmp.unlink(missing_ok=True)


def _matches(filename: str, queue: str) -> bool:
    return not filename.startswith(".") and filename.partition(".")[2] == f"{queue}.msg"


class Channel(filesystem.Channel):
    """kombu's filesystem channel with an atomic ``_put`` and an exactly-once ``_get``."""

    # kombu's filesystem Channel already renames AbstractChannel._put's ``message``: keep its names
    def _put(self, queue: str, payload: dict[str, Any], **kwargs: Any) -> None:  # type: ignore[override]
        """Publish ``payload`` (a kombu message) on ``queue``: write a temp file, fsync, rename
        it into place."""
        folder = self.data_folder_out
        name = message_name(queue)
        tmp = os.path.join(folder, temp_name(name))
        data = str_to_bytes(dumps(payload))
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
            try:
                view = memoryview(data)
                while view:
                    view = view[os.write(fd, view) :]
                os.fsync(fd)
            finally:
                os.close(fd)
            os.rename(tmp, os.path.join(folder, name))
        except OSError as exc:
            try:
                os.unlink(tmp)
            except OSError:
                pass
            raise ChannelError(f"Cannot add message {name!r} to {folder!r}: {exc}") from exc

    def _get(self, queue: str, timeout: float | None = None) -> dict[str, Any]:
        """The oldest complete message of ``queue`` (claimed by this consumer alone), or
        ``queue.Empty``. Never raises on a bad file: it goes to ``corrupt_folder``."""
        folder = self.data_folder_in
        processing = self._processing_folder()
        try:
            names = sorted(os.listdir(folder))
        except OSError as exc:
            raise ChannelError(f"Cannot list queue folder {folder!r}: {exc}") from exc
        for filename in names:
            if not _matches(filename, queue):
                continue
            claimed = os.path.join(processing, filename)
            try:
                os.rename(os.path.join(folder, filename), claimed)
            except FileNotFoundError:
                continue  # another consumer claimed it first
            except OSError as exc:
                log.error("broker: cannot claim %s: %s", filename, exc)
                continue
            payload = self._read_claimed(claimed)
            if payload is not None:
                return payload
        raise Empty()

    def _read_claimed(self, claimed: str) -> dict[str, Any] | None:
        """Parse and remove a claimed file; None (file moved to ``corrupt_folder``) if it is
        not a kombu message after :data:`TORN_GRACE_S` s of retries."""
        deadline = time.monotonic() + TORN_GRACE_S
        while True:
            try:
                with open(claimed, "rb") as f:
                    filesystem.lock(f, filesystem.LOCK_SH)  # waits for a stock writer
                    try:
                        raw = f.read()
                    finally:
                        filesystem.unlock(f)
                payload = loads(bytes_to_str(raw))
                if not isinstance(payload, dict):
                    raise TypeError(f"payload is a {type(payload).__name__}, not an object")
                self.Message(payload, channel=self)  # what kombu builds from it: must not raise
            except Exception as exc:  # whatever is wrong with the file
                if time.monotonic() < deadline:
                    time.sleep(_RETRY_S)
                    continue
                self._quarantine(claimed, exc)
                return None
            try:
                os.remove(claimed)
            except OSError as exc:
                log.warning("broker: cannot remove claimed message %s: %s", claimed, exc)
            return payload

    def _quarantine(self, claimed: str, exc: BaseException) -> None:
        corrupt = self._folder("corrupt_folder", ".corrupt")
        target = os.path.join(corrupt, os.path.basename(claimed))
        log.error(
            "broker: unreadable message %s (%s: %s) moved to %s",
            os.path.basename(claimed),
            type(exc).__name__,
            exc,
            corrupt,
        )
        try:
            os.rename(claimed, target)
        except OSError as err:
            log.error("broker: cannot move %s to %s (%s); removing it", claimed, corrupt, err)
            try:
                os.remove(claimed)
            except OSError:
                pass

    def _queue_bind(
        self, exchange: str, routing_key: str | None, pattern: str | None, queue: str | None
    ) -> None:
        """Add a binding to the exchange's table file. kombu creates that file with
        ``open("wb")`` and writes it afterwards, so a process binding (or publishing) at the
        same time reads it empty (JSONDecodeError when two workers start on a fresh folder):
        here it is created complete (:func:`_create_table`), then updated under its lock."""
        file = self._exchange_file(exchange)
        entry = filesystem.exchange_queue_t(routing_key or "", pattern or "", queue or "")
        try:
            self.control_folder.mkdir(parents=True, exist_ok=True)
            _create_table(file)
            with open(file, "rb+", buffering=0) as f:
                filesystem.lock(f, filesystem.LOCK_EX)
                try:
                    raw = bytes_to_str(f.read())
                    rows = loads(raw) if raw.strip() else []  # empty: a stock process creating it
                    table = [filesystem.exchange_queue_t(*row) for row in rows]
                    if entry not in table:
                        table.insert(0, entry)
                        f.seek(0)
                        f.write(str_to_bytes(dumps(table)))
                        f.truncate()
                finally:
                    filesystem.unlock(f)
        except OSError as exc:
            raise ChannelError(f"Cannot update exchange table {file}: {exc}") from exc

    def _folder(self, option: str, default: str) -> str:
        """The folder ``transport_options[option]`` (default ``<data_folder_in>/<default>``),
        created, and checked to be on the queue folder's filesystem (rename must be atomic)."""
        cache: dict[str, str] = self.__dict__.setdefault("_fs_folders", {})
        if option in cache:
            return cache[option]
        path = str(self.transport_options.get(option) or Path(self.data_folder_in) / default)
        try:
            os.makedirs(path, exist_ok=True)
            same_fs = os.stat(path).st_dev == os.stat(self.data_folder_in).st_dev
        except OSError as exc:
            raise ChannelError(f"broker folder {option}={path!r}: {exc}") from exc
        if not same_fs:
            raise ChannelError(
                f"broker folder {option}={path!r} is not on the filesystem of data_folder_in="
                f"{self.data_folder_in!r}: claims would not be atomic"
            )
        cache[option] = path
        return path

    def _processing_folder(self) -> str:
        return self._folder("processing_folder", ".processing")


class Transport(filesystem.Transport):
    """kombu's filesystem transport with :class:`Channel` (same URLs, options and files)."""

    Channel = Channel
    global_state = virtual.BrokerState()
