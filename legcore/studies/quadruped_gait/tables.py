"""Tables of the ``quadruped_gait`` study: the servo table of any quadruped, and seed 003's
Table 2 layout (2-joint closed-form legs) beside the printed rows.

Servo mapping (seed 003 Table 2, generalised to n joints per leg): link angles
``Ang = link_offset + link_matrix · q`` (deg; the robot's ``meta["servo"]``, identity — the
joint angles themselves — when it has none), then ``servo = offset + direction · Ang`` per servo
(``servo_offset_deg`` / ``servo_direction`` per leg, robot's meta then the study's params).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore.ik.leg2 import leg2_fk, leg2_ik
from legcore.studies.quadruped_gait.cycle import servo_angles_deg
from legcore.studies.quadruped_gait.legs import GaitLeg
from legcore.studies.quadruped_gait.params import Params

__all__ = ["TABLE2_COLUMNS", "servo_mapping", "servo_table", "table2", "table2_comparison"]

FloatArray = NDArray[np.float64]
TABLE2_COLUMNS = ("position", "Ang3", "Ang4", "q3DA", "q4DA", "Ang3", "Ang4", "q3TA", "q4TA")
_DH_NAMES = {2: ("q3", "q4"), 3: ("q1", "q2", "q3")}
_LINK_NAMES = {2: ("Ang3", "Ang4"), 3: ("Ang1", "Ang2", "Ang3")}


def servo_mapping(
    meta: dict[str, Any], legs: Sequence[GaitLeg], params: Params
) -> dict[str, dict[str, Any]]:
    """Per leg: link-angle offset/matrix, servo offsets/directions and the paper's leg name."""
    names = [g.name for g in legs]
    for pname, given in (("servo_offset_deg", params.servo_offset_deg),
                         ("servo_direction", params.servo_direction)):
        if given is not None:
            unknown = sorted(set(given) - set(names))
            if unknown:
                raise ValueError(f"{pname}: unknown legs {unknown}; legs are {names}")
            for leg, v in given.items():
                n = next(g.n for g in legs if g.name == leg)
                if len(v) != n:
                    raise ValueError(f"{pname}: leg {leg!r} has {n} joints, got {len(v)} values")
    servo = meta.get("servo", {}) if isinstance(meta.get("servo", {}), dict) else {}
    offs = {**dict(servo.get("servo_offset_deg", {})), **(params.servo_offset_deg or {})}
    dirs = {**dict(servo.get("servo_direction", {})), **(params.servo_direction or {})}
    paper = meta.get("paper_names", {})
    out: dict[str, dict[str, Any]] = {}
    for g in legs:
        n = g.n
        if servo and n == len(servo.get("link_angle_offset_deg", ())):
            offset = tuple(float(v) for v in servo["link_angle_offset_deg"])
            matrix = tuple(tuple(float(v) for v in r) for r in servo["link_angle_matrix"])
            link_names = _LINK_NAMES.get(n, tuple(f"Ang{i + 1}" for i in range(n)))
        else:
            offset, matrix = (0.0,) * n, tuple(tuple(float(i == j) for j in range(n))
                                               for i in range(n))
            link_names = tuple(f"q{i + 1}" for i in range(n))
        out[g.name] = {
            "link_offset": offset,
            "link_matrix": matrix,
            "link_names": link_names,
            "dh_names": _DH_NAMES.get(n, link_names) if servo else link_names,
            "servo_offset": tuple(float(v) for v in offs.get(g.name, (0.0,) * n)),
            "servo_direction": tuple(int(v) for v in dirs.get(g.name, (1,) * n)),
            "paper_name": paper.get(g.name, g.name) if isinstance(paper, dict) else g.name,
        }
    return out


def servo_table(
    legs: Sequence[GaitLeg], mapping: dict[str, dict[str, Any]], joint_names: Sequence[str],
    t: FloatArray, q: FloatArray,
) -> dict[str, Any]:
    """Servo commands (deg) per time step (rows) and servo (columns) over one cycle.

    ``t`` (K+1,) s, ``q`` (K+1, Σn) rad (legs side by side); the closing sample is left out, so
    the K rows are positions 1…K of the cycle.
    """
    servos, cols = [], []
    start = 0
    for g in legs:
        m = mapping[g.name]
        _, cmd = servo_angles_deg(q[:-1, start:start + g.n], m["link_offset"], m["link_matrix"],
                                  m["servo_offset"], m["servo_direction"])
        cols.append(cmd)
        for i in range(g.n):
            servos.append({
                "name": joint_names[start + i],
                "leg": g.name,
                "paper_leg": m["paper_name"],
                "dh_angle": m["dh_names"][i],
                "link_angle": m["link_names"][i],
                "offset_deg": m["servo_offset"][i],
                "direction": m["servo_direction"][i],
            })
        start += g.n
    cmd_all = np.concatenate(cols, -1)
    rows = [
        [k + 1, round(float(t[k]), 6), *(round(float(v), 2) for v in cmd_all[k])]
        for k in range(cmd_all.shape[0])
    ]
    first = mapping[legs[0].name]
    if first["link_names"] == first["dh_names"]:
        rule = "servo = offset + direction * q (deg; q the joint angles)"
    else:
        rule = ("servo = offset + direction * Ang; Ang3 = 90 - q3, Ang4 = 90 - q3 - q4 "
                "(deg; q3, q4 the DH angles of seed 003)")
    return {"mapping": rule, "columns": ["position", "t_s", *joint_names], "servos": servos,
            "rows": rows}


def _front_rear(legs: Sequence[GaitLeg]) -> tuple[GaitLeg, GaitLeg] | None:
    """The front-right and rear-right legs when every leg is a closed-form 2-joint leg."""
    if not all(g.closed_form for g in legs):
        return None
    by_role = {g.role: g for g in legs}
    return by_role["FR"], by_role["RR"]


def table2(
    legs: Sequence[GaitLeg], mapping: dict[str, dict[str, Any]], params: Params, s: float,
    positions: int | None = None,
) -> dict[str, Any] | None:
    """Seed 003 Table 2 layout for the stance stroke of step length ``s`` (m): ``positions``
    equally spaced foot positions from touch-down (front) to lift-off (back) at the depth H,
    front-right and rear-right legs: link angles Ang3/Ang4 and DH q3/q4 in degrees (DH angles
    wrapped into [0, 360) as the paper prints them; its front q3 column adds 360° to every row,
    e.g. 369 for 9°). Rows of unreachable positions hold None. None unless every leg is a
    closed-form 2-joint leg."""
    pair = _front_rear(legs)
    if pair is None:
        return None
    n = positions or params.table_positions
    depth, center = float(params.need("depth")), float(params.need("stroke_center"))
    y = center + 0.5 * s - s * np.linspace(0.0, 1.0, n)
    P = np.stack((np.full(n, depth), y), -1)
    cols: list[FloatArray] = []
    names = {}
    for role, g in zip(("FR", "RR"), pair, strict=True):
        names[role] = g.name
        rb = g.leg.robot
        q, _ = leg2_ik(P, g.L, g.branch, rb.q_min, rb.q_max)
        m = mapping[g.name]
        ang, _ = servo_angles_deg(q, m["link_offset"], m["link_matrix"], (0.0, 0.0), (1, 1))
        cols += [ang, np.mod(np.degrees(q), 360.0)]
    A = np.concatenate(cols, -1)
    rows = [[k + 1, *(None if not np.isfinite(v) else round(float(v), 2) for v in A[k])]
            for k in range(n)]
    return {"legs": names, "columns": list(TABLE2_COLUMNS), "rows": rows,
            "stroke": {"step_length_m": s, "depth_m": depth, "center_m": center}}


def table2_comparison(
    legs: Sequence[GaitLeg], mapping: dict[str, dict[str, Any]], params: Params,
    printed: Sequence[tuple[int, Sequence[float], Sequence[float]]],
) -> dict[str, Any] | None:
    """Seed 003's printed Table 2 rows (``printed``: position, front and rear columns) beside
    ours at the same stroke positions (default step length), with the differences (deg) and
    the foot depth of the printed rows. None unless :func:`table2` applies."""
    ours_t = table2(legs, mapping, params, float(params.need("step_length")), 48)
    pair = _front_rear(legs)
    if ours_t is None or pair is None:
        return None
    ours = ours_t["rows"]
    rows = []
    for pos, front, rear in printed:
        paper = [*front, *rear]
        mine = ours[pos - 1][1:]
        diff = [None if m is None else round(_wrap180(m - v), 2)
                for m, v in zip(mine, paper, strict=True)]
        depths = []
        for g, row in zip(pair, (front, rear), strict=True):
            q = np.radians([90.0 - row[0], row[0] - row[1]])
            depths.append(round(float(leg2_fk(q, g.L)[0]), 5))
        rows.append({"position": pos, "paper": paper, "ours": mine, "diff_deg": diff,
                     "paper_foot_depth_m": depths})
    return {"columns": list(TABLE2_COLUMNS[1:]), "rows": rows}


def _wrap180(a: float) -> float:
    return (a + 180.0) % 360.0 - 180.0
