"""Gradient-based local refinement of a solution: SciPy SLSQP with batched finite differences.

``refine(problem, x0)`` improves one decision vector of a single-objective problem locally:

1. The problem's **continuous relaxation** (:class:`Relaxation`) gives the space SLSQP moves in.
   A problem may define ``relaxation()`` (seed 000: the via points themselves, continuous, so
   that the integer grid and the dead band of its genes do not flatten the gradient); a
   continuous problem relaxes to itself; any other integer-coded problem is evaluated off the
   grid as it is and its result snapped back.
2. SLSQP minimises F with the constraints ``G <= 0`` as inequalities and the bounds, on the
   box scaled to ``[0, 1]``. Gradients of F and G are central finite differences computed as
   **one** batched ``evaluate`` of the ``2 m + 1`` points ``u, u ± h e_j`` per iterate (the
   stencil is shifted inside the box at a bound), so an iterate costs one vectorised call.
3. The end point and the best point seen on the way are brought back to the problem's decision
   space (``lower``: onto the grid for an integer-coded problem) and evaluated there; the best of
   them replaces ``x0`` only if it is better by the feasibility rule (feasible beats infeasible;
   then lower F; then lower violation).
4. For an integer-coded problem (``Relaxation.step``), rounding can undo SLSQP's gain: a
   steepest-descent climb on the grid follows (:func:`grid_polish`: the ``2 m`` neighbours
   ``z ± step e_j`` as one batch per round, at most ``max_iter`` rounds).

Refinement therefore never returns a worse or less feasible point than it was given.

Several objectives are not scalarised: ``refine`` returns ``x0`` with ``skipped`` set.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize as scipy_minimize

from legcore.optimizers.driver import Result
from legcore.problems.base import Problem, constraint_violation

__all__ = [
    "RefineResult", "Relaxation", "best_index", "better", "fd_gradients", "grid_polish", "refine",
    "refine_result", "relaxation_of",
]

FloatArray = NDArray[np.float64]
Evaluate = Callable[[FloatArray], tuple[FloatArray, FloatArray]]


@dataclass(frozen=True)
class Relaxation:
    """A continuous space standing in for a problem's decision space.

    Attributes:
        xl, xu: ``(m,)`` bounds of the relaxed variables ``z``.
        evaluate: ``Z (B, m) -> (F (B, n_obj), G (B, n_constr))``, the problem's objectives and
            constraints at relaxed points (equal to ``problem.evaluate`` at ``lift(x)``).
        lift: ``x (n_var,) -> z (m,)``, a decision vector in the relaxed space.
        lower: ``z (m,) -> x (n_var,)``, a valid decision vector of the problem (on its grid).
        step: ``(m,)`` the grid spacing of ``z`` for an integer-coded problem (``lift`` of a
            grid point ± ``step`` is a grid point again), None for a continuous one.
    """

    xl: FloatArray
    xu: FloatArray
    evaluate: Evaluate
    lift: Callable[[FloatArray], FloatArray]
    lower: Callable[[FloatArray], FloatArray]
    step: FloatArray | None = None


def relaxation_of(problem: Problem) -> Relaxation:
    """The problem's own ``relaxation()`` if it has one, else the decision box itself (with
    ``problem.snap`` bringing a point back onto the grid of an integer-coded problem)."""
    hook = getattr(problem, "relaxation", None)
    if callable(hook):
        relax = hook()
        if not isinstance(relax, Relaxation):
            raise TypeError(f"{problem.name}.relaxation() must return a Relaxation")
        return relax
    return Relaxation(
        xl=np.asarray(problem.xl, dtype=float),
        xu=np.asarray(problem.xu, dtype=float),
        evaluate=problem.evaluate,
        lift=lambda x: np.asarray(x, dtype=float).copy(),
        lower=lambda z: problem.snap(np.asarray(z, dtype=float)[None])[0],
        step=None if problem.resolution is None else np.asarray(problem.resolution, dtype=float),
    )


def better(f_a: float, cv_a: float, f_b: float, cv_b: float) -> bool:
    """True when (f_a, cv_a) is strictly better than (f_b, cv_b) by the feasibility rule."""
    feas_a, feas_b = cv_a <= 0.0, cv_b <= 0.0
    if feas_a != feas_b:
        return feas_a
    if feas_a:
        return f_a < f_b
    return cv_a < cv_b or (cv_a == cv_b and f_a < f_b)


def best_index(f: FloatArray, cv: FloatArray) -> int:
    """Row of the best of ``f (B,)`` / ``cv (B,)`` by the feasibility rule."""
    feasible = cv <= 0.0
    if feasible.any():
        return int(np.argmin(np.where(feasible, f, np.inf)))
    return int(np.lexsort((f, cv))[0])


def fd_gradients(
    evaluate: Evaluate, u: FloatArray, h: float = 1e-6, with_value: bool = True
) -> tuple[float, FloatArray, FloatArray, FloatArray]:
    """Value and central-difference gradients of F (first column) and G at ``u`` in ``[0, 1]^m``.

    One call of ``evaluate`` on the ``2 m + 1`` points ``u, u + h e_j, u - h e_j`` (each pair
    shifted inside ``[0, 1]`` at a bound, keeping the spacing ``2 h``); without ``u`` itself
    when ``with_value`` is False (``f`` is then NaN and ``g`` empty).

    Returns:
        ``f`` (float), ``g`` ``(n_constr,)``, ``df`` ``(m,)``, ``dG`` ``(n_constr, m)``.
    """
    m = u.size
    lo = np.clip(u - h, 0.0, 1.0 - 2.0 * h)
    hi = lo + 2.0 * h
    c = int(with_value)
    U = np.repeat(u[None], 2 * m + c, axis=0)
    idx = np.arange(m)
    U[c + idx, idx] = hi
    U[c + m + idx, idx] = lo
    F, G = evaluate(U)
    f = F[:, 0]
    step = hi - lo
    df = (f[c:c + m] - f[c + m:]) / step
    dG = ((G[c:c + m] - G[c + m:]) / step[:, None]).T
    if not with_value:
        return float("nan"), np.zeros(0), df, dG
    return float(f[0]), G[0].copy(), df, dG


@dataclass(frozen=True)
class RefineResult:
    """The outcome of :func:`refine` (objective values are the problem's F, minimised).

    Attributes:
        x: ``(n_var,)`` the refined decision vector (``x0`` itself if nothing better was found).
        f, cv: its objective and constraint violation.
        before, after: F of ``x0`` and of ``x``; ``cv_before`` the violation of ``x0``.
        relaxed_f, relaxed_cv: F and violation of the best point SLSQP met in the relaxed space
            (before ``lower``; for an integer-coded problem a bound the grid cannot beat only if
            SLSQP found the relaxed optimum), None when skipped.
        n_evals: rows evaluated (relaxed and real); elapsed_s: wall time (s).
        success: SLSQP's success flag; improved: ``x`` differs from ``x0``; skipped: refinement
            did not apply (several objectives); message: SLSQP's or the skip reason.
    """

    x: FloatArray
    f: float
    cv: float
    before: float
    after: float
    cv_before: float
    relaxed_f: float | None
    relaxed_cv: float | None
    n_evals: int
    elapsed_s: float
    success: bool
    improved: bool
    skipped: bool
    message: str

    def summary(self) -> dict[str, Any]:
        """The JSON record of a refinement (``result.optimizer["refine"]``)."""
        return {
            "before": self.before, "after": self.after, "cv_before": self.cv_before,
            "cv_after": self.cv, "relaxed": self.relaxed_f, "n_evals": self.n_evals,
            "elapsed_s": self.elapsed_s, "success": self.success, "improved": self.improved,
            "skipped": self.skipped, "message": self.message,
        }


def refine(
    problem: Problem,
    x0: FloatArray,
    *,
    max_iter: int = 100,
    h: float = 1e-6,
    ftol: float = 1e-10,
    relax: Relaxation | None = None,
) -> RefineResult:
    """Locally refine ``x0`` (``(n_var,)``) by SLSQP on the problem's continuous relaxation.

    Args:
        problem: a single-objective problem (several objectives: skipped, ``x0`` returned).
        x0: the start, a valid decision vector.
        max_iter: SLSQP iterations (each one batched evaluation of ``2 m + 1`` points, plus
            line-search points).
        h: finite-difference step on the box scaled to ``[0, 1]``.
        ftol: SLSQP's tolerance on F.
        relax: the relaxation to use (default :func:`relaxation_of`).
    """
    t0 = time.perf_counter()
    x0 = np.asarray(x0, dtype=float).copy()
    F0, G0 = problem.evaluate(x0[None])
    f0, cv0 = float(F0[0, 0]), float(constraint_violation(G0)[0])
    n_evals = 1
    if problem.n_obj != 1:
        return RefineResult(x0, f0, cv0, f0, f0, cv0, None, None, n_evals,
                            time.perf_counter() - t0, False, False, True,
                            f"skipped: {problem.n_obj} objectives (refine is single-objective)")
    relax = relax or relaxation_of(problem)
    span = np.asarray(relax.xu - relax.xl, dtype=float)
    free = span > 0.0
    scale = np.where(free, span, 1.0)

    def to_z(u: FloatArray) -> FloatArray:
        return relax.xl + np.clip(u, 0.0, 1.0) * scale * free

    def evaluate_u(U: FloatArray) -> tuple[FloatArray, FloatArray]:
        nonlocal n_evals
        n_evals += U.shape[0]
        F, G = relax.evaluate(relax.xl + np.clip(U, 0.0, 1.0) * scale * free)
        cv = constraint_violation(G)
        k = best_index(F[:, 0], cv)
        if better(float(F[k, 0]), float(cv[k]), best_seen[1], best_seen[2]):
            best_seen[:] = [U[k].copy(), float(F[k, 0]), float(cv[k])]
        return F, G

    best_seen: list[Any] = [None, np.inf, np.inf]
    # One-entry caches: SLSQP asks for F, G and their gradients at the same point in turn;
    # a line-search point costs one row, an accepted iterate one batch of 2 m (+ 1) rows.
    values: dict[bytes, tuple[float, FloatArray]] = {}
    grads: dict[bytes, tuple[FloatArray, FloatArray]] = {}

    def value(u: FloatArray) -> tuple[float, FloatArray]:
        key = u.tobytes()
        if key not in values:
            F, G = evaluate_u(u[None])
            values.clear()
            values[key] = (float(F[0, 0]), G[0].copy())
        return values[key]

    def grad(u: FloatArray) -> tuple[FloatArray, FloatArray]:
        key = u.tobytes()
        if key not in grads:
            known = key in values
            f, g, df, dG = fd_gradients(evaluate_u, u, h, with_value=not known)
            if not known:
                values.clear()
                values[key] = (f, g)
            grads.clear()
            grads[key] = (df, dG)
        return grads[key]

    u0 = np.where(free, (relax.lift(x0) - relax.xl) / scale, 0.0)
    u0 = np.clip(u0, 0.0, 1.0)
    constraints = []
    if problem.n_constr:
        constraints.append({"type": "ineq", "fun": lambda u: -value(_f64(u))[1],
                            "jac": lambda u: -grad(_f64(u))[1]})
    with np.errstate(all="ignore"):
        res = scipy_minimize(
            lambda u: value(_f64(u))[0], u0, jac=lambda u: grad(_f64(u))[0], method="SLSQP",
            bounds=[(0.0, 1.0)] * u0.size, constraints=constraints,
            options={"maxiter": int(max_iter), "ftol": ftol},
        )
    u_end = np.clip(np.asarray(res.x, dtype=float), 0.0, 1.0)
    evaluate_u(u_end[None])  # the end point may not have been evaluated
    relaxed_f, relaxed_cv = float(best_seen[1]), float(best_seen[2])

    Xc = np.stack([relax.lower(to_z(u_end)), relax.lower(to_z(best_seen[0]))])
    Fc, Gc = problem.evaluate(Xc)
    n_evals += Xc.shape[0]
    cvc = constraint_violation(Gc)
    k = best_index(Fc[:, 0], cvc)
    x, f, cv = x0, f0, cv0
    if better(float(Fc[k, 0]), float(cvc[k]), f0, cv0):
        x, f, cv = Xc[k].copy(), float(Fc[k, 0]), float(cvc[k])
    if relax.step is not None:  # rounding undid part of SLSQP's gain: climb on the grid
        z, fz, cvz, n = grid_polish(relax, relax.lift(x), f, cv, max_iter)
        n_evals += n
        xp = relax.lower(z)
        Fp, Gp = problem.evaluate(xp[None])
        n_evals += 1
        fp, cvp = float(Fp[0, 0]), float(constraint_violation(Gp)[0])
        if better(fp, cvp, f, cv):
            x, f, cv = xp, fp, cvp
    return RefineResult(
        x=x, f=f, cv=cv, before=f0, after=f, cv_before=cv0, relaxed_f=relaxed_f,
        relaxed_cv=relaxed_cv, n_evals=n_evals, elapsed_s=time.perf_counter() - t0,
        success=bool(res.success), improved=x is not x0, skipped=False, message=str(res.message),
    )


def grid_polish(
    relax: Relaxation, z: FloatArray, f: float, cv: float, max_rounds: int
) -> tuple[FloatArray, float, float, int]:
    """Steepest descent on the grid of an integer-coded problem from the grid point ``z``
    (value ``f``, violation ``cv``): each round evaluates the ``2 m`` neighbours ``z ± step e_j``
    as one batch and moves to the best if it is better by the feasibility rule.

    Returns:
        the final ``z``, its ``f`` and ``cv``, and the number of rows evaluated.
    """
    assert relax.step is not None
    m = z.size
    idx = np.arange(m)
    n_evals = 0
    for _ in range(max_rounds):
        Z = np.repeat(z[None], 2 * m, axis=0)
        Z[idx, idx] += relax.step
        Z[m + idx, idx] -= relax.step
        Z = np.clip(Z, relax.xl, relax.xu)
        F, G = relax.evaluate(Z)
        n_evals += Z.shape[0]
        cvs = constraint_violation(G)
        k = best_index(F[:, 0], cvs)
        if not better(float(F[k, 0]), float(cvs[k]), f, cv):
            break
        z, f, cv = relax.lift(relax.lower(Z[k])), float(F[k, 0]), float(cvs[k])
    return z, f, cv, n_evals


def _f64(u: Any) -> FloatArray:
    return np.ascontiguousarray(u, dtype=float)


def refine_result(
    problem: Problem, result: Result, max_iter: int = 100
) -> tuple[Result, dict[str, Any]]:
    """A finished run's ``result`` with its best replaced by the refined one when refinement
    improved it (single objective: the front is that point if feasible), and the refinement's
    record (:meth:`RefineResult.summary`) — ``optimizer.refine`` of a job."""
    r = refine(problem, np.asarray(result.x), max_iter=max_iter)
    if r.improved:
        feasible = r.cv <= 0.0
        result = dataclasses.replace(
            result, x=r.x, F=np.array([r.f]), cv=r.cv,
            front_X=r.x[None] if feasible else np.zeros((0, r.x.size)),
            front_F=np.array([[r.f]]) if feasible else np.zeros((0, 1)),
        )
    return result, r.summary()
