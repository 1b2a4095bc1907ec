"""``path_placement`` defaults relative to the arm it is given, and the pre-flight check.

``derive(robot, params) -> Task`` (the contract of :mod:`legcore.studies.task`) fills every
field the user left unset, by these rules (recorded with their numbers in ``Task.rules``):

- **the path's size** (``path_scale``, built-in paths): the arm's reach / the PUMA 560's (both
  by the same sampled FK, :func:`legcore.studies.arm_workspace.arm_workspace`; the PUMA's is
  1.076 m): the pan's radius 0.08 m and the jar's 0.06 × 0.15 m scale with it, the tool
  orientations are kept;
- **the tool orientation** (``path_axis``, ``spin``; built-in paths): the path as drawn, or
  turned rigidly so that its mean tool axis points down, forward (away from the arm) or up —
  the first the arm holds with the whole path reachable and feasible; each pose spun about
  its own axis by the first of 0, π/2, π, −π/2 (a torch spins freely about its axis) at which
  the arm reaches the most of the path;
- **the original placement** (``original``) — the % reference and a start of the search: the
  path's centroid on a well-conditioned posture holding the path's mean tool axis
  (:func:`~legcore.studies.arm_workspace.centres`, at least 0.1 × the reach above the base),
  the first of the best :data:`CENTRES_TRIED` where the whole path is reachable and every
  constraint holds;
- **the start posture** (``postures``): that posture (the IK of every candidate starts there
  and a redundant arm is pulled toward it);
- **the duration** (``duration``, built-in paths): the paper's, stretched (never shortened)
  until every joint stays within :data:`SPEED_SHARE` of its speed limit at the original
  placement (the path's speeds scale with 1/duration);
- **the region** (``region``): a sector of a spherical shell about the shoulder around the
  original anchor, ± h in distance and ± h of arc in elevation and azimuth, h the largest of
  :data:`REGION_SIZES` × the reach for which the whole path is reachable at the sector's 8
  corners (else the smallest: reachable at the original placement only, said in the rule);
- **the nominal power** (``nominal_power_kw``): Σ τ_max,i q̇_max,i, the combined peak
  mechanical power of the joints at their torque and speed limits — the power constraint then
  follows from the joint limits and P_n only scales the energy term of the cost. A joint
  without a torque limit (a DH table without ``tau_max``, e.g. an edited PUMA 560) counts with
  :data:`MOTOR_SIZING` × its largest gravity torque over the sampled workspace (a motor sized
  with that margin over its static load), said in the rule.

Other fields (the energy weight, the anchor, the timing, the branch rule) are robot
independent; ``max_manipulability`` is the arm's own (computed when the problem is built).
No original placement passes → ``ValueError("original: …")``. Cost: a few batched IK solves
of the path, ~0.1-0.5 s (cached per robot by :func:`legcore.studies.fit.fit`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore.dynamics import inverse_dynamics
from legcore.robots.model import Robot
from legcore.studies.arm_workspace import arm_workspace, centres
from legcore.studies.path_placement.params import Params
from legcore.studies.path_placement.paths import JAR_DURATION, PAN_DURATION, oriented
from legcore.studies.path_placement.region import BoxRegion
from legcore.studies.task import Task

__all__ = ["CENTRES_TRIED", "REGION_SIZES", "SPEED_SHARE", "derive", "puma560_reach"]

FloatArray = NDArray[np.float64]

#: Region half-sizes tried, fractions of the reach (largest first).
REGION_SIZES = (0.2, 0.1, 0.05)
#: Share of each joint's speed limit the original placement may use (duration stretched).
SPEED_SHARE = 0.5
#: Well-conditioned postures tried for the original placement.
CENTRES_TRIED = 4
_PAPER_DURATION = {"pan": PAN_DURATION, "jar": JAR_DURATION}

#: A joint without a torque limit counts with this multiple of its largest gravity torque (a
#: motor sized with a margin of 2 over its static load) in the derived nominal power.
MOTOR_SIZING = 2.0


def puma560_reach() -> float:
    """The PUMA 560's reach (m) by :func:`~legcore.studies.arm_workspace.arm_workspace`."""
    from legcore.robots import catalog

    return arm_workspace(catalog.get("puma560")).reach  # type: ignore[arg-type]


def _problem(robot: Robot, params: Params) -> Any:
    from legcore.studies.path_placement.problem import PathPlacementProblem

    return PathPlacementProblem(robot, params)


def _sector(ws: Any, base: FloatArray, anchor: FloatArray, h: float) -> dict[str, Any]:
    """The shell sector (a ``ShellSpec`` dict, base coordinates) about the shoulder, ± ``h``
    (m) in distance and ± h of arc in elevation and azimuth around ``anchor`` (world)."""
    c = base[:3, :3].T @ (ws.shoulder - base[:3, 3])
    d = base[:3, :3].T @ (anchor - base[:3, 3]) - c
    rho = float(np.hypot(d[0], d[1]))
    R = float(np.linalg.norm(d))
    gamma, phi = math.atan2(-d[2], rho), math.atan2(d[1], d[0])
    dg, dp = h / max(R, h), h / max(rho, h)
    return {"kind": "shell", "center": tuple(float(v) for v in c),
            "R": (max(R - h, 0.0), R + h),
            "gamma": (max(gamma - dg, -math.pi / 2), min(gamma + dg, math.pi / 2)),
            "phi": (phi - dp, phi + dp)}


def _corners(region: Any) -> FloatArray:
    """The 8 corners (8, 3) of a shell sector's decision box."""
    lo, hi = region.xl, region.xu
    return np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]]
                     for i in (0, 1) for j in (0, 1) for k in (0, 1)])


def _torque_limits(robot: Robot, q: FloatArray) -> tuple[FloatArray, list[str]]:
    """Each joint's torque limit (n,) N·m — a joint without one (infinite) gets
    :data:`MOTOR_SIZING` × its largest gravity torque over the configurations ``q`` (N, n) —
    and the names of the joints whose limit was so estimated."""
    tau = np.asarray(robot.tau_max, dtype=float).copy()
    free = ~np.isfinite(tau)
    if not free.any():
        return tau, []
    zero = np.zeros_like(q)
    gravity = np.abs(inverse_dynamics(robot, q, zero, zero)).max(axis=0)
    tau[free] = MOTOR_SIZING * np.maximum(gravity[free], 1e-3)
    names = [str(robot.model.names[int(j) + 1]) for j in np.flatnonzero(free)]
    return tau, names


def derive(robot: Any, params: Params) -> Task:
    """The fields of ``params`` the user left unset, by the rules of the module docstring,
    and the pre-flight check (``ValueError("<field>: …")``)."""
    if not isinstance(robot, Robot) or robot.nq < 6:  # refused by the study's needs
        return Task(params, {})
    given = params.model_fields_set
    rules: dict[str, str] = {}
    values: dict[str, Any] = {}
    ws = arm_workspace(robot)
    if "nominal_power_kw" not in given:
        tau, estimated = _torque_limits(robot, ws.q)
        P = tau * robot.qd_max
        values["nominal_power_kw"] = float(f"{P.sum() / 1000.0:.4g}")
        rules["nominal_power_kw"] = (
            f"{P.sum() / 1000.0:.4g} kW = Σ τ_max,i q̇_max,i of the joints (their combined peak "
            f"mechanical power): the power constraint follows from the torque and speed limits"
            + (f"; no torque limit on {estimated}: {MOTOR_SIZING:g} × the joint's largest "
               "gravity torque over the sampled workspace" if estimated else ""))
    builtin = params.path != "csv"
    if builtin and "path_scale" not in given:
        scale = float(f"{ws.reach / puma560_reach():.3g}")
        values["path_scale"] = scale
        rules["path_scale"] = (
            f"{scale:.3g} = the reach of {robot.name} ({ws.reach:.3f} m) / the PUMA 560's "
            f"({puma560_reach():.3f} m), by the same sampled FK: "
            + ("a pan of radius " + f"{0.08 * scale:.4f} m" if params.path == "pan" else
               f"a jar of radius {0.06 * scale:.4f} m and height {0.15 * scale:.4f} m"))
    placed = {"original", "region", "postures"} | ({"duration", "path_axis", "spin"}
                                                    if builtin else set())
    if placed <= given:
        task = Params.model_validate({**params.model_dump(exclude_unset=True), **values})
        return Task(task, rules)
    base = _base(robot)
    draft = Params.model_validate({**params.model_dump(exclude_unset=True), **values,
                                   "path_axis": params.path_axis, "spin": 0.0})
    drawn = draft.tool_path()
    mean = drawn.T[:, :3, 2].mean(axis=0)
    mean /= np.linalg.norm(mean)
    base_h = float(base[:3, 3] @ ws.up)
    tried: list[str] = []
    for words, turn in _orientations(ws, params, mean, given, builtin):
        path = oriented(drawn, turn, 0.0)
        axis = path.T[:, :3, 2].mean(axis=0)
        axis /= np.linalg.norm(axis)
        if abs(float(axis @ ws.up)) > math.cos(math.radians(5.0)):
            axis = np.sign(float(axis @ ws.up)) * ws.up  # within 5° of vertical: the centres
            # are looked for with a vertical axis (and face forward); the IK checks the path
        anchor = path.p[0] if params.anchor == "first" else path.p.mean(axis=0)
        offset = anchor - path.p.mean(axis=0)
        cands = [c for c in centres(robot, axis) if c.p @ ws.up >= base_h + 0.1 * ws.reach]
        if "region" in given:  # the original must lie in the user's region
            inside = [c for c in cands if _inside(robot, params, c.p + offset)]
            cands = inside[:CENTRES_TRIED] + _region_centre(robot, params, axis, offset, cands)
        if not cands:
            tried.append(f"{words}: the arm holds that tool axis nowhere above its base"
                         + (" in the region" if "region" in given else ""))
            continue
        for c in cands[:CENTRES_TRIED + 1]:
            a_pos = c.p + offset
            fixed = dict(values)
            if builtin and "path_axis" not in given:
                fixed["path_axis"] = None if turn is None else tuple(float(v) for v in turn)
            if builtin and "spin" not in given:
                fixed["spin"] = _best_spin(robot, path, c.q, c.p - path.p.mean(axis=0))
            if "postures" not in given:
                fixed["postures"] = (tuple(float(v) for v in c.q),)
            fixed["region"] = params.region if "region" in given else _sector(
                ws, base, a_pos, REGION_SIZES[-1] * ws.reach)
            trial = Params.model_validate({**params.model_dump(exclude_unset=True), **fixed})
            pr = _problem(robot, trial)
            x0 = pr.workspace.coords(a_pos) if "original" not in given else np.asarray(
                params.original, dtype=float)
            d = pr._detail(x0)
            if d["unreachable"] > 0.0:
                tried.append(f"{words}: {100 * d['unreachable']:.0f} % out of reach at "
                             f"{_vec(a_pos)} m")
                continue
            stretch = 1.0
            if builtin and "duration" not in given:
                use = float(np.max(np.abs(d["qd"]).max(axis=0) / robot.qd_max))
                stretch = max(1.0, use / SPEED_SHARE)
                paper = _PAPER_DURATION[params.path]
                fixed["duration"] = float(f"{paper * stretch:.4g}") if stretch > 1.0 else None
                trial = Params.model_validate({**params.model_dump(exclude_unset=True),
                                               **fixed})
                pr = _problem(robot, trial)
                d = pr._detail(x0)
            if d["cv"] > 0.0:
                broken = "; ".join(v.text for v in pr.violations(x0))
                tried.append(f"{words}: infeasible at {_vec(a_pos)} m ({broken})")
                continue
            if builtin and "path_axis" not in given:
                rules["path_axis"] = (
                    f"{words}: the first of as drawn, down, forward, up whose mean tool axis "
                    f"{robot.name} holds with the whole path reachable and feasible")
            if builtin and "spin" not in given:
                rules["spin"] = (
                    f"{fixed['spin']:.4g} rad: the first of 0, π/2, π, −π/2 (a torch spins "
                    f"freely about its axis) at which {robot.name} reaches the most of the path")
            return _finish(robot, params, ws, base, pr, trial, fixed, rules, c, a_pos, x0,
                           stretch, given)
    raise ValueError(
        f"original: no well-conditioned placement of the {params.path} path on {robot.name} "
        f"is reachable and feasible ({'; '.join(tried)}); give original (and region, "
        f"postures)")


_SPINS = (0.0, math.pi / 2, math.pi, -math.pi / 2)


def _inside(robot: Robot, params: Params, p: FloatArray) -> bool:
    """Whether world point ``p`` is in the user's ``region``."""
    from legcore.studies.path_placement.region import region_of

    assert params.region is not None
    reg = region_of(params.region, robot)
    x = reg.coords(p)
    return bool(np.all(x >= reg.xl - 1e-12) and np.all(x <= reg.xu + 1e-12))


def _region_centre(robot: Robot, params: Params, axis: FloatArray, offset: FloatArray,
                   cands: list[Any]) -> list[Any]:
    """The user's region's centre as one more candidate: the posture holding ``axis`` there,
    from the best well-conditioned posture (none when the arm cannot hold it there)."""
    from legcore.ik import solve
    from legcore.studies.arm_workspace import Centre
    from legcore.studies.path_placement.region import region_of

    assert params.region is not None
    reg = region_of(params.region, robot)
    p = reg.point(0.5 * (reg.xl + reg.xu)) - offset
    q0 = cands[0].q if cands else robot.home
    sol = solve(robot, np.concatenate([p, axis]), "axis", q0=q0, rest=q0)
    if not bool(sol.reachable):
        return []
    return [Centre(np.asarray(sol.q, float), p, axis, 0.0, 0.0)]


def _orientations(ws: Any, params: Params, mean: FloatArray, given: set[str],
                  builtin: bool) -> list[tuple[str, FloatArray | None]]:
    """(words, the direction the path's mean tool axis is turned to or None) in the order
    tried: as drawn, then down, forward, up (a built-in path whose ``path_axis`` is unset)."""
    out: list[tuple[str, FloatArray | None]] = [("as drawn", None)]
    if not builtin or "path_axis" in given:
        return out
    for words, a in (("down", ws.down), ("forward (away from the arm, horizontal)",
                                          ws.forward), ("up", ws.up)):
        if float(a @ mean) < 1.0 - 1e-6:
            out.append((words, np.asarray(a, dtype=float)))
    return out


def _best_spin(robot: Robot, path: Any, q: FloatArray, shift: FloatArray) -> float:
    """The first of :data:`_SPINS` at which the numerical IK from ``q`` reaches the most of
    every 8th pose of ``path`` moved by ``shift`` (m)."""
    from legcore.ik import solve
    from legcore.studies.path_placement.paths import oriented as turn

    T = np.stack([turn(path, None, s).T[::8] for s in _SPINS])
    T[..., :3, 3] += shift
    sol = solve(robot, T, "pose", q0=q, rest=q, path=True, method="numeric", restarts=2,
                max_substeps=4, max_iter=60)
    return float(_SPINS[int(np.argmax(sol.reachable.sum(axis=1)))])


def _finish(robot: Robot, params: Params, ws: Any, base: FloatArray, pr: Any, trial: Params,
            fixed: dict[str, Any], rules: dict[str, str], c: Any, a_pos: FloatArray,
            x0: FloatArray, stretch: float, given: set[str]) -> Task:
    """The task with the region grown to the largest size that keeps the path reachable at
    its corners, and the rules of the placement."""
    if "region" not in given:
        chosen, where = fixed["region"], "at the original placement only"
        for f in REGION_SIZES:
            spec = _sector(ws, base, a_pos, f * ws.reach)
            probe = _problem(robot, Params.model_validate(
                {**trial.model_dump(exclude_unset=True), "region": spec}))
            b = probe._batch(_corners(probe.workspace))
            reach_ok = np.min(b.unreachable, axis=1) <= 0.0
            if reach_ok.all():
                chosen, where = spec, f"at its 8 corners (h = {f:g} × reach = {f * ws.reach:.3f} m)"
                break
        fixed["region"] = chosen
        R, g, p = chosen["R"], chosen["gamma"], chosen["phi"]
        rules["region"] = (
            f"shell sector about the shoulder {_vec(ws.shoulder)} m: R {R[0]:.3f}–{R[1]:.3f} m, "
            f"γ {g[0]:.3f}–{g[1]:.3f} rad, φ {p[0]:.3f}–{p[1]:.3f} rad, around the original "
            f"anchor; the whole path is reachable {where}")
        pr = _problem(robot, Params.model_validate(
            {**trial.model_dump(exclude_unset=True), "region": chosen}))
        x0 = pr.workspace.coords(a_pos) if "original" not in given else x0
    if "original" not in given:
        fixed["original"] = tuple(float(v) for v in x0)
        rel = c.p - ws.shoulder
        height = float(rel @ ws.up)
        box = isinstance(pr.workspace, BoxRegion)  # x = (x, y, z) m, else (R m, γ rad, φ rad)
        units = ("m", "m", "m") if box else ("m", "rad", "rad")
        coords = ", ".join(f"{v:.4f} {u}" for v, u in zip(x0, units, strict=True))
        rules["original"] = (
            f"({coords}): the path's centroid at "
            f"{_vec(c.p)} m ({float(np.linalg.norm(rel - height * ws.up)):.3f} m from the base "
            f"axis, {height:+.3f} m above the shoulder), a well-conditioned posture holding the "
            f"path's mean tool axis (dexterity {c.dexterity:.3f}); the whole path is reachable "
            f"there and every constraint holds")
    if "postures" not in given:
        rules["postures"] = "the original placement's well-conditioned posture (IK start, rest)"
    if params.path != "csv" and "duration" not in given:
        paper = _PAPER_DURATION[params.path]
        rules["duration"] = (
            f"the paper's {paper:.6g} s" + (f" × {stretch:.3g} = {fixed['duration']:.4g} s"
                                             if fixed.get("duration") else "")
            + f": every joint within {100 * SPEED_SHARE:.0f} % of its speed limit at the "
              f"original placement")
    task = Params.model_validate({**params.model_dump(exclude_unset=True), **fixed})
    return Task(task, rules)


def _base(robot: Robot) -> FloatArray:
    from legcore.studies.path_placement.region import _base as base_of

    return base_of(robot)


def _vec(v: FloatArray) -> str:
    return "(" + ", ".join(f"{x:.3f}" for x in np.asarray(v, float)) + ")"
