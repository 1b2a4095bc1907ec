"""Artifact store on a local directory: atomic writes, checksums, path traversal rejected
(the contract both backends share: ``test_artifacts_s3.py``)."""

from __future__ import annotations

import hashlib
import io
import os
from pathlib import Path

import pytest

from services.store import (
    ArtifactStore,
    ChecksumMismatchError,
    Settings,
    StoredFile,
    UnsafePathError,
)
from services.store.artifacts import LocalArtifactStore

JOB = "0b6f4c1e-2a4d-4a8e-9d55-6f0c1f6b9a10"


@pytest.fixture
def store(tmp_path: Path) -> LocalArtifactStore:
    return LocalArtifactStore(tmp_path / "artifacts")


def test_put_bytes_file_and_stream(store: LocalArtifactStore, tmp_path: Path) -> None:
    data = b"rerun recording" * 1000
    stored = store.put(JOB, "recording", data)
    assert stored == StoredFile(f"{JOB}/recording.rrd", hashlib.sha256(data).hexdigest(), 15000)
    rel, sha, size = stored  # a plain tuple too
    assert store.read(rel, sha) == data
    with store.open(rel, sha) as f:
        assert f.read() == data

    src = tmp_path / "export.csv"
    src.write_text("t,q1\n0,0.1\n")
    csv = store.put(JOB, "csv", src)
    assert csv.relative_path == f"{JOB}/csv.csv" and csv.size_bytes == src.stat().st_size
    stream = store.put(JOB, "pareto", io.BytesIO(b"abc"), suffix=".json")
    assert stream.relative_path == f"{JOB}/pareto.json"
    assert store.exists(stream.relative_path)
    assert sorted(p.name for p in (store.root / JOB).iterdir()) == [
        "csv.csv",
        "pareto.json",
        "recording.rrd",
    ]  # no temporary files left behind


def test_replacing_is_atomic_and_failures_leave_no_partial_file(store: LocalArtifactStore) -> None:
    first = store.put(JOB, "recording", b"old")
    target = store.path(first.relative_path)
    inode = target.stat().st_ino

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
        store.put(JOB, "recording", Broken())  # type: ignore[arg-type]
    assert target.read_bytes() == b"old"  # untouched
    assert [p.name for p in target.parent.iterdir()] == ["recording.rrd"]

    second = store.put(JOB, "recording", b"new")
    assert second.relative_path == first.relative_path
    assert target.read_bytes() == b"new" and target.stat().st_ino != inode  # replaced


def test_checksum_mismatch_is_detected(store: LocalArtifactStore) -> None:
    stored = store.put(JOB, "recording", b"good bytes")
    store.path(stored.relative_path).write_bytes(b"evil bytes")
    with pytest.raises(ChecksumMismatchError):
        store.read(stored.relative_path, stored.sha256)
    with pytest.raises(ChecksumMismatchError):
        store.open(stored.relative_path, stored.sha256)
    with pytest.raises(ChecksumMismatchError):
        store.verify(stored.relative_path, stored.sha256)
    assert store.read(stored.relative_path) == b"evil bytes"  # no checksum given: no check


@pytest.mark.parametrize(
    "rel",
    [
        "../outside.txt",
        f"{JOB}/../../outside.txt",
        "/etc/passwd",
        "",
        ".",
        f"{JOB}//recording.rrd",
        f"./{JOB}/recording.rrd",
        "a\\..\\b",
    ],
)
def test_traversal_is_rejected(store: LocalArtifactStore, rel: str) -> None:
    with pytest.raises(UnsafePathError):
        store.read(rel)


@pytest.mark.parametrize(
    ("job_id", "kind", "suffix"),
    [("..", "recording", None), (JOB, "../x", None), ("a/b", "csv", None), (JOB, "csv", "/x")],
)
def test_bad_names_are_rejected(
    store: LocalArtifactStore, job_id: str, kind: str, suffix: str | None
) -> None:
    with pytest.raises(UnsafePathError):
        store.put(job_id, kind, b"x", suffix=suffix)


def test_symlink_out_of_the_root_is_rejected(store: LocalArtifactStore, tmp_path: Path) -> None:
    outside = tmp_path / "secret.txt"
    outside.write_text("secret")
    (store.root / JOB).mkdir(parents=True)
    os.symlink(outside, store.root / JOB / "link.txt")
    with pytest.raises(UnsafePathError):
        store.read(f"{JOB}/link.txt")


def test_delete_job_and_settings(store: LocalArtifactStore, tmp_path: Path) -> None:
    store.put(JOB, "recording", b"x")
    store.delete_job(JOB)
    assert not (store.root / JOB).exists()
    store.delete_job(JOB)  # idempotent
    s = Settings.from_env(env={}, data_dir=tmp_path / "d")
    assert ArtifactStore.from_settings(s).root == tmp_path / "d" / "artifacts"
