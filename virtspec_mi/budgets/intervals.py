"""
Confidence intervals for ray counts
===================================

:func:`clopper_pearson` gives the exact (Clopper–Pearson) two-sided confidence
interval of a binomial proportion from k successes in n trials: it covers the true
proportion with probability at least ``1 − δ`` for every proportion and every n
(equal tails of δ/2, from the beta quantiles). Every :class:`virtspec_mi.Result`
carries one for its reflectance, transmittance and absorptance, at the δ of each
quantity; the two-stage ray budget (:mod:`virtspec_mi.budgets.twostage`) sizes its second
batch from the pilot's interval.

References
----------
Clopper, C.J., Pearson, E.S. (1934). The use of confidence or fiducial limits
illustrated in the case of the binomial. Biometrika 26, 404–413.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from virtspec_mi.base.checks import check_delta, validated

__all__ = ["clopper_pearson", "clopper_pearson_each"]


@validated(delta=check_delta)
def clopper_pearson(k: Any, n: Any, delta: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Exact two-sided ``1 − δ`` confidence interval ``(lower, upper)`` of a binomial
    proportion from ``k`` successes in ``n`` trials (NumPy-broadcast, vectorised).

    ``lower = B⁻¹(δ/2; k, n − k + 1)`` (0 when k = 0) and
    ``upper = B⁻¹(1 − δ/2; k + 1, n − k)`` (1 when k = n), with B⁻¹ the beta quantile.
    δ is checked here, once; callers holding a validated δ (the two-stage sizing, the
    goniophotometer's bands) call ``clopper_pearson.unchecked``. The counts are checked on
    every call: they are the caller's contract (tallies of n rays).

    Examples
    --------
    >>> lower, upper = clopper_pearson(0, 2000, 0.001)
    >>> float(lower), round(float(upper), 6)
    (0.0, 0.003793)
    """

    k, n = np.broadcast_arrays(np.asarray(k, dtype=np.float64), np.asarray(n, dtype=np.float64))
    if np.any(n < 1) or np.any(k < 0) or np.any(k > n) or np.any(k != np.floor(k)):
        raise ValueError("clopper_pearson needs whole counts with 0 <= k <= n and n >= 1")
    return _beta_bounds(k, n, delta)


def clopper_pearson_each(k: Any, n: Any, delta: Any) -> tuple[np.ndarray, np.ndarray]:
    """
    :func:`clopper_pearson` with a δ per element (the cells of a table carry their own
    share of δ): the same beta quantiles, broadcast over ``delta`` too.
    """

    k, n, delta = np.broadcast_arrays(np.asarray(k, dtype=np.float64), np.asarray(n, dtype=np.float64),
                                      np.asarray(delta, dtype=np.float64))
    if np.any(n < 1) or np.any(k < 0) or np.any(k > n) or not np.all((delta > 0) & (delta < 1)):
        raise ValueError("clopper_pearson_each needs whole counts 0 <= k <= n, n >= 1 and 0 < delta < 1")
    return _beta_bounds(k, n, delta)


def _beta_bounds(k: np.ndarray, n: np.ndarray, delta: Any) -> tuple[np.ndarray, np.ndarray]:
    """The Clopper–Pearson bounds of checked counts: the beta quantiles at δ/2 (0 at k = 0, 1 at k = n)."""

    from scipy.special import betainccinv, betaincinv  # scipy.stats would add ~1 s to a cold start

    with np.errstate(invalid="ignore"):
        lower = np.where(k > 0, betaincinv(np.maximum(k, 1), n - k + 1, delta / 2), 0.0)
        upper = np.where(k < n, betainccinv(k + 1, np.maximum(n - k, 1), delta / 2), 1.0)
    return lower, upper
