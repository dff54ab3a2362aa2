"""Shared random-walk conventions: capped walks are counted apart, walk RNG streams."""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.kernel.walk import CAPPED_COMPONENT, walk_rng


@pytest.fixture(scope="module")
def capping_bsdf(mi):
    """A test specimen: reports a capped walk when sample1 < 0.25, else reflects."""

    import drjit as dr

    class Capping(mi.BSDF):
        def __init__(self, props):
            super().__init__(props)
            self.m_flags = mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide

        def sample(self, ctx, si, sample1, sample2, active=True):
            capped = sample1 < 0.25
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = mi.reflect(si.wi)
            bs.pdf = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DeltaReflection)
            bs.sampled_component = dr.select(capped, mi.UInt32(CAPPED_COMPONENT), mi.UInt32(0))
            return bs, dr.select(capped, mi.Spectrum(0.0), mi.Spectrum(1.0))

        def eval(self, ctx, si, wo, active=True):
            return mi.Spectrum(0.0)

        def pdf(self, ctx, si, wo, active=True):
            return mi.Float(0.0)

        def traverse(self, callback):
            pass

    mi.register_bsdf("capping_test", lambda props: Capping(props))
    return "capping_test"


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
