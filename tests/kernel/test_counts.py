"""
Tests of :mod:`virtspec_mi.kernel.counts`: exact ray counts by name.

Every ray has one fate: ``absorbed`` is what the reflected, transmitted, capped and
invalid rays leave of ``rays``; the record keeps its fields by name through selection,
concatenation and writes in place.

References
----------
Baranoski et al. (2001), eq. (2) and Sect. 3.
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.kernel.counts import DIRECTION_TOLERANCE, QUANTITIES, WEIGHT_ROUNDING, Counts, Fate


def example() -> Counts:
    """Three readings of 100, 200 and 50 rays."""

    counts = Counts.zeros(3)
    counts.rays[:] = [100, 200, 50]
    counts.reflected[:] = [40, 10, 0]
    counts.transmitted[:] = [30, 150, 25]
    counts.capped[:] = [5, 0, 1]
    counts.invalid_directions[:] = [1, 0, 0]
    counts.specular_reflected[:] = [4, 10, 0]
    counts.largest_weight[:] = [np.nan, 1.5, np.nan]
    return counts


def test_fates_are_the_kernel_codes():
    assert [int(f) for f in Fate] == [0, 1, 2, 3, 4]
    assert Fate(1) is Fate.REFLECTED and Fate(4) is Fate.INVALID
    assert QUANTITIES == ("reflectance", "transmittance", "absorptance")
    assert 0 < WEIGHT_ROUNDING < 1e-3 and 0 < DIRECTION_TOLERANCE < 1e-2


def test_zeros_are_int64_with_no_weight_seen():
    counts = Counts.zeros((2, 3))
    for name in Counts.names():
        value = getattr(counts, name)
        assert value.shape == (2, 3)
        if name == "largest_weight":
            assert np.all(np.isnan(value))
        else:
            assert value.dtype == np.int64 and not value.any()


def test_absorbed_is_what_no_other_fate_takes():
    counts = example()
    np.testing.assert_array_equal(counts.absorbed, [24, 40, 24])
    total = sum(counts.count(fate) for fate in Fate)
    np.testing.assert_array_equal(total, counts.rays)
    np.testing.assert_array_equal(counts.count(Fate.CAPPED), [5, 0, 1])
    np.testing.assert_array_equal(counts.count(3), counts.capped)
    with pytest.raises(ValueError):
        counts.count(7)


def test_map_concatenate_and_put_keep_fields_by_name():
    counts = example()
    picked = counts.map(lambda v: v[[2, 0]])
    np.testing.assert_array_equal(picked.rays, [50, 100])
    np.testing.assert_array_equal(picked.absorbed, [24, 24])
    both = Counts.concatenate([counts, picked])
    assert both.rays.shape == (5,)
    np.testing.assert_array_equal(both.transmitted, [30, 150, 25, 25, 30])
    assert Counts.concatenate([counts]) is counts
    target = Counts.zeros(5)
    target.put(np.array([4, 1]), picked)
    np.testing.assert_array_equal(target.rays, [0, 100, 0, 0, 50])
    assert np.isnan(target.largest_weight).all()
    target.add(np.array([4, 1]), picked)  # added where put wrote: twice the counts
    np.testing.assert_array_equal(target.rays, [0, 200, 0, 0, 100])
    for weights in ([1.5, np.nan], [1.2, 2.5]):  # readings 4 and 1: the larger weight is kept; NaN (none) loses
        weighed = picked.map(np.copy)
        weighed.largest_weight[:] = weights
        target.add(np.array([4, 1]), weighed)
    np.testing.assert_array_equal(target.largest_weight, [np.nan, 2.5, np.nan, np.nan, 1.5])
    assert counts.rays[0] == 100  # the source is not changed


def test_as_dict_and_names():
    counts = example()
    names = Counts.names()
    assert names[0] == "rays" and "absorbed" not in names and len(set(names)) == len(names) == 10
    as_dict = counts.as_dict()
    assert set(as_dict) == set(names) | {"absorbed"}
    np.testing.assert_array_equal(as_dict["absorbed"], counts.absorbed)
