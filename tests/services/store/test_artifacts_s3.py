"""The artifact store's contract on both backends — a local directory and S3 (a real moto
server over HTTP on 127.0.0.1) — atomic writes, checksums, byte ranges, attempts that never
replace a finished job's files, deletes, unsafe paths; then what only S3 has: keys under the
URL's prefix with the store's SHA-256, an unreachable store, the settings that choose it."""

from __future__ import annotations

import base64
import hashlib
import io
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from pydantic import ValidationError

from services.store.artifacts import ArtifactStore, LocalArtifactStore, artifact_store, s3_endpoint
from services.store.errors import (
    ArtifactMissingError,
    ArtifactUnavailableError,
    ChecksumMismatchError,
    UnsafePathError,
)
from services.store.settings import Settings
from tests.s3_server import aws_env, free_port, moto_server, s3_client

JOB = "0b6f4c1e-2a4d-4a8e-9d55-6f0c1f6b9a10"
PREFIX = "legopt/test"


@pytest.fixture(scope="module")
def endpoint() -> Iterator[str]:
    with moto_server() as url:
        yield url


def _s3_store(endpoint: str) -> Any:
    from services.store.artifacts.s3 import S3ArtifactStore

    client = s3_client(endpoint)
    bucket = f"legopt-{uuid.uuid4().hex[:12]}"
    client.create_bucket(Bucket=bucket)
    return S3ArtifactStore(bucket, PREFIX, client=client)


@pytest.fixture(params=["local", "s3"])
def store(request: pytest.FixtureRequest, tmp_path: Path) -> ArtifactStore:
    if request.param == "local":
        return LocalArtifactStore(tmp_path / "artifacts")
    return _s3_store(request.getfixturevalue("endpoint"))


@pytest.fixture
def s3(endpoint: str) -> Any:
    return _s3_store(endpoint)


def overwrite(store: Any, rel: str, data: bytes) -> None:
    """Replace the stored bytes behind the store's back (corruption, another writer)."""
    if isinstance(store, LocalArtifactStore):
        store.path(rel).write_bytes(data)
    else:
        store.client.put_object(Bucket=store.bucket, Key=store.key(rel), Body=data)


def remove(store: Any, rel: str) -> None:
    """Remove a stored file behind the store's back."""
    if isinstance(store, LocalArtifactStore):
        store.path(rel).unlink()
    else:
        store.client.delete_object(Bucket=store.bucket, Key=store.key(rel))


def names(store: Any) -> list[str]:
    """Every stored relative path (no temporary files)."""
    if isinstance(store, LocalArtifactStore):
        if not store.root.exists():
            return []
        return sorted(
            p.relative_to(store.root).as_posix() for p in store.root.rglob("*") if p.is_file()
        )
    pages = store.client.get_paginator("list_objects_v2").paginate(
        Bucket=store.bucket, Prefix=PREFIX + "/"
    )
    return sorted(o["Key"][len(PREFIX) + 1 :] for page in pages for o in page.get("Contents", []))


# ---------------------------------------------------------------------------------- contract


def test_put_bytes_file_and_stream(store: ArtifactStore, tmp_path: Path) -> None:
    data = b"rerun recording" * 1000
    stored = store.put(JOB, "recording", data, attempt="a1-x")
    assert stored == (f"{JOB}/a1-x/recording.rrd", hashlib.sha256(data).hexdigest(), 15000)
    assert store.read(stored.relative_path, stored.sha256) == data
    assert store.verify(stored.relative_path, stored.sha256) == 15000
    assert store.size(stored.relative_path) == 15000
    with store.open(stored.relative_path, stored.sha256) as f:
        assert f.read() == data
    src = tmp_path / "export.csv"
    src.write_text("t,q1\n0,0.1\n")
    csv = store.put(JOB, "csv", src)
    assert csv.relative_path == f"{JOB}/csv.csv" and csv.size_bytes == src.stat().st_size
    stream = store.put(JOB, "pareto", io.BytesIO(b"abc"), suffix=".json")
    assert stream.relative_path == f"{JOB}/pareto.json" and store.exists(stream.relative_path)
    assert not store.exists(f"{JOB}/nothing.json")
    assert names(store) == [f"{JOB}/a1-x/recording.rrd", f"{JOB}/csv.csv", f"{JOB}/pareto.json"]


def test_byte_ranges_and_local_copies(store: ArtifactStore) -> None:
    data = bytes(range(256)) * 10_000  # 2.5 MB: several chunks
    rel, sha, size = store.put(JOB, "recording", data, attempt="a1")
    assert b"".join(store.open_range(rel, 0, 100)) == data[:100]
    assert b"".join(store.open_range(rel, 1_000_000, 2_100_000)) == data[1_000_000:2_100_000]
    assert b"".join(store.open_range(rel, size - 7, size)) == data[-7:]
    assert b"".join(store.open_range(rel, 0, size)) == data
    with store.local_copy(rel, sha) as path:
        assert path.read_bytes() == data
    empty = store.put(JOB, "empty", b"", attempt="a1")
    assert empty.size_bytes == 0 and store.read(empty.relative_path, empty.sha256) == b""
    assert b"".join(store.open_range(empty.relative_path, 0, 0)) == b""


def test_checksum_mismatch_is_detected(store: ArtifactStore) -> None:
    stored = store.put(JOB, "recording", b"good bytes", attempt="a1")
    overwrite(store, stored.relative_path, b"evil bytes")
    for check in (store.read, store.open, store.verify):
        with pytest.raises(ChecksumMismatchError):
            check(stored.relative_path, stored.sha256)
    with (
        pytest.raises(ChecksumMismatchError),
        store.local_copy(stored.relative_path, stored.sha256),
    ):
        pass
    assert store.read(stored.relative_path) == b"evil bytes"  # no checksum given: no check


def test_a_missing_artifact_is_named(store: ArtifactStore) -> None:
    stored = store.put(JOB, "recording", b"bytes", attempt="a1")
    remove(store, stored.relative_path)
    rel, sha = stored.relative_path, stored.sha256
    assert not store.exists(rel)
    calls = [
        lambda: store.read(rel, sha),
        lambda: store.verify(rel, sha),
        lambda: store.open(rel, sha),
        lambda: store.size(rel),
        lambda: store.open_range(rel, 0, 3),
    ]
    for call in calls:
        with pytest.raises(ArtifactMissingError, match="recording.rrd"):
            call()
    with pytest.raises(ArtifactMissingError), store.local_copy(rel, sha):
        pass
    with pytest.raises(FileNotFoundError):  # still what callers of the old store caught
        store.read(rel)


@pytest.mark.parametrize(
    "rel",
    ["../outside.txt", f"{JOB}/../../outside.txt", "/etc/passwd", "", ".",
     f"{JOB}//recording.rrd", f"./{JOB}/recording.rrd", "a\\..\\b", "a\x00b"],
)  # fmt: skip
def test_unsafe_paths_are_rejected(store: ArtifactStore, rel: str) -> None:
    with pytest.raises(UnsafePathError):
        store.read(rel)
    with pytest.raises(UnsafePathError):
        store.exists(rel)


@pytest.mark.parametrize(
    ("job_id", "kind", "suffix", "attempt"),
    [("..", "recording", None, None), (JOB, "../x", None, None), ("a/b", "csv", None, None),
     (JOB, "csv", "/x", None), (JOB, "csv", None, "../a2"), (JOB, "csv", None, "a/b")],
)  # fmt: skip
def test_bad_names_are_rejected(
    store: ArtifactStore, job_id: str, kind: str, suffix: str | None, attempt: str | None
) -> None:
    with pytest.raises(UnsafePathError):
        store.put(job_id, kind, b"x", suffix=suffix, attempt=attempt)
    with pytest.raises(UnsafePathError):
        store.delete_attempt(job_id, attempt or "..")


def test_a_stale_attempt_never_replaces_the_finished_object(store: ArtifactStore) -> None:
    """The lease holder's attempt finished (its path and hash are the job's); a worker that
    lost the lease writes the same kind: under its own attempt, and cleans only that up."""
    winner = store.put(JOB, "result", b'{"winner": true}', suffix=".json", attempt="a1-w")
    stale = store.put(JOB, "result", b'{"winner": false}', suffix=".json", attempt="a2-s")
    assert stale.relative_path != winner.relative_path
    store.delete_attempt(JOB, "a2-s")
    assert store.read(winner.relative_path, winner.sha256) == b'{"winner": true}'
    assert names(store) == [winner.relative_path]


def test_a_failed_write_leaves_the_old_bytes(store: ArtifactStore) -> None:
    first = store.put(JOB, "recording", b"old", attempt="a1")

    class Broken(io.RawIOBase):
        def __init__(self) -> None:
            self.calls = 0

        def readable(self) -> bool:
            return True

        def read(self, n: int = -1) -> bytes:
            self.calls += 1
            if self.calls > 1:
                raise OSError("disk unplugged")
            return b"new partial bytes"

    with pytest.raises(OSError, match="disk unplugged"):
        store.put(JOB, "recording", Broken(), attempt="a1")  # type: ignore[arg-type]
    assert store.read(first.relative_path, first.sha256) == b"old"
    assert names(store) == [first.relative_path]  # no partial file or object


def test_deletes(store: ArtifactStore) -> None:
    keep = store.put(JOB, "result", b"{}", suffix=".json", attempt="a3")
    store.put(JOB, "recording", b"dead worker", attempt="a1")
    store.put(JOB, "result", b"{}", suffix=".json", attempt="a2")
    loose = store.put(JOB, "csv", b"t\n")  # no attempt: beside the attempts
    other = store.put("other-job", "recording", b"x", attempt="a1")
    store.prune_attempts(JOB, keep="a3")
    assert names(store) == sorted([keep.relative_path, loose.relative_path, other.relative_path])
    store.delete_attempt(JOB, "a3")
    store.delete_attempt(JOB, "a3")  # idempotent
    assert names(store) == sorted([loose.relative_path, other.relative_path])
    store.delete_job(JOB)
    store.delete_job(JOB)  # idempotent
    assert names(store) == [other.relative_path]


# ---------------------------------------------------------------------------------- S3 only


def test_objects_carry_their_sha256_and_verify_reads_no_bytes(s3: Any) -> None:
    data = b"x" * 5000
    rel, sha, _ = s3.put(JOB, "recording", data, attempt="a1")
    head = s3.client.head_object(Bucket=s3.bucket, Key=f"{PREFIX}/{rel}", ChecksumMode="ENABLED")
    assert head["ChecksumSHA256"] == base64.b64encode(bytes.fromhex(sha)).decode()
    gets: list[str] = []
    s3.client.meta.events.register("before-call.s3.GetObject", lambda **kw: gets.append("get"))
    assert s3.verify(rel, sha) == 5000 and gets == []  # one HEAD: the store's own checksum
    with pytest.raises(ChecksumMismatchError):
        s3.verify(rel, hashlib.sha256(b"other").hexdigest())
    s3.client.put_object(Bucket=s3.bucket, Key=f"{PREFIX}/{rel}", Body=data)  # no checksum kept
    assert s3.verify(rel, sha) == 5000 and gets == ["get"]  # then the bytes are hashed


def test_an_unreachable_store_is_unavailable_not_an_error(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    aws_env(monkeypatch)
    from services.store.artifacts.s3 import S3ArtifactStore, make_client

    dead = S3ArtifactStore(
        "legopt-gone", "p", client=make_client(f"http://127.0.0.1:{free_port()}")
    )
    rel = f"{JOB}/a1/recording.rrd"
    calls = [
        lambda: dead.read(rel, "0" * 64),
        lambda: dead.verify(rel, "0" * 64),
        lambda: dead.exists(rel),
        lambda: dead.open_range(rel, 0, 10),
        lambda: dead.put(JOB, "recording", b"x", attempt="a1"),
    ]
    for call in calls:
        with pytest.raises(ArtifactUnavailableError, match="cannot be reached"):
            call()
    dead.delete_job(JOB)  # logged, never raised (like rmtree(ignore_errors=True))
    dead.prune_attempts(JOB, keep="a1")


def test_a_missing_bucket_is_unavailable(endpoint: str) -> None:
    from services.store.artifacts.s3 import S3ArtifactStore

    store = S3ArtifactStore("legopt-no-such-bucket", client=s3_client(endpoint))
    with pytest.raises(ArtifactUnavailableError, match="NoSuchBucket"):
        store.put(JOB, "recording", b"x")


def test_settings_choose_the_backend(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    aws_env(monkeypatch)
    from services.store.artifacts.s3 import S3ArtifactStore

    local = Settings.from_env(env={}, data_dir=tmp_path)
    assert isinstance(artifact_store(local), LocalArtifactStore)
    assert ArtifactStore.from_settings(local).root == tmp_path / "artifacts"  # type: ignore[attr-defined]
    env = {
        "LEGOPT_ARTIFACTS_URL": "s3://legopt-bucket/team/a/",
        "LEGOPT_S3_ENDPOINT_URL": "http://127.0.0.1:9",
        "LEGOPT_ARTIFACTS_PRESIGN": "1",
    }
    s = Settings.from_env(env=env, data_dir=tmp_path)
    assert s.artifacts_s3 == ("legopt-bucket", "team/a") and s.artifacts_presign
    store = ArtifactStore.from_settings(s)
    assert isinstance(store, S3ArtifactStore)
    assert (store.bucket, store.prefix, store.location) == (
        "legopt-bucket", "team/a", "s3://legopt-bucket/team/a"
    )  # fmt: skip
    assert store.client.meta.endpoint_url == "http://127.0.0.1:9"
    assert artifact_store(s).client is store.client  # one client per process and endpoint
    monkeypatch.setenv("AWS_ENDPOINT_URL", "http://minio:9000")
    assert s3_endpoint(s.with_overrides(s3_endpoint_url="")) == "http://minio:9000"
    for bad in ("http://bucket/x", "s3://", "s3://UPPER/x", "s3://ok-bucket/../x", "/tmp/x"):
        with pytest.raises(ValidationError, match="artifacts_url"):
            Settings.from_env(env={"LEGOPT_ARTIFACTS_URL": bad}, data_dir=tmp_path)
