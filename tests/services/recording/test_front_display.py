"""How recordings draw Pareto fronts (issue 10, item 8): the front's box drawn as the unit square
with named, ticked axes (the data keep their true values), the final front shown on every
timeline, and merged sweep recordings giving each job its colour, name and one common box."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import numpy as np
import pyarrow as pa
from rerun.chunk import RrdReader

from services.recording import merge as M
from services.recording import writer as W
from services.recording.front_display import front_display
from tests.recording_fixtures import arm_motion, fake_result


def chunks(path: Path) -> dict[str, list[pa.RecordBatch]]:
    out: dict[str, list[pa.RecordBatch]] = defaultdict(list)
    for chunk in RrdReader(path).stream():
        out[chunk.entity_path.lstrip("/")].append(chunk.to_record_batch())
    return dict(out)


def values(batches: list[pa.RecordBatch], suffix: str) -> list:
    """Every value of the component whose column name ends with ``suffix``."""
    return [v for b in batches for n in b.schema.names if n.endswith(suffix)
            for v in b.column(n).to_pylist() if v is not None]  # fmt: skip


def test_box_maps_to_the_unit_square_with_y_up_and_named_axes() -> None:
    F = np.array([[5.0, 14.45], [20.0, 14.2], [35.0, 14.15]])
    d = front_display([F], ["time", "energy"], "path_tracking")
    assert d is not None and d.labels == ("cycle time [s]", "mechanical energy ∫|τ·ω|dt [J]")
    t, s = d.transform()
    drawn = np.c_[F, np.zeros(3)] * s + t
    assert np.all((drawn[:, :2] > 0) & (drawn[:, :2] < 1))  # the spread fills the square
    assert drawn[0, 1] < drawn[2, 1]  # y down in a 2-D view: the larger energy is drawn higher
    lines, marks = d.axes()
    assert len(lines) == 2 and {m.label for m in marks} >= set(d.labels)
    assert "5" not in {m.label for m in marks} and any(m.label.startswith("14.") for m in marks)
    flat = front_display([np.array([[1.0, 2.0], [1.0, 2.0]])], ["a", "b"])
    assert flat is not None and np.all(flat.hi > flat.lo)
    assert front_display([np.zeros((0, 2))], ["a", "b"]) is None


def test_recording_shows_the_final_front_on_every_timeline(tmp_path: Path) -> None:
    res = fake_result(arm_motion(K=100), generations=5)
    path = tmp_path / "job.rrd"
    rng = np.random.default_rng(1)
    fronts = {g: rng.random((20, 3)) * [10.0, 0.5, 3.0] for g in range(1, 6)}
    W.write_recording(res, path, fronts=fronts)
    ents = chunks(path)
    final = ents["optimization/final_front"]
    assert all("generation" not in b.schema.names for b in final)  # static
    (pts,) = values(final, ":positions")
    np.testing.assert_allclose(pts, fronts[5], rtol=1e-6)  # true values, not normalised
    assert values(ents["optimization/axes/labels"], ":labels")
    assert values(ents["optimization/front"], ":scale")  # the box's transform
    (names,) = values(ents["optimization/axes"], "legopt_axis_names")
    assert len(names) == 3


def test_merged_recording_colours_and_boxes_jobs_together(tmp_path: Path) -> None:
    paths = []
    for i, shift in enumerate((0.0, 5.0)):
        p = tmp_path / f"{i}.rrd"
        fronts = {1: np.random.default_rng(i).random((15, 3)) + shift}
        W.write_recording(fake_result(arm_motion(K=50), generations=1), p, fronts=fronts)
        paths.append(p)
    out = tmp_path / "merged.rrd"
    M.merge_recordings(paths, out, ["a", "b"])
    ents = chunks(out)
    colours = [values(ents[f"jobs/{j}/optimization/front"], ":colors")[-1] for j in "ab"]
    assert colours[0] != colours[1]
    scales = [values(ents[f"jobs/{j}/optimization/front"], ":scale")[-1] for j in "ab"]
    assert scales[0] == scales[1]  # one box for both: the overlay compares like with like
    legend = str(values(ents["jobs/legend"], ":text"))
    assert "`a`" in legend and "`b`" in legend and "blue" in legend


def test_merged_jobs_never_share_a_colour() -> None:
    """Up to 32 jobs merge into one recording; each keeps its own colour and legend name."""
    from services.api.routes.sweeps import MAX_MERGED_JOBS
    from services.recording.merge import job_color

    colours = [job_color(i) for i in range(MAX_MERGED_JOBS)]
    assert len({rgb for rgb, _ in colours}) == MAX_MERGED_JOBS
    assert len({name for _, name in colours}) == MAX_MERGED_JOBS
    assert colours[0] == ((31, 119, 180), "blue")
