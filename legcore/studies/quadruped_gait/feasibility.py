"""What one step of the ``quadruped_gait`` walk violates, in words with sizes and units: the
optimum's and the baselines' ``violations`` and the pre-flight check of the default step
(:mod:`legcore.studies.quadruped_gait.defaults`).

The constraint columns of the problem's ``G`` (≤ 0 feasible) and their violations:

* ``stability_margin_mm``: the least static margin of the COM in the support polygon over the
  cycle is below the required one (mm; "airborne" when some instant has no foot down);
* ``unreachable_fraction``: a fraction of the foot positions is out of the leg's reach or its
  joint limits (which legs, and whether in stance or only in the swing);
* ``joint_speed`` / ``torque``: the joint with the highest |q̇| / q̇_max (|τ| / τ_max), its peak
  and its limit (rad/s, N·m);
* ``foot_pull``: a stance foot would have to pull on the ground (a negative vertical load, N,
  and as a share of the robot's weight) to hold the body in static equilibrium.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from legcore.studies.quadruped_gait.contract import GaitProblem
from legcore.studies.task import Violation

__all__ = ["StepReport", "step_report"]


@dataclass(frozen=True)
class StepReport:
    """One step ``x = (s, h, β)`` against every limit (SI units; see the module docstring).

    ``G``: the problem's constraint row; ``margin``/``required`` m (``-inf``: airborne);
    ``unreachable`` fraction of samples, ``unreachable_legs`` and ``unreachable_in_stance``;
    ``qd_ratio``/``tau_ratio`` the peak share of a limit on ``qd_joint``/``tau_joint`` with
    its peak and limit; ``pull`` N the largest downward force a foot would need (≤ 0: none)
    on ``pull_leg``; ``weight`` N the robot's weight.
    """

    G: tuple[float, ...]
    margin: float
    required: float
    unreachable: float
    unreachable_legs: tuple[str, ...]
    unreachable_in_stance: bool
    qd_ratio: float
    qd_joint: str
    qd_peak: float
    qd_limit: float
    tau_ratio: float
    tau_joint: str
    tau_peak: float
    tau_limit: float
    pull: float
    pull_leg: str
    weight: float

    def violations(self) -> tuple[Violation, ...]:
        """The violated columns of ``G``, each with its size, unit and words."""
        g_margin, g_reach, g_speed, g_torque, g_pull = self.G
        out: list[Violation] = []
        if g_margin > 0.0:
            if math.isfinite(self.margin):
                text = (f"static stability margin {self.margin * 1e3:.3g} mm, "
                        f"{g_margin:.3g} mm short of the required {self.required * 1e3:.3g} mm")
            else:
                text = "no foot on the ground at some instant (airborne): no static margin"
            out.append(Violation("stability_margin_mm", g_margin, "mm", text))
        if g_reach > 0.0:
            where = "in stance" if self.unreachable_in_stance else "in the swing only"
            out.append(Violation(
                "unreachable_fraction", g_reach, "",
                f"{g_reach:.1%} of the foot positions out of reach or outside the joint limits "
                f"(legs {', '.join(self.unreachable_legs) or '?'}; {where})"))
        if g_speed > 0.0:
            out.append(Violation(
                "joint_speed", g_speed, "",
                f"joint {self.qd_joint} at {self.qd_ratio:.0%} of its speed limit "
                f"{self.qd_limit:.4g} rad/s (peak {self.qd_peak:.4g} rad/s)"))
        if g_torque > 0.0:
            out.append(Violation(
                "torque", g_torque, "",
                f"joint {self.tau_joint} at {self.tau_ratio:.0%} of its torque limit "
                f"{self.tau_limit:.4g} N·m (peak {self.tau_peak:.4g} N·m)"))
        if g_pull > 0.0:
            out.append(Violation(
                "foot_pull", self.pull, "N",
                f"foot {self.pull_leg} pulls on the ground with {self.pull:.3g} N "
                f"({self.pull / self.weight:.1%} of the robot's weight) to hold the body"))
        return tuple(out)


def _peak(values: Any, limits: Any, names: tuple[str, ...]) -> tuple[float, str, float, float]:
    """(peak ratio, joint, peak, limit) of |values| (K, n) against ``limits`` (n,)."""
    peak = np.max(np.abs(values), axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(np.isfinite(limits) & (limits > 0.0), peak / limits, 0.0)
    j = int(np.argmax(ratio))
    return float(ratio[j]), names[j], float(peak[j]), float(limits[j])


def step_report(problem: GaitProblem, x: Any) -> StepReport:
    """Walk one cycle of step ``x`` (3,) with ``problem`` (a ``QuadrupedGaitProblem``) and
    report it against every limit."""
    x = np.asarray(x, dtype=float).reshape(1, 3)
    r = problem.simulate(x, detail=True)
    _, G = problem.objective_constraints(r)
    qd_max = np.concatenate([leg.robot.qd_max for leg in problem.legs])
    tau_max = np.concatenate([leg.robot.tau_max for leg in problem.legs])
    qd = _peak(r["qd"][0], qd_max, problem.joint_names)
    tau = _peak(r["tau"][0], tau_max, problem.joint_names)
    ok, sup = r["reachable"][0], r["support"][0]
    bad_legs = tuple(n for j, n in enumerate(problem.leg_names) if not ok[:, j].all())
    loads = r["loads"][0]  # (K+1, legs)
    j_pull = int(np.argmin(loads.min(axis=0)))
    return StepReport(
        G=tuple(float(g) for g in G[0]),
        margin=float(r["margin"][0]),
        required=float(problem.required_margin),
        unreachable=float(r["bad"][0]),
        unreachable_legs=bad_legs,
        unreachable_in_stance=bool(np.any(~ok & sup)),
        qd_ratio=qd[0], qd_joint=qd[1], qd_peak=qd[2], qd_limit=qd[3],
        tau_ratio=tau[0], tau_joint=tau[1], tau_peak=tau[2], tau_limit=tau[3],
        pull=float(-loads.min()),
        pull_leg=problem.leg_names[j_pull],
        weight=float(problem.mass * problem.g),
    )
