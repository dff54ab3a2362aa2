"""
Tests of :mod:`virtspec_mi.applications.targets.indices`: normalised differences with exact intervals.

The interval over a box of the bands is the index's range over the box: no value of a dense
grid of the box falls outside it and its ends are attained at the two corners; the gradient is
the derivative (checked by central differences); the catalogue's bands are as published;
unknown names and band keys are refused naming the allowed ones.

References
----------
Rouse et al. (1974); Gamon et al. (1992); Gitelson et al. (1996); Montero et al. (2023).
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.applications.targets.bands import SENTINEL_2
from virtspec_mi.applications.targets.indices import INDICES, Index, index_definition

NDVI = INDICES["NDVI"]


def test_values_are_normalised_differences():
    assert Index.value(0.5, 0.1) == pytest.approx(0.4 / 0.6)
    assert Index.value(0.3, 0.3) == 0.0 and Index.value(1.0, 0.0) == 1.0 and Index.value(0.0, 0.2) == -1.0
    with pytest.raises(ValueError, match=r"a normalised difference needs A \+ B > 0 \(both bands dark\)"):
        Index.value(0.0, 0.0)


@pytest.mark.parametrize("a, b", [((0.40, 0.48), (0.05, 0.07)), ((0.1, 0.3), (0.2, 0.25)),
                                  ((-0.02, 0.03), (0.9, 1.05))])
def test_the_interval_is_the_range_over_the_clipped_box(a, b):
    low, high = NDVI.interval(a, b)
    grid_a = np.linspace(max(a[0], 0.0), min(a[1], 1.0), 41)
    grid_b = np.linspace(max(b[0], 0.0), min(b[1], 1.0), 41)
    A, B = np.meshgrid(grid_a, grid_b)
    values = (A - B) / (A + B)
    assert values.min() == pytest.approx(low, abs=1e-12) and values.max() == pytest.approx(high, abs=1e-12)
    assert low <= NDVI.value(np.mean(grid_a), np.mean(grid_b)) <= high


def test_an_interval_reaching_a_dark_corner_is_refused():
    with pytest.raises(ValueError, match=r"NDVI: the bands' intervals reach A \+ B = 0: no interval"):
        NDVI.interval((-0.1, 0.0), (-0.05, 0.0))  # both bands dark at once: clipped to A = B = 0
    assert NDVI.interval((-0.1, 0.2), (-0.05, 0.1)) == (-1.0, 1.0)  # a dark corner, but A + B > 0 elsewhere


def test_the_gradient_is_the_derivative():
    a, b, h = 0.42, 0.07, 1e-6
    da, db = NDVI.gradient(a, b)
    assert da == pytest.approx((Index.value(a + h, b) - Index.value(a - h, b)) / (2 * h), rel=1e-6)
    assert db == pytest.approx((Index.value(a, b + h) - Index.value(a, b - h)) / (2 * h), rel=1e-6)
    assert da > 0 > db


def test_the_catalogue_and_its_lookup():
    assert set(INDICES) == {"NDVI", "GNDVI", "NDRE", "PRI"}
    for index in INDICES.values():
        for band in (index.plus, index.minus):
            assert band in SENTINEL_2 or (isinstance(band, tuple) and band[0] < band[1])
    assert (NDVI.plus, NDVI.minus) == ("B08", "B04")
    assert index_definition("ndvi") is NDVI
    custom = index_definition("NDVI", {"minus": (650.0, 680.0)})
    assert (custom.plus, custom.minus, custom.reference) == ("B08", (650.0, 680.0), NDVI.reference)
    with pytest.raises(ValueError, match=r"index must be one of NDVI, GNDVI, NDRE, PRI \(got 'EVI'\)"):
        index_definition("EVI")
    with pytest.raises(ValueError, match=r"bands of an index are 'plus' \(A\) and 'minus' \(B\) .*\(got \['red'\]\)"):
        index_definition("NDVI", {"red": "B04"})
