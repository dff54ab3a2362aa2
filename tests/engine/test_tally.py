"""
Tests of :mod:`virtspec_mi.engine.tally`: a run's exact tallies, taken, written and joined.

References
----------
Baranoski et al. (2001), eq. (2).
"""

from __future__ import annotations

import numpy as np

from virtspec_mi.engine.tally import Tally
from virtspec_mi.kernel.counts import Counts


def filled(size: int, start: int, bins: int = 2, pilot: bool = True) -> Tally:
    """Readings numbered ``start`` … with every tally a function of that number."""

    tally = Tally.zeros(size, bins=bins, sums=("hits",), pilot=pilot)
    number = np.arange(start, start + size)
    tally.counts.rays[:] = 100 * number
    tally.counts.reflected[:] = number
    if pilot:
        tally.pilot.rays[:] = 10 * number
    tally.bins[:] = number[:, None] * np.arange(1, bins + 1)
    tally.sums["hits"][:] = 7 * number
    return tally.with_seconds(float(size))


def test_zeros_have_the_shapes_asked_for():
    tally = Tally.zeros(4, bins=3, sums=("a", "b"), pilot=True)
    assert tally.counts.rays.shape == (4,) and tally.pilot.rays.shape == (4,)
    assert tally.bins.shape == (4, 3) and tally.bins.dtype == np.int64 and not tally.bins.any()
    assert set(tally.sums) == {"a", "b"} and tally.sums["a"].dtype == np.int64
    assert tally.seconds == 0.0
    plain = Tally.zeros(2)
    assert plain.pilot is None and plain.bins is None and plain.sums == {}


def test_take_selects_every_tally_in_order():
    tally = filled(4, 0)
    part = tally.take(np.array([3, 1]))
    np.testing.assert_array_equal(part.counts.rays, [300, 100])
    np.testing.assert_array_equal(part.pilot.rays, [30, 10])
    np.testing.assert_array_equal(part.bins, [[3, 6], [1, 2]])
    np.testing.assert_array_equal(part.sums["hits"], [21, 7])
    assert part.seconds == tally.seconds == 4.0


def test_put_writes_back_what_take_took():
    source = filled(4, 0)
    target = Tally.zeros(4, bins=2, sums=("hits",), pilot=True)
    index = np.array([2, 0, 3, 1])
    target.put(index, source.take(index))
    for name in Counts.names():
        np.testing.assert_array_equal(getattr(target.counts, name), getattr(source.counts, name))
    np.testing.assert_array_equal(target.pilot.rays, source.pilot.rays)
    np.testing.assert_array_equal(target.bins, source.bins)
    np.testing.assert_array_equal(target.sums["hits"], source.sums["hits"])
    assert target.seconds == 0.0  # seconds are the caller's


def test_put_without_a_pilot_on_either_side_leaves_it_alone():
    target = Tally.zeros(2, bins=2, sums=("hits",), pilot=True)
    target.put(np.array([0, 1]), filled(2, 5, pilot=False))
    assert not target.pilot.rays.any()
    np.testing.assert_array_equal(target.counts.rays, [500, 600])


def test_concatenate_joins_readings_and_adds_seconds():
    joined = Tally.concatenate([filled(2, 0), filled(3, 2)])
    np.testing.assert_array_equal(joined.counts.reflected, [0, 1, 2, 3, 4])
    np.testing.assert_array_equal(joined.pilot.rays, [0, 10, 20, 30, 40])
    np.testing.assert_array_equal(joined.bins[:, 1], [0, 2, 4, 6, 8])
    np.testing.assert_array_equal(joined.sums["hits"], [0, 7, 14, 21, 28])
    assert joined.seconds == 5.0
    one = filled(2, 0)
    assert Tally.concatenate([one]) is one


def test_with_seconds_is_a_new_tally_sharing_the_counts():
    tally = filled(2, 0)
    timed = tally.with_seconds(3)
    assert timed.seconds == 3.0 and isinstance(timed.seconds, float) and tally.seconds == 2.0
    assert timed.counts is tally.counts and timed.bins is tally.bins
