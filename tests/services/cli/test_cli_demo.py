"""`legopt demo` on a fresh data directory (two examples, 3 generations each): the real service
processes, then one summary block per study with no repeated quantity, the maximised score shown
positive in the progress line and in the summary, and the front size of the multi-objective
study."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ["000_swing_energy_flat.yaml", "004_path_tracking_energy_time.yaml"]

pytestmark = pytest.mark.integration


@pytest.fixture(scope="module")
def demo_output(tmp_path_factory: pytest.TempPathFactory) -> str:
    data = tmp_path_factory.mktemp("demo") / "data"
    env = dict(os.environ, LEGOPT_DATA_DIR=str(data), NUMBA_NUM_THREADS="1", COLUMNS="160")
    for var in ("LEGOPT_DATABASE_URL", "LEGOPT_BROKER_URL", "LEGOPT_ARTIFACT_DIR",
                "LEGOPT_API_URL", "LEGOPT_API_KEY"):  # fmt: skip
        env.pop(var, None)
    args = [sys.executable, "-m", "services.cli", "demo", "--generations", "3"]
    for e in EXAMPLES:
        args += ["--examples", e]
    out = subprocess.run(args, env=env, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    assert (data / "legopt.db").exists()
    left = _processes_of(data)  # issue 8: every `demo` used to leave its two workers running
    assert not left, f"processes left after the demo exited: {left}"
    return out.stdout


def _processes_of(data: Path) -> list[str]:
    """Live processes whose environment names ``data`` as their data directory."""
    import psutil

    marker = f"LEGOPT_DATA_DIR={data}".encode()
    found = []
    for p in psutil.process_iter(["pid", "cmdline"]):
        try:
            if marker in Path(f"/proc/{p.pid}/environ").read_bytes().split(b"\0"):
                found.append(f"{p.pid} {' '.join(p.info['cmdline'] or [])[:120]}")
        except (OSError, psutil.Error):
            continue
    return found


NUMBER = r"\d+(?:\.\d+)?(?:e[-+]?\d+)?"


def _significant(number: str) -> int:
    """Significant digits of a printed number (``0.001169`` → 4, ``1.5e-05`` → 2)."""
    mantissa = number.split("e")[0].replace(".", "").lstrip("0")
    return len(mantissa)


def _blocks(text: str) -> dict[str, list[str]]:
    """Summary blocks by example label: the lines from its title to the next blank line."""
    blocks: dict[str, list[str]] = {}
    current: list[str] | None = None
    for line in text.splitlines():
        m = re.match(r"^(\S+) — \w+ · ", line)
        if m:
            assert m.group(1) not in blocks, f"two blocks for {m.group(1)}"
            current = blocks[m.group(1)] = []
        elif current is not None:
            if not line.strip():
                current = None
            else:
                current.append(line)
    return blocks


def _rows(block: list[str]) -> dict[str, str]:
    """Quantity -> the rest of its row, for the table rows of a block."""
    rows: dict[str, str] = {}
    in_table = False
    for line in block:
        if line.lstrip().startswith("───"):
            in_table = True
            continue
        if not in_table or line.lstrip().startswith("note —"):
            continue
        name, *rest = re.split(r"\s{2,}", line.strip(), maxsplit=1)
        assert name not in rows, f"quantity {name!r} appears twice"
        rows[name] = rest[0] if rest else ""
    return rows


def test_demo_prints_one_block_per_study(demo_output: str) -> None:
    blocks = _blocks(demo_output)
    assert sorted(blocks) == sorted(Path(e).stem for e in EXAMPLES)
    for label, block in blocks.items():
        rows = _rows(block)
        assert rows, f"{label}: no table rows"
        names = [n.split(" (paper:")[0].split(" — ")[0] for n in rows]
        assert len(names) == len(set(names)), f"{label}: a quantity repeats: {names}"
        for v in rows.values():
            assert all(_significant(n) <= 4 for n in re.findall(NUMBER, v)), v
    # the lines after the summaries say where to look next, with the demo's own job ids
    assert re.search(r"legopt results [0-9a-f]{8}", demo_output)
    assert re.search(r"legopt replay [0-9a-f]{8} --web", demo_output)
    assert "━" in demo_output and len(demo_output.splitlines()) < 60


def test_maximised_score_is_positive_everywhere(demo_output: str) -> None:
    progress = re.search(r"000_swing_energy_flat .* succeeded\s+score (\S+)", demo_output)
    assert progress, demo_output
    block = _blocks(demo_output)["000_swing_energy_flat"]
    row = next(line for line in block if "score F" in line)
    assert "maximised" in row and "(paper: F)" in row
    start, end = re.search(r"(\S+) → (\S+)", row).groups()  # type: ignore[union-attr]
    assert float(end) > 0 and float(start) > 0
    assert float(progress.group(1)) == pytest.approx(float(end), rel=1e-3)
    energy = next(line for line in block if "swing energy" in line)
    assert "(paper: E_T)" in energy and "-" not in energy.split("→")[1].split()[0]


def test_multi_objective_study_prints_its_front_size(demo_output: str) -> None:
    block = _blocks(demo_output)["004_path_tracking_energy_time"]
    assert re.search(r"Pareto front of \d+ points", " ".join(block))
    rows = _rows(block)
    assert sum("minimised" in n for n in rows) == 2  # both objectives, named once each


def test_demo_says_where_to_look_next(demo_output: str) -> None:
    """The demo ends with the dashboard address and the replay command (issue 13)."""
    tail = demo_output[-2000:]
    assert re.search(r"open http://127\.0\.0\.1:\d+/\s+the dashboard", demo_output), tail
    assert re.search(r"legopt replay [0-9a-f]{8} --web", demo_output), tail
