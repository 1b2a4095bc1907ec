"""Cached numba kernels are dropped when legcore's source changes (numba itself only checks the
file that defines a kernel, not the kernels it calls from other files)."""

from __future__ import annotations

from pathlib import Path

import pytest

from legcore.kernel_cache import STAMP_NAME, check_kernel_cache, source_hash


def _package(tmp: Path) -> Path:
    pkg = tmp / "pkg"
    (pkg / "sub" / "__pycache__").mkdir(parents=True)
    (pkg / "a.py").write_text("x = 1\n")
    (pkg / "sub" / "b.py").write_text("y = 2\n")
    return pkg


def test_in_tree_cache_is_dropped_when_any_source_file_changes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    pkg = _package(tmp_path)
    kernel = pkg / "sub" / "__pycache__" / "b.f-1.py311.nbi"
    kernel.write_bytes(b"index")
    assert check_kernel_cache(pkg)  # nothing stamped yet: drop and stamp
    assert not kernel.exists()
    assert (pkg / "__pycache__" / STAMP_NAME).read_text().strip() == source_hash(pkg)
    kernel.write_bytes(b"index")  # compiled again
    assert not check_kernel_cache(pkg) and kernel.exists()  # same source: kept
    (pkg / "a.py").write_text("x = 3\n")  # a callee elsewhere changed
    assert check_kernel_cache(pkg) and not kernel.exists()


def test_numba_cache_dir_is_checked_when_set(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pkg = _package(tmp_path)
    cache = tmp_path / "cache" / "numba"
    (cache / "sub_abc").mkdir(parents=True)
    kernel = cache / "sub_abc" / "b.f-1.py311.1.nbc"
    kernel.write_bytes(b"code")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache))
    assert check_kernel_cache(pkg) and not kernel.exists()
    assert (cache / STAMP_NAME).is_file()
    kernel.write_bytes(b"code")
    assert not check_kernel_cache(pkg) and kernel.exists()
