"""Shared fixtures of the recording tests (legcore.recording and the Rerun writer)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from legcore.dynamics import inverse_dynamics
from legcore.kinematics import fk
from legcore.recording.helpers import _cumtrapz
from legcore.robots import catalog
from legcore.studies.study import Motion, Solution


def arm_motion(K: int = 5000, T: float = 3.0, **scene: object) -> Motion:
    """A smooth 5-DOF motion of ``articulated_5dof`` with dynamics and energy."""
    robot = catalog.get("articulated_5dof")
    t = np.linspace(0.0, T, K)
    q = robot.home + 0.3 * np.sin(np.outer(t, np.arange(1, 6)))
    qd = np.gradient(q, t, axis=0)
    qdd = np.gradient(qd, t, axis=0)
    jerk = np.gradient(qdd, t, axis=0)
    tau = inverse_dynamics(robot, q, qd, qdd)
    power = tau * qd
    energy = _cumtrapz(np.abs(power), t).sum(axis=1)
    return Motion(
        t=t,
        q=q,
        joint_names=tuple(f"q{i + 1}" for i in range(5)),
        qd=qd,
        qdd=qdd,
        jerk=jerk,
        tau=tau,
        power=power,
        energy=energy,
        tool=fk(robot, q)[:, :3, 3],
        robot="articulated_5dof",
        scene=dict(scene),
    )


def fake_result(
    motion: Motion | None,
    *,
    m: int = 3,
    generations: int = 10,
    baselines: dict[str, Motion] | None = None,
    front_size: int = 50,
) -> SimpleNamespace:
    """Duck-typed RunResult (no JobSpec needed)."""
    rng = np.random.default_rng(0)
    history = [
        {
            "generation": g,
            "n_evals": 100 * g,
            "elapsed": 0.1 * g,
            "best_f": [1.0 / g + j for j in range(m)],
            "best_cv": 0.0,
            "front_size": front_size,
            "ideal": [0.0] * m,
            "nadir": [1.0] * m,
        }
        for g in range(1, generations + 1)
    ]
    sol = Solution(x=np.zeros(2), objectives={}, metrics={}, motion=motion)
    return SimpleNamespace(
        spec=None,
        status="succeeded",
        best=sol,
        pareto=[{"x": [0.0], "objectives": list(f)} for f in rng.random((front_size, m))],
        baselines={
            k: Solution(x=None, objectives={}, metrics={}, motion=v)
            for k, v in (baselines or {}).items()
        },
        history=history,
        study_extras=dict,
        optimizer={"kind": "moead"},
        objective_names=tuple(f"f{j + 1}" for j in range(m)),
    )


# ---------------------------------------------------------------------------------------------
# downsampling
# ---------------------------------------------------------------------------------------------
