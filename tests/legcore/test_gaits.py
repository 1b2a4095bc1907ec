"""Gait sequences (seed 002 Fig. 3, seed 003 Fig. 8), support polygon, stability margins."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from legcore.gaits import (
    QUADRUPED_FIG8,
    QUADRUPED_WALK,
    TRIPOD,
    Gait,
    gait_phase,
    leg_phase,
    support_flags,
)
from legcore.support_polygon import stability_margin, support_polygon
from legcore.tripod_stability import (
    support_triangle,
    tripod_feet,
    tripod_stability,
    tripod_triangle,
)

GRID = (np.arange(2400) + 0.5) / 2400  # fine phase grid, no sample on a state boundary


def _lift_offs(gait: Gait) -> np.ndarray:
    on = support_flags(gait, GRID)
    return np.sum(on & ~np.roll(on, -1, axis=0), axis=0)  # ground -> air, cyclically


# ---------------------------------------------------------------- sequences


def test_tripod_matches_seed002_fig3_states() -> None:
    assert len(TRIPOD.states) == 6
    mids = (np.arange(6) + 0.5) / 6
    flags = support_flags(TRIPOD, mids)
    for state, row in zip(TRIPOD.states, flags, strict=True):
        on = {leg for leg, f in zip(TRIPOD.legs, row, strict=True) if f}
        assert on == state.support, state.name
    # The paper's words: state 1, 1-3-5 support and 2-4-6 lifted; state 4 the reverse;
    # transitions 3 and 6 have both tripods down.
    assert [sorted(s.support) for s in TRIPOD.states] == [
        ["L1", "L3", "L5"], ["L1", "L3", "L5"], ["L1", "L2", "L3", "L4", "L5", "L6"],
        ["L2", "L4", "L6"], ["L2", "L4", "L6"], ["L1", "L2", "L3", "L4", "L5", "L6"],
    ]  # fmt: skip
    # recoveries: 2-4-6 in state 2, 1-3-5 in state 5, each while in the air
    assert TRIPOD.states[1].moving == {"L2", "L4", "L6"}
    assert TRIPOD.states[4].moving == {"L1", "L3", "L5"}
    for k in (1, 4):
        assert not (TRIPOD.states[k].moving & TRIPOD.states[k].support)


def test_every_leg_swings_exactly_once_per_cycle() -> None:
    for gait in (TRIPOD, QUADRUPED_WALK, QUADRUPED_FIG8):
        assert np.all(_lift_offs(gait) == 1), gait.name
        air = 1.0 - support_flags(gait, GRID).mean(axis=0)
        assert np.allclose(air, 1.0 - gait.duty, atol=1e-3)


def test_tripod_legs_move_in_two_antiphase_groups() -> None:
    flags = support_flags(TRIPOD, GRID)
    a, b = flags[:, [0, 2, 4]], flags[:, [1, 3, 5]]
    assert np.all(a == a[:, :1]) and np.all(b == b[:, :1])
    assert np.all(a[:, 0] | b[:, 0])  # always at least one tripod on the ground
    # tripod B's air phase is half a cycle after tripod A's
    assert np.array_equal(np.roll(a[:, 0], len(GRID) // 2), b[:, 0])


def test_quadruped_walk_quarter_offsets_and_order() -> None:
    offs = dict(zip(QUADRUPED_WALK.legs, QUADRUPED_WALK.offsets, strict=True))
    assert sorted(offs.values()) == [0.0, 0.25, 0.5, 0.75]
    # swing order: FL (PDI), RR (PTD), FR (PDD), RL (PTI)
    assert sorted(offs, key=offs.get) == ["FL", "RR", "FR", "RL"]
    flags = support_flags(QUADRUPED_WALK, GRID)
    assert np.all(flags.sum(axis=1) == 3)  # one foot in the air at a time
    for k, state in enumerate(QUADRUPED_WALK.states):
        row = support_flags(QUADRUPED_WALK, (k + 0.5) / 4)
        assert {leg for leg, f in zip(QUADRUPED_WALK.legs, row, strict=True) if f} == state.support
    # Fig. 8's pairing: diagonal FL+RR swing in the first half-cycle, RL+FR in the second
    first, second = GRID < 0.5, GRID >= 0.5
    legs = np.array(QUADRUPED_WALK.legs)
    assert set(legs[(~flags[first]).any(axis=0)]) == {"FL", "RR"}
    assert set(legs[(~flags[second]).any(axis=0)]) == {"FR", "RL"}


def test_quadruped_fig8_table_reproduced() -> None:
    # Seed 003 Fig. 8: rows PDI, PTI, PTD, PDD; columns tiempos 1-4; R = retracción (air),
    # A = avance (ground).
    fig8 = {
        "FL": "RARA",  # PDI
        "RL": "ARAR",  # PTI
        "RR": "RARA",  # PTD
        "FR": "ARAR",  # PDD
    }
    tiempos = (np.arange(4) + 0.5) / 2.0 % 1.0  # one tiempo = half a cycle
    flags = support_flags(QUADRUPED_FIG8, tiempos)
    for j, leg in enumerate(QUADRUPED_FIG8.legs):
        assert "".join("A" if f else "R" for f in flags[:, j]) == fig8[leg]


def test_phase_helpers() -> None:
    assert gait_phase([0.0, 0.75, 1.5, -0.25], period=1.0).tolist() == [0.0, 0.75, 0.5, 0.75]
    u = leg_phase(QUADRUPED_WALK, np.array([0.1]))
    assert u.shape == (1, 4) and u[0].tolist() == pytest.approx([0.1, 0.6, 0.35, 0.85])
    longer = QUADRUPED_WALK.with_duty(0.8)
    assert longer.states == () and np.all(_lift_offs(longer) == 1)
    with pytest.raises(ValueError, match="period"):
        gait_phase([0.0], period=0.0)
    with pytest.raises(ValueError, match="duty"):
        Gait("bad", ("a",), (0.0,), 1.0)
    with pytest.raises(ValueError, match="offsets"):
        Gait("bad", ("a", "b"), (0.0,), 0.5)


# ---------------------------------------------------------------- polygon and margin


def test_margin_hand_computed_cases() -> None:
    square = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])
    assert stability_margin(square) == pytest.approx(1.0)
    assert stability_margin(square, c=[0.5, 0.2]) == pytest.approx(0.5)
    assert stability_margin(square, c=[2.0, 0.0]) == pytest.approx(-1.0)
    # 3-4-5 right triangle: its incentre (1, 1) is at the inradius r = (3 + 4 − 5)/2 = 1
    tri = np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 3.0]])
    assert stability_margin(tri, c=[1.0, 1.0]) == pytest.approx(1.0)
    assert stability_margin(tri, c=[2.0, 1.0]) == pytest.approx(abs(3 * 2 + 4 * 1 - 12) / 5)
    # a lifted foot: square minus the (1, 1) corner -> the diagonal through (−1, 1), (1, −1)
    sup = np.array([False, True, True, True])
    assert stability_margin(square, sup, c=[0.0, 0.0]) == pytest.approx(0.0, abs=1e-15)
    assert stability_margin(square, sup, c=[-0.5, -0.5]) == pytest.approx(0.5)  # the sides
    assert stability_margin(square, sup, c=[-0.2, -0.2]) == pytest.approx(0.4 / math.sqrt(2))
    assert stability_margin(square, sup, c=[0.5, 0.5]) == pytest.approx(-math.sqrt(0.5))


def test_margin_degenerate_supports() -> None:
    line = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 0.0]])
    assert stability_margin(line, c=[1.0, 0.0]) == 0.0
    assert stability_margin(line, c=[1.0, 0.5]) == pytest.approx(-0.5)
    assert stability_margin(line, c=[3.0, 0.0]) == pytest.approx(-1.0)  # beyond the segment end
    two = np.array([[0.0, 0.0], [2.0, 0.0], [5.0, 5.0]])
    assert stability_margin(two, [True, True, False], c=[1.0, 1.0]) == pytest.approx(-1.0)
    assert stability_margin(two, [False, False, True], c=[2.0, 1.0]) == pytest.approx(-5.0)
    assert stability_margin(two, [False, False, False]) == -np.inf


def test_margin_batched_3d_input_matches_per_sample() -> None:
    rng = np.random.default_rng(5)
    feet = rng.normal(size=(300, 6, 3))
    sup = rng.random((300, 6)) < 0.7
    c = rng.normal(scale=0.3, size=(300, 2))
    m = stability_margin(feet, sup, c)
    assert m.shape == (300,)
    for b in range(0, 300, 7):  # independent check: scipy-free hull via all edge lines
        P = feet[b, sup[b], :2]
        if len(P) < 3:
            continue
        best = np.inf
        for i in range(len(P)):
            for j in range(len(P)):
                if i == j:
                    continue
                d = P[j] - P[i]
                cr = d[0] * (P[:, 1] - P[i, 1]) - d[1] * (P[:, 0] - P[i, 0])
                if np.all(cr >= -1e-12):
                    s = (d[0] * (c[b, 1] - P[i, 1]) - d[1] * (c[b, 0] - P[i, 0])) / np.hypot(*d)
                    best = min(best, s)
        assert m[b] == pytest.approx(best, abs=1e-12)


def test_support_polygon_vertices_ccw() -> None:
    feet = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [0.0, 2.0], [1.0, 1.0], [2.0, 0.0]])
    V, n = support_polygon(feet)
    assert n == 4
    hull = V[:4]
    assert {tuple(v) for v in hull} == {(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)}
    area = 0.5 * np.sum(hull[:, 0] * np.roll(hull[:, 1], -1) - np.roll(hull[:, 0], -1) * hull[:, 1])
    assert area == pytest.approx(4.0)  # positive: counter-clockwise
    assert np.all(np.isnan(V[4:]))
    V, n = support_polygon(feet, [True, True, True, False, False, False])
    assert n == 2  # collinear: the two end points
    assert {tuple(v) for v in V[:2]} == {(0.0, 0.0), (2.0, 2.0)}


def test_walk_is_statically_stable_and_the_diagonal_sequence_is_not() -> None:
    # Rectangle of hips (±0.11, ±0.063); stance feet slide back linearly over the stroke s.
    hips = {"FL": (0.11, 0.063), "FR": (0.11, -0.063), "RL": (-0.11, 0.063), "RR": (-0.11, -0.063)}
    s = 0.08

    def feet(gait: Gait, phase: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u = leg_phase(gait, phase)
        air = 1.0 - gait.duty
        prog = np.clip((u - air) / gait.duty, 0.0, 1.0)  # stance progress
        H = np.array([hips[leg] for leg in gait.legs])
        x = H[:, 0] + s / 2 - s * prog
        return np.stack((x, np.broadcast_to(H[:, 1], x.shape)), -1), support_flags(gait, phase)

    F, S = feet(QUADRUPED_WALK, GRID)
    m = stability_margin(F, S)
    assert np.all(m >= -1e-12)
    beat_pos = np.mod(GRID * 4, 1.0)
    assert np.all(m[(beat_pos > 0.05) & (beat_pos < 0.95)] > 1e-4)
    # Every other order of the four quarter-cycle swings tips over at some phase.
    for order in itertools.permutations(("RR", "FR", "RL")):
        if order == ("RR", "FR", "RL"):
            continue
        pos = {leg: k / 4 for k, leg in enumerate(("FL", *order))}
        other = Gait("x", QUADRUPED_WALK.legs, tuple(pos[g] for g in QUADRUPED_WALK.legs), 0.75)
        F, S = feet(other, GRID)
        assert np.min(stability_margin(F, S)) < -0.005, order
    # Fig. 8's two-foot diagonal support has zero area: margin <= 0 (dynamic, not static).
    F, S = feet(QUADRUPED_FIG8, GRID)
    assert np.all(stability_margin(F, S) <= 1e-12)


# ---------------------------------------------------------------- seed 002 triangle


HIPS_135 = np.array(
    [
        [[1, 0, 0, 3.5], [0, 1, 0, 5.0], [0, 0, 1, 0], [0, 0, 0, 1]],  # leg 1, cm
        [[1, 0, 0, 3.5], [0, 1, 0, -5.0], [0, 0, 1, 0], [0, 0, 0, 1]],  # leg 3
        [[-1, 0, 0, -3.5], [0, -1, 0, 0.0], [0, 0, 1, 0], [0, 0, 0, 1]],  # leg 5, yaw π
    ],
    dtype=float,
)
L_CM = (1.0, 3.5, 6.0)
TH2, TH3 = -math.pi / 8, -math.pi / 4
REACH = 1.0 + 3.5 * math.cos(math.pi / 8) + 6.0 * math.cos(3 * math.pi / 8)  # 6.5297 cm


def test_initial_support_triangle_by_hand() -> None:
    beta1, beta5, p = tripod_triangle(np.zeros(3), HIPS_135, L_CM, TH2, TH3)
    X = 3.5 + REACH  # feet at (X, 5), (X, −5), (−X, 0)
    side = math.hypot(2 * X, 5.0)
    assert p == pytest.approx(10.0 + 2 * side, abs=1e-12)
    assert beta1 == pytest.approx(math.atan(2 * X / 5.0), abs=1e-12)  # eq (12), x1 = x3
    assert beta5 == pytest.approx(math.asin(math.sin(beta1) * 10.0 / side), abs=1e-12)  # eq (13)
    paper = tripod_triangle(np.zeros(3), HIPS_135, L_CM, TH2, TH3, formula="paper")
    assert np.allclose(paper, (beta1, beta5, p), atol=1e-12)
    assert 2 * beta1 + beta5 == pytest.approx(math.pi)  # isosceles, apex at foot 5


def test_support_triangle_population_and_invariance() -> None:
    rng = np.random.default_rng(6)
    th1 = rng.uniform(-math.pi / 6, math.pi / 6, (500, 3))
    b1, b5, p = tripod_triangle(th1, HIPS_135, L_CM, TH2, TH3)
    assert b1.shape == b5.shape == p.shape == (500,)
    F = tripod_feet(th1, HIPS_135, L_CM, TH2, TH3)
    assert F.shape == (500, 3, 3) and np.allclose(F[..., 2], -6.882669208, atol=1e-9)
    # interior angles are those of the law of cosines, and invariant to a rigid motion
    d1 = np.linalg.norm(F[:, 0] - F[:, 1], axis=-1)
    d2 = np.linalg.norm(F[:, 1] - F[:, 2], axis=-1)
    d3 = np.linalg.norm(F[:, 0] - F[:, 2], axis=-1)
    assert np.allclose(b1, np.arccos((d1**2 + d3**2 - d2**2) / (2 * d1 * d3)), atol=1e-12)
    assert np.allclose(b5, np.arccos((d2**2 + d3**2 - d1**2) / (2 * d2 * d3)), atol=1e-12)
    c, s = math.cos(0.7), math.sin(0.7)
    G = F[..., :2] @ np.array([[c, s], [-s, c]]) + [3.0, -1.0]
    moved = support_triangle(G[:, 0], G[:, 1], G[:, 2])
    assert np.allclose(moved, (b1, b5, p), atol=1e-12)


def test_tripod_stability_along_x() -> None:
    X = 3.5 + REACH
    front, middle, back = np.array([X, 5.0]), np.array([-X, 0.0]), np.array([X, -5.0])
    # body centre at the origin: both diagonals cross y = 0 at x = −X
    sf, sb = tripod_stability(front, middle, back)
    assert sf == pytest.approx(X) and sb == pytest.approx(X)
    # body moved forward by y: the front diagonal is at x = −X + 2X·y/5
    y = np.array([0.0, 1.0, 2.5, 3.0])
    sf, sb = tripod_stability(front, middle, back, c=np.column_stack((np.zeros(4), y)))
    assert np.allclose(sf, X - 2 * X * y / 5, atol=1e-12)
    assert np.allclose(sb, X + 2 * X * y / 5, atol=1e-12)
    assert sf[2] == pytest.approx(0.0, abs=1e-12) and sf[3] < 0  # leaves through the front edge


def test_tripod_stability_nearly_parallel_diagonal_is_unbounded_not_a_number() -> None:
    """Issue 11: a diagonal almost parallel to x gave S_f = 16 642.8 m; it is +inf now."""
    front, middle, back = np.array([0.3, 1e-6]), np.array([-0.3, 0.0]), np.array([0.3, -0.2])
    sf, sb = tripod_stability(front, middle, back, c=np.array([0.0, -0.05]))
    assert sf == np.inf and np.isfinite(sb)
    # a merely slanted diagonal stays a finite distance
    sf2, _ = tripod_stability(np.array([0.3, 0.2]), middle, back, c=np.array([0.0, -0.05]))
    assert np.isfinite(sf2) and sf2 > 0


# ---------------------------------------------------------------- unbounded margins in results


def _numbers_under(doc: object, keys: set[str]) -> list[tuple[str, object]]:
    """Every (key, value) of ``doc`` (nested dicts/lists) whose key is in ``keys``."""
    out: list[tuple[str, object]] = []
    if isinstance(doc, dict):
        for k, v in doc.items():
            if k in keys:
                out.append((k, v))
            out.extend(_numbers_under(v, keys))
    elif isinstance(doc, list):
        for v in doc:
            out.extend(_numbers_under(v, keys))
    return out


def test_unbounded_front_distance_is_flagged_and_stored_as_null() -> None:
    """Issue 11: seed 002's Table 2 c and d have feet 1 and 5 at the same y, so S_f along x is
    unbounded — once stored as 16 642.8 m. Now the metric carries ``S_f_unbounded = 1`` and the
    stored result (``RunResult.to_dict``, written as result.json and into the database) has no
    number for S_f: the key is absent or null, never a finite value."""
    import json

    import legcore

    spec = {"problem": {"kind": "hexapod_workspace", "pose_xy_step": 0.004},
            "optimizer": {"kind": "moead", "params": {"n_subproblems": 20}},
            "budget": {"generations": 2}, "seed": 1}
    result = legcore.run(spec)
    for key in ("paper_c", "paper_d"):
        m = result.baselines[key].metrics
        assert m["S_f_unbounded"] == 1.0 and m["S_b_unbounded"] == 0.0
        assert "S_f" not in m or not math.isfinite(m["S_f"])
        assert math.isfinite(m["S_b"]) and m["stability_margin"] > 0  # the perpendicular margin
    a = result.baselines["paper_a"].metrics
    assert a["S_f_unbounded"] == 0.0 and math.isfinite(a["S_f"])
    doc = json.loads(json.dumps(result.to_dict(), allow_nan=False))  # strict JSON
    for key in ("paper_c", "paper_d"):
        stored = doc["baselines"][key]["metrics"]
        assert stored["S_f_unbounded"] == 1.0 and stored.get("S_f") is None
    # nowhere in the stored document is a stability distance a huge finite number
    for k, v in _numbers_under(doc, {"S_f", "S_b"}):
        vals = v if isinstance(v, list) else [v]
        assert all(x is None or abs(x) < 1.0 for x in vals), (k, v)


def test_airborne_gait_margin_is_flagged_and_stored_as_null() -> None:
    """Seed 003: a duty factor of 0.2 leaves instants with no foot on the ground; the margin is
    -inf in memory, ``airborne = 1`` is set, and the stored result has null for it."""
    import json

    import legcore

    spec = {"robot": "animatronic_quadruped",
            "problem": {"kind": "quadruped_gait", "duty": 0.2, "duty_bounds": [0.15, 0.9]},
            "optimizer": {"kind": "hka", "params": {"n_samples": 10, "n_best": 3,
                                                     "init": "center"}},
            "budget": {"generations": 1}, "seed": 1}
    result = legcore.run(spec)
    m = result.baselines["default_step"].metrics
    assert m["airborne"] == 1.0 and m["min_stability_margin_m"] == -math.inf
    assert m["feasible"] == 0.0
    assert result.baselines["paper_walk"].metrics["airborne"] == 0.0
    doc = json.loads(json.dumps(result.to_dict(), allow_nan=False))
    stored = doc["baselines"]["default_step"]["metrics"]
    assert stored["airborne"] == 1.0 and stored["min_stability_margin_m"] is None
    walk = doc["baselines"]["paper_walk"]["metrics"]
    assert walk["airborne"] == 0.0 and isinstance(walk["min_stability_margin_m"], float)
