"""
Rays for a ratio of two proportions to a tolerance (virtspec_mi.budgets.ratio): the
interval is the extreme combinations of two Clopper–Pearson intervals at δ/2, the sizing
gives the least N whose expected counts at the pilot box's widest corner meet the
tolerance, and what no number of rays can promise is refused with its reason.
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.budgets.ratio import MOST_RATIO_RAYS, ratio_half_width, ratio_interval, ratio_rays


def test_the_interval_is_the_extreme_combinations_of_the_two_fractions():
    low1, high1 = clopper_pearson(300, 10_000, 0.005)
    low2, high2 = clopper_pearson(600, 10_000, 0.005)
    interval = ratio_interval(300, 10_000, 600, 10_000, 0.99, 0.01)
    assert interval == pytest.approx([0.99 * low1 / high2, 0.99 * high1 / low2])
    half = ratio_half_width(300, 10_000, 600, 10_000, 0.99, 0.01)
    assert half == pytest.approx(max(0.495 - interval[0], interval[1] - 0.495))
    assert np.isinf(ratio_half_width(3, 10, 0, 10, 1.0, 0.01))  # no light with the standard: no bound


def test_the_rays_are_the_least_that_meet_the_tolerance_at_the_widest_corner():
    k1, k2, n1, delta, pilot_delta = 1_340, 2_970, 50_000, 0.01, 0.001
    n = int(ratio_rays(k1, k2, n1, 0.005, 0.99, delta, pilot_delta)[0])
    _, p1 = clopper_pearson(k1, n1, pilot_delta / 2)
    p2, _ = clopper_pearson(k2, n1, pilot_delta / 2)

    def half(rays: int) -> float:
        return float(ratio_half_width(np.round(p1 * rays), rays, np.round(p2 * rays), rays, 0.99, delta))

    assert half(n) <= 0.005 < half(n - 1)
    assert ratio_rays(k1, k2, n1, 0.01, 0.99, delta, pilot_delta)[0] < n  # a wider tolerance: fewer rays
    many = ratio_rays(10 * k1, 10 * k2, 10 * n1, 0.005, 0.99, delta, pilot_delta)[0]
    assert many < n  # a longer pilot: a tighter box, fewer rays


def test_readings_are_sized_each_and_what_cannot_be_promised_is_refused():
    rays = ratio_rays([500, 5_000], [1_000, 10_000], 50_000, 0.01, 1.0, 0.01, 0.001)
    assert rays[0] > rays[1]  # the dimmer reading needs more
    with pytest.raises(ValueError, match="saw no light reach the detector with the standard"):
        ratio_rays([10], [0], 1_000, 0.01, 1.0, 0.01, 0.001)
    with pytest.raises(ValueError, match=f"needs more than {MOST_RATIO_RAYS:,} rays"):
        ratio_rays([1], [1], 1_000_000, 1e-6, 1.0, 0.01, 0.001)
