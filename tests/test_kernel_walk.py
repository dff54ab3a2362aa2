"""Shared random-walk conventions: capped walks are counted apart, walk RNG streams."""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.kernel.walk import CAPPED_COMPONENT, walk_rng

from mirror_specimen import register_mirror


@pytest.fixture(scope="module")
def capping_bsdf(mi):
    """A test specimen: reports a capped walk when sample1 < 0.25, else reflects."""

    import drjit as dr

    def change(bs, weight, sample1, si, props):
        capped = sample1 < 0.25
        bs.sampled_component = dr.select(capped, mi.UInt32(CAPPED_COMPONENT), mi.UInt32(0))
        return bs, dr.select(capped, mi.Spectrum(0.0), weight)

    return register_mirror(mi, "capping_test", change)


def test_capped_walks_are_counted_in_no_tally(mi, capping_bsdf):
    scene = vm.instrument_scene({"type": capping_bsdf})
    with pytest.warns(RuntimeWarning, match="step cap"):
        reading = vm.measure(scene, theta_i=20, rays=40_000, wavelengths=[500, 600])
    n = reading.rays
    assert np.all(reading.capped > 0)
    assert np.all(reading.reflected + reading.capped == n)
    assert np.all(reading.absorbed == 0) and np.all(reading.transmitted == 0)
    # sample1 is uniform: P(capped) = 1/4, so the count is Binomial(N, 1/4); 6 sigma.
    assert np.all(np.abs(reading.capped / n - 0.25) < 6 * np.sqrt(0.25 * 0.75 / n))
    assert "step cap" in reading.summary()
    assert reading.as_dict()["capped"] == reading.capped.tolist()


def test_ordinary_specimens_have_no_capped_walks(diamond):
    reading = vm.measure(diamond, rays=10_000)
    assert reading.capped.sum() == 0
    assert reading.absorbed.sum() == 0


def test_walk_rng_is_a_function_of_the_samples(mi):
    import drjit as dr

    s1 = mi.Float([0.1, 0.1, 0.7])
    s2 = mi.Point2f([0.2, 0.2, 0.2], [0.3, 0.3, 0.3])
    a = walk_rng(s1, s2).next_float32()
    b = walk_rng(s1, s2).next_float32()
    dr.eval(a, b)
    a, b = np.array(a), np.array(b)
    assert np.array_equal(a, b)
    assert a[0] == a[1] and a[0] != a[2]
