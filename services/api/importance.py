"""How much each decision variable explains of each objective, over a job's stored trials.

The estimator is scikit-learn's random forest (``RandomForestRegressor``: 64 trees, leaves of
at least 2 trials, seed 0) fitted per objective on the feasible trials (all trials when fewer
than ``MIN_TRIALS`` are feasible), and the importance is its mean decrease in impurity,
normalised to sum to 1 per objective — the quantity optuna-dashboard's default evaluator
(fANOVA over a random forest) approximates. At most ``MAX_TRIALS`` trials (evenly strided)
are used. Pure: arrays in, the response model out.
"""

from __future__ import annotations

import numpy as np

from services.api.trial_schemas import ImportanceOut
from services.api.trial_view import TrialSet, sample

#: Fewer feasible trials than this: fit on every trial instead.
MIN_TRIALS = 10
#: At most this many trials are fitted on (evenly strided over the stored ones).
MAX_TRIALS = 5000
N_TREES = 64

METHOD = (
    "scikit-learn RandomForestRegressor ({trees} trees, min_samples_leaf=2, seed 0) per "
    "objective, mean decrease in impurity normalised per objective, on {which} ({n} trials)"
)


def importance(trials: TrialSet) -> ImportanceOut:
    """The importance of each variable for each objective (zeros where it cannot be fitted:
    fewer than 2 usable trials, or an objective that does not vary)."""
    from sklearn.ensemble import RandomForestRegressor

    ev = trials.ev
    feasible = np.flatnonzero(ev.cv <= 0.0)
    which = "the feasible trials"
    idx = feasible
    if feasible.size < MIN_TRIALS:
        idx, which = np.arange(len(ev)), "every trial (fewer than 10 are feasible)"
    idx = sample(idx, MAX_TRIALS)
    X = ev.X[idx]
    n_var = ev.X.shape[1]
    rows: list[list[float]] = []
    for j in range(ev.F.shape[1]):
        y = ev.F[idx, j]
        ok = np.isfinite(y) & np.isfinite(X).all(axis=1)
        if ok.sum() < 2 or np.ptp(y[ok]) == 0.0 or n_var == 0:
            rows.append([0.0] * n_var)
            continue
        forest = RandomForestRegressor(
            n_estimators=N_TREES, min_samples_leaf=2, random_state=0, n_jobs=1
        )
        forest.fit(X[ok], y[ok])
        share = np.asarray(forest.feature_importances_, dtype=float)
        total = share.sum()
        rows.append((share / total if total > 0 else share).tolist())
    return ImportanceOut(
        job_id=trials.job_id,
        method=METHOD.format(trees=N_TREES, which=which, n=int(idx.size)),
        trials=int(idx.size),
        variables=trials.variables(),
        objectives=trials.objectives(),
        importance=rows,
    )


__all__ = ["MAX_TRIALS", "MIN_TRIALS", "importance"]
