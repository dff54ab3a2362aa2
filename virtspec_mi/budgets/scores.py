"""
Confidence intervals for the mean of bounded scores
===================================================

:func:`score_interval` is the two-sided empirical Bernstein interval of Maurer & Pontil
(2009, Theorem 4) for the mean of independent, identically distributed scores in [0, 1],
from the three numbers a tally keeps: the rays n, the sum of the scores and the sum of
their squares. With the unbiased sample variance
V = (n Σx² − (Σx)²)/(n (n − 1)), each side

    |x̄ − μ| ≤ √(2 V ln(4/δ) / n) + 7 ln(4/δ) / (3 (n − 1))

holds with probability ≥ 1 − δ/2 (Theorem 4 at δ/2, for x and for 1 − x: the variance is
the same), so the interval holds with probability ≥ 1 − δ, for every distribution on
[0, 1] and every n ≥ 2 fixed before the scores are drawn. Its width follows the scores'
spread, not their range: scores that vary little (an expected-value detector's,
:mod:`virtspec_mi.instruments.sphere.expected`) are certified with far fewer rays than
Hoeffding's bound (range only) or a binomial count of rare hits would need.

The scores are given as whole numbers q = S·x (``scale`` S), so the sums are exact; V is
computed from them in exact integer arithmetic and rounded up. ``below`` and ``above``
(≥ 0) widen the ends: for a quantity that lies in [E q/S − below, E q/S + above] (e.g. a
stochastic rounding's resolution below, a walk's truncation above).

References
----------
Maurer, A., Pontil, M. (2009). Empirical Bernstein bounds and sample variance
penalization. COLT 2009, Theorem 4.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from virtspec_mi.base.checks import check_delta, validated

__all__ = ["score_interval", "score_half_width"]


def score_half_width(n: int, variance: float, delta: float) -> float:
    """
    The half-width √(2 V ln(4/δ)/n) + 7 ln(4/δ)/(3(n − 1)) of :func:`score_interval` at
    ``n`` ≥ 2 scores of sample variance ``variance`` (e.g. to plan n from a variance).
    """

    if n < 2:
        return math.inf
    log = math.log(4.0 / delta)
    return math.sqrt(2.0 * max(variance, 0.0) * log / n) + 7.0 * log / (3.0 * (n - 1))


@validated(delta=check_delta)
def score_interval(total: Any, squares: Any, n: Any, delta: float, scale: int = 1,
                   below: float = 0.0, above: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """
    Two-sided ``1 − δ`` interval ``(lower, upper)`` of the mean of scores in [0, 1]
    (module docstring), NumPy-broadcast over ``total`` = Σq, ``squares`` = Σq² and ``n``
    (whole numbers, q = ``scale``·x in [0, scale]), widened by ``below`` and ``above``; clipped to [0, 1];
    (0, 1) where n < 2.
    """

    total, squares, n = np.broadcast_arrays(*(np.asarray(v) for v in (total, squares, n)))
    for name, values in (("total", total), ("squares", squares), ("n", n)):
        if values.size and (not np.issubdtype(values.dtype, np.integer) or np.any(values < 0)):
            raise ValueError(f"score_interval: {name} must be whole numbers >= 0")
    if not (isinstance(scale, (int, np.integer)) and scale >= 1):
        raise ValueError(f"score_interval: scale must be a whole number >= 1 (got {scale!r})")
    for name, value in (("below", below), ("above", above)):
        if not (value >= 0.0 and math.isfinite(value)):
            raise ValueError(f"score_interval: {name} must be a finite number >= 0 (got {value!r})")
    lower, upper = np.zeros(total.shape), np.ones(total.shape)
    for index in np.ndindex(*total.shape):
        rays, q, q2 = int(n[index]), int(total[index]), int(squares[index])
        if rays < 2:
            continue
        if q > scale * rays or q2 > scale * q or q * q > rays * q2:
            raise ValueError(f"score_interval: sums (total {q}, squares {q2}) are not those of {rays} scores in "
                             f"[0, {scale}]")
        spread = (rays * q2 - q * q) / (rays * (rays - 1) * scale * scale)  # exact integers, one rounding
        width = score_half_width(rays, float(np.nextafter(spread, np.inf)), delta)
        width = float(np.nextafter(width, np.inf))
        mean = q / (rays * scale)
        lower[index] = max(0.0, float(np.nextafter(mean - width - below, -np.inf)))
        upper[index] = min(1.0, float(np.nextafter(mean + width + above, np.inf)))
    return lower, upper
