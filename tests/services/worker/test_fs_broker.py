"""The embedded broker transport (issue 8, defect 5): atomic publish, exactly-once claim, a
consumer that never dies on a bad file, and Celery using it for ``filesystem://``.

The stress test runs real producer and consumer processes (spawned) over one queue folder, all
declaring the queue at once, the consumers polling without pause. kombu's stock filesystem
transport under the same stress (2 producers x 500 messages, 3 consumers) hands consumers empty
files (JSONDecodeError, which Celery calls an "Unrecoverable error": the worker exits, the
message is lost): measured 100 of 9000 messages lost in 9 runs (0-57 per run, 6 runs of 9 with
a loss) plus 1 run of 10 where a producer died declaring the queue (the exchange-table race);
ours: 0 of 10000 lost or duplicated in 10 runs. Not reliable enough per run for a mandatory
test, so that stress is opt-in (``LEGOPT_STRESS_STOCK=1``); the single-process
``test_stock_consumer_loses_a_message_being_written`` shows the same defect deterministically.
A Celery worker on the stock transport with one torn file in its queue logged "Unrecoverable
error" and ran 0 of 10 tasks; on this one, 10 of 10 (``test_celery_round_trip...``).

Module-level imports stay light (kombu, fs_broker): spawned children import this module.
"""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import threading
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from queue import Empty
from typing import Any

import pytest
from kombu import Connection
from kombu.transport import filesystem as stock_fs

from services.worker import fs_broker

OURS = fs_broker.TRANSPORT
STOCK = "kombu.transport.filesystem:Transport"
QUEUE = "stress"


def _options(root: Path) -> dict[str, str]:
    folders = {
        "data_folder_in": root / "queue",
        "data_folder_out": root / "queue",
        "processing_folder": root / "processing",
        "corrupt_folder": root / "corrupt",
        "control_folder": root / "control",
    }
    for d in folders.values():
        d.mkdir(parents=True, exist_ok=True)
    return {k: str(v) for k, v in folders.items()}


def _connection(transport: str, root: Path) -> Connection:
    return Connection("filesystem://", transport=transport, transport_options=_options(root))


def _messages(root: Path, sub: str = "queue") -> list[str]:
    return sorted(f for f in os.listdir(root / sub) if not f.startswith("."))


# ---------------------------------------------------------------------------------------------
# stress: producers and consumers in spawned processes
# ---------------------------------------------------------------------------------------------


def _produce(transport: str, root: str, producer: int, n: int, ready: Any, go: Any) -> None:
    with _connection(transport, Path(root)) as conn:
        ready.put(1)
        go.wait()  # all processes declare the queue at once: the exchange table race
        q = conn.SimpleQueue(QUEUE, serializer="json")
        for i in range(n):
            q.put({"id": f"{producer}-{i}"})
        q.close()


def _consume(transport: str, root: str, done: Any, ready: Any, go: Any, out: Any) -> None:
    """Poll without pause until the producers are done and the queue stays empty; report the
    ids received and every exception ``get`` raised (that message is gone)."""
    ids: list[str] = []
    errors: list[str] = []
    with _connection(transport, Path(root)) as conn:
        ready.put(1)
        go.wait()
        try:
            q = conn.SimpleQueue(QUEUE, serializer="json")
        except Exception as exc:  # the stock transport: JSONDecodeError on the exchange table
            out.put(([], [f"declare: {type(exc).__name__}: {exc}"]))
            raise
        empty_after_done = 0
        while empty_after_done < 50:
            try:
                msg = q.get_nowait()
            except q.Empty:
                if done.is_set():
                    empty_after_done += 1
                continue
            except Exception as exc:  # the stock transport: JSONDecodeError on a torn file
                errors.append(f"{type(exc).__name__}: {exc}")
                continue
            ids.append(msg.payload["id"])
            msg.ack()
        q.close()
    out.put((ids, errors))


def _stress(
    transport: str, root: Path, producers: int, per_producer: int, consumers: int
) -> tuple[Counter[str], list[str]]:
    """(times each message id was received, the consumers' errors) of one stress run."""
    ctx = mp.get_context("spawn")
    done, go, ready, out = ctx.Event(), ctx.Event(), ctx.Queue(), ctx.Queue()
    prods = [
        ctx.Process(target=_produce, args=(transport, str(root), p, per_producer, ready, go))
        for p in range(producers)
    ]
    cons = [
        ctx.Process(target=_consume, args=(transport, str(root), done, ready, go, out))
        for _ in range(consumers)
    ]
    for p in cons + prods:
        p.start()
    try:
        for _ in cons + prods:  # every process has imported kombu
            ready.get(timeout=120)
        go.set()
        for p in prods:
            p.join(180)
            assert p.exitcode == 0, f"a producer exited with {p.exitcode}"
        done.set()
        results = [out.get(timeout=180) for _ in cons]
        for p in cons:
            p.join(30)
    finally:
        for p in cons + prods:
            if p.is_alive():
                p.kill()
    seen: Counter[str] = Counter()
    errors: list[str] = []
    for ids, errs in results:
        seen.update(ids)
        errors.extend(errs)
    return seen, errors


def _check_exactly_once(seen: Counter[str], producers: int, per_producer: int) -> None:
    expected = {f"{p}-{i}" for p in range(producers) for i in range(per_producer)}
    missing = expected - set(seen)
    dup = {k: v for k, v in seen.items() if v > 1}
    assert not missing, (
        f"{len(missing)} of {len(expected)} messages lost, e.g. {sorted(missing)[:5]}"
    )
    assert not dup, f"{len(dup)} messages delivered more than once, e.g. {list(dup.items())[:5]}"
    assert set(seen) == expected


@pytest.mark.slow
def test_every_message_delivered_exactly_once_under_aggressive_polling(tmp_path: Path) -> None:
    seen, errors = _stress(OURS, tmp_path, producers=2, per_producer=300, consumers=3)
    assert errors == [], f"{len(errors)} consumer errors, e.g. {errors[:3]}"
    _check_exactly_once(seen, 2, 300)
    assert _messages(tmp_path) == [] and _messages(tmp_path, "processing") == []
    assert _messages(tmp_path, "corrupt") == []
    assert [f for f in os.listdir(tmp_path / "queue") if f.endswith(".tmp")] == []


@pytest.mark.skipif(
    os.environ.get("LEGOPT_STRESS_STOCK") != "1", reason="opt-in: LEGOPT_STRESS_STOCK=1"
)
def test_stock_transport_loses_messages(tmp_path: Path) -> None:
    """The defect this transport fixes, on kombu's own: some of 5 stress runs lose messages."""
    for run in range(5):
        try:
            seen, errors = _stress(STOCK, tmp_path / str(run), 2, 500, 3)
        except AssertionError:  # a producer died on the exchange table
            return
        if errors or len(seen) < 1000:
            return
    pytest.fail("kombu's filesystem transport lost nothing in 5 stress runs")


def test_stock_consumer_loses_a_message_being_written(tmp_path: Path) -> None:
    """kombu's own ``_get`` takes a message file its producer has created but not yet written:
    it raises and the message is gone (what this module's transport exists for)."""
    with _connection(STOCK, tmp_path) as stock:
        (tmp_path / "queue" / f"1_x.{QUEUE}.msg").write_bytes(b"")  # open("wb") done, no write
        with pytest.raises(ValueError):  # json.JSONDecodeError
            stock.default_channel._get(QUEUE)
        assert _messages(tmp_path) == []  # lost


# ---------------------------------------------------------------------------------------------
# one process
# ---------------------------------------------------------------------------------------------


def _payload(body: str = "x") -> dict[str, Any]:
    return {"body": body, "properties": {"delivery_tag": "t", "body_encoding": None}}


def test_put_writes_a_name_no_consumer_matches_then_renames_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    with _connection(OURS, tmp_path) as conn, _connection(STOCK, tmp_path) as stock:
        ch, stock_ch = conn.default_channel, stock.default_channel
        during: list[tuple[list[str], list[Exception]]] = []
        real_rename = os.rename

        def spy(src: str, dst: str) -> None:
            # the file is complete but not yet renamed: no consumer may see it
            missed: list[Exception] = []
            for c in (ch, stock_ch):
                try:
                    c._get(QUEUE)
                except Empty as exc:
                    missed.append(exc)
            during.append((sorted(os.listdir(tmp_path / "queue")), missed))
            real_rename(src, dst)

        monkeypatch.setattr(fs_broker.os, "rename", spy)
        ch._put(QUEUE, _payload())
        monkeypatch.undo()
        ((names, missed),) = during
        assert len(names) == 1 and names[0].startswith(".") and names[0].endswith(".tmp")
        assert len(missed) == 2, "a consumer took the temporary file"
        (final,) = _messages(tmp_path)
        assert final.endswith(f".{QUEUE}.msg")
        assert json.loads((tmp_path / "queue" / final).read_text()) == _payload()
        assert ch._get(QUEUE) == _payload()
        assert _messages(tmp_path) == [] and _messages(tmp_path, "processing") == []


def test_bad_files_go_to_corrupt_and_the_next_message_is_delivered(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(fs_broker, "TORN_GRACE_S", 0.05)
    q = tmp_path / "queue"
    with _connection(OURS, tmp_path) as conn:
        ch = conn.default_channel
        bad = {
            f"0_a.{QUEUE}.msg": b"",  # created, not yet written (the stock race)
            f"0_b.{QUEUE}.msg": b'{"body": "x", "prop',  # half written
            f"0_c.{QUEUE}.msg": b"[1, 2]",  # JSON, not a kombu message
            f"0_d.{QUEUE}.msg": b'{"body": "x"}',  # no properties
        }
        for name, data in bad.items():
            (q / name).write_bytes(data)
        ch._put(QUEUE, _payload("good"))
        assert ch._get(QUEUE)["body"] == "good"  # never raises on the bad ones
        assert _messages(tmp_path, "corrupt") == sorted(bad)
        assert _messages(tmp_path) == [] and _messages(tmp_path, "processing") == []
        (q / f"0_e.{QUEUE}.msg").write_bytes(b"{")
        with pytest.raises(Empty):
            ch._get(QUEUE)


def test_a_file_claimed_by_another_consumer_is_skipped(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    with _connection(OURS, tmp_path) as conn:
        ch = conn.default_channel
        ch._put(QUEUE, _payload("first"))
        time.sleep(0.002)
        ch._put(QUEUE, _payload("second"))
        real_rename = os.rename
        calls: list[str] = []

        def lose_first(src: str, dst: str) -> None:
            calls.append(src)
            if len(calls) == 1:  # another consumer renamed it away first
                os.remove(src)
                raise FileNotFoundError(src)
            real_rename(src, dst)

        monkeypatch.setattr(fs_broker.os, "rename", lose_first)
        assert ch._get(QUEUE)["body"] == "second"
        assert len(calls) == 2


def test_message_format_is_compatible_both_ways(tmp_path: Path) -> None:
    """An existing queue folder (stock files) is read by ours, and the reverse."""
    with _connection(OURS, tmp_path) as conn, _connection(STOCK, tmp_path) as stock:
        ours_q = conn.SimpleQueue(QUEUE, serializer="json")
        stock_q = stock.SimpleQueue(QUEUE, serializer="json")
        stock_q.put({"n": 1})
        assert ours_q.get(timeout=2).payload == {"n": 1}
        ours_q.put({"n": 2})
        assert stock_q.get(timeout=2).payload == {"n": 2}
        assert ours_q.qsize() == 0


def test_reads_a_stock_producers_file_only_once_it_is_written(tmp_path: Path) -> None:
    """A stock producer (an old process) creates the file, then locks and writes it; our
    consumer waits on the lock instead of reading it empty."""
    with _connection(OURS, tmp_path) as conn:
        ch = conn.default_channel
        path = tmp_path / "queue" / f"1_x.{QUEUE}.msg"
        f = open(path, "wb", buffering=0)  # noqa: SIM115 - held open across the get
        stock_fs.lock(f, stock_fs.LOCK_EX)

        def finish() -> None:
            time.sleep(0.2)
            f.write(json.dumps(_payload("late")).encode())
            stock_fs.unlock(f)
            f.close()

        t = threading.Thread(target=finish)
        t.start()
        try:
            assert ch._get(QUEUE)["body"] == "late"
        finally:
            t.join(5)
        assert _messages(tmp_path, "corrupt") == []


# ---------------------------------------------------------------------------------------------
# Celery
# ---------------------------------------------------------------------------------------------


@pytest.fixture
def fs_settings(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Any]:
    from services.store.settings import Settings, get_settings

    # importing services.worker.celery_app builds its app from the environment: keep it here
    monkeypatch.setenv("LEGOPT_DATA_DIR", str(tmp_path / "env"))
    get_settings.cache_clear()
    try:
        yield Settings.from_env(env={"LEGOPT_DATA_DIR": str(tmp_path / "data")})
    finally:
        get_settings.cache_clear()


def test_celery_app_uses_this_transport_for_filesystem_urls_only(fs_settings: Any) -> None:
    from services.worker.celery_app import broker_transport, make_celery

    app = make_celery(fs_settings)
    with app.connection_for_write() as conn:
        assert isinstance(conn.transport, fs_broker.Transport)
        assert isinstance(conn.default_channel, fs_broker.Channel)
        opts = conn.transport_options
        for k in ("data_folder_in", "processing_folder", "corrupt_folder", "control_folder"):
            assert Path(opts[k]).is_dir(), k
    redis = fs_settings.model_copy(update={"broker_url": "redis://127.0.0.1:1/0"})
    assert broker_transport(redis) is None
    assert make_celery(redis).connection_for_write().transport_cls == "redis"


@pytest.mark.slow
def test_celery_round_trip_survives_a_torn_message(fs_settings: Any) -> None:
    """A real Celery worker (in a thread) consumes over this transport; a torn file in the queue
    is set aside instead of killing the worker, and every task runs once."""
    from celery import Celery
    from celery.contrib.testing.worker import start_worker

    from services.worker.celery_app import broker_options, broker_transport

    app = Celery("fs-broker-test", broker=fs_settings.broker_url, set_as_current=False)
    app.conf.update(
        broker_transport=broker_transport(fs_settings),
        broker_transport_options=broker_options(fs_settings),
        task_default_queue="t",
        task_serializer="json",
        accept_content=["json"],
        task_ignore_result=True,
        worker_hijack_root_logger=False,
    )
    got: list[int] = []
    all_done = threading.Event()

    @app.task(name="fsb.record")
    def record(i: int) -> None:
        got.append(i)
        if len(got) >= 10:
            all_done.set()

    queue_dir = Path(broker_options(fs_settings)["data_folder_in"])  # type: ignore[arg-type]
    (queue_dir / "0_torn.t.msg").write_bytes(b'{"body": "')
    for i in range(10):
        record.delay(i)
    with start_worker(app, pool="solo", perform_ping_check=False, shutdown_timeout=10):
        assert all_done.wait(60), f"only tasks {sorted(got)} ran within 60 s"
    assert sorted(got) == list(range(10))
    corrupt = Path(broker_options(fs_settings)["corrupt_folder"])  # type: ignore[arg-type]
    assert [p.name for p in corrupt.iterdir()] == ["0_torn.t.msg"]
