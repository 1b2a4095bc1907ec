"""Resource names from robot files resolve only inside allow-listed roots (DESIGN §5).

Every refused form is checked to be refused *without touching* anything outside the roots:
``os.lstat`` / ``os.stat`` / ``os.open`` / ``os.readlink`` are spied on and no call may name a
path outside the root (the root itself and its own ancestors aside).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest

from legcore.resource_paths import (
    NO_FILE_ACCESS,
    ResourceRefused,
    confine_resource,
    read_resource,
)

SECRET = b"SECRET-5f1c0e-do-not-leak\n"


@pytest.fixture
def tree(tmp_path: Path) -> dict[str, Path]:
    """``root/`` with a mesh, a sub-folder and symlinks; ``outside/secret.txt`` next to it."""
    root = tmp_path / "root"
    (root / "meshes").mkdir(parents=True)
    (root / "meshes" / "leg.stl").write_bytes(b"solid leg\nendsolid leg\n")
    outside = tmp_path / "outside"
    outside.mkdir()
    secret = outside / "secret.txt"
    secret.write_bytes(SECRET)
    (root / "meshes" / "evil.stl").symlink_to(secret)  # symlink inside the root, out of it
    (root / "meshes" / "evil_rel.stl").symlink_to(Path("..") / ".." / "outside" / "secret.txt")
    (root / "escape").symlink_to(outside)  # a directory link out of the root
    (root / "meshes" / "alias.stl").symlink_to("leg.stl")  # stays inside: fine
    (root / "meshes" / "loop.stl").symlink_to("loop.stl")
    return {"root": root, "secret": secret, "outside": outside, "tmp": tmp_path}


@pytest.fixture
def touched(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[str]]:
    """Every path given to os.lstat / os.stat / os.open / os.readlink while the test runs."""
    seen: list[str] = []
    for name in ("lstat", "stat", "open", "readlink"):
        real = getattr(os, name)

        def spy(path: object, *a: object, _real: object = real, **k: object) -> object:
            seen.append(os.fsdecode(path) if isinstance(path, str | bytes | os.PathLike) else "")
            return _real(path, *a, **k)  # type: ignore[operator]

        monkeypatch.setattr(os, name, spy)
    yield seen


def _outside(seen: list[str], root: Path) -> list[str]:
    """Paths touched that are neither inside ``root`` nor ``root`` or one of its ancestors."""
    real = Path(os.path.realpath(root))
    bad = []
    for s in seen:
        p = Path(s)
        if p == real or real in p.parents or p in real.parents:
            continue
        bad.append(s)
    return bad


def test_a_mesh_inside_a_root_is_read(tree: dict[str, Path], touched: list[str]) -> None:
    root = tree["root"]
    for name in ("package://my_robot/meshes/leg.stl", "meshes/leg.stl", "./meshes/leg.stl",
                 "package://x/meshes/alias.stl"):  # fmt: skip
        path, data = read_resource(name, [root], max_bytes=1000)
        assert path == (root / "meshes" / "leg.stl").resolve(), name
        assert data.startswith(b"solid leg"), name
    assert confine_resource("meshes/leg.stl", [str(root)]) == (root / "meshes/leg.stl").resolve()
    assert touched and not _outside(touched, root)  # the spy sees the walk, all inside the root


def test_second_root_is_searched(tree: dict[str, Path]) -> None:
    other = tree["tmp"] / "other"
    other.mkdir()
    (other / "arm.obj").write_text("v 0 0 0\n")
    assert confine_resource("package://p/arm.obj", [tree["root"], other]) == other.resolve() / (
        "arm.obj"
    )


@pytest.mark.parametrize(
    ("name", "reason"),
    [
        ("{secret}", "absolute paths"),
        ("file://{secret}", "file: names are never opened"),
        ("FILE://{secret}", "FILE: names are never opened"),
        ("http://169.254.169.254/latest/meta-data", "http: names are never opened"),
        ("package://../../../../{secret}", "'..' segments"),
        ("package://pkg/../../outside/secret.txt", "'..' segments"),
        ("package:///{secret}", "the package name is missing"),
        ("package://pkg/{secret}", "absolute paths"),
        ("../outside/secret.txt", "'..' segments"),
        ("meshes/../../outside/secret.txt", "'..' segments"),
        ("meshes\\..\\..\\outside\\secret.txt", "backslash"),
        ("meshes/leg.stl\x00.png", "NUL byte"),
        ("", "gives no file"),
        ("package://pkg/", "gives no file"),
        ("meshes/evil.stl", "outside the mesh roots"),  # symlink inside the root -> outside
        ("package://p/meshes/evil_rel.stl", "outside the mesh roots"),  # relative link out
        ("escape/secret.txt", "outside the mesh roots"),  # directory link out
        ("meshes/loop.stl", "too many levels of symbolic links"),
        ("meshes", "not a regular file"),
        ("meshes/none.stl", "no such file under the mesh roots"),
    ],
)
def test_refused_without_touching_outside_the_root(
    tree: dict[str, Path], touched: list[str], name: str, reason: str
) -> None:
    name = name.format(secret=tree["secret"])
    with pytest.raises(ResourceRefused) as exc:
        read_resource(name, [tree["root"]], max_bytes=1 << 20)
    assert reason in exc.value.reason, exc.value.reason
    assert exc.value.name == name
    assert not _outside(touched, tree["root"]), touched


@pytest.mark.parametrize(
    "name", ["{secret}", "file://{secret}", "meshes/leg.stl", "package://p/meshes/leg.stl"]
)
def test_no_roots_means_no_file_access(
    tree: dict[str, Path], touched: list[str], name: str
) -> None:
    """Uploaded robots: nothing is resolved and no path at all is stat-ed or opened."""
    with pytest.raises(ResourceRefused) as exc:
        read_resource(name.format(secret=tree["secret"]), [], max_bytes=1 << 20)
    assert exc.value.reason == NO_FILE_ACCESS
    assert touched == []


def test_a_root_given_through_a_symlink_still_confines(tree: dict[str, Path]) -> None:
    """The root's own real path is what confines: a link to the root is fine, escapes are not."""
    link = tree["tmp"] / "root_link"
    link.symlink_to(tree["root"])
    assert confine_resource("meshes/leg.stl", [link]) == (tree["root"] / "meshes/leg.stl").resolve()
    with pytest.raises(ResourceRefused, match="outside the mesh roots"):
        confine_resource("meshes/evil.stl", [link])


def test_absolute_symlink_into_another_root_is_followed(tree: dict[str, Path]) -> None:
    other = tree["tmp"] / "shared" / "meshes"
    other.mkdir(parents=True)
    (other / "foot.stl").write_bytes(b"solid foot\n")
    (tree["root"] / "foot.stl").symlink_to(other / "foot.stl")
    assert confine_resource("foot.stl", [tree["root"], other]) == (other / "foot.stl").resolve()
    with pytest.raises(ResourceRefused, match="outside the mesh roots"):
        confine_resource("foot.stl", [tree["root"]])


def test_size_limit(tree: dict[str, Path]) -> None:
    with pytest.raises(ResourceRefused, match="over the"):
        read_resource("meshes/leg.stl", [tree["root"]], max_bytes=5)
