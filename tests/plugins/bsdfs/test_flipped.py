"""
Tests of :mod:`virtspec_mi.plugins.bsdfs.flipped`: the ``virtspec_flipped`` BSDF mirrors its
nested BSDF's frame through the surface, for the incident and the outgoing direction.

Its ``eval``, ``pdf`` and ``eval_pdf`` at (ωi, ωo) are the nested BSDF's at the mirrored
directions; ``sample`` with the same random numbers gives the nested sample's direction
mirrored and the same weight; the nested specimen's protocol is kept; without a nested BSDF
it is refused with the parameter's name.

References
----------
Ward et al., the Radiance BSDF library, ``bsdf_m.c`` (back-side Klems vectors).
"""

from __future__ import annotations

import numpy as np
import pytest

NESTED = {"type": "roughdielectric", "alpha": 0.3, "int_ior": 1.5}


@pytest.fixture(scope="module")
def pair(mi):
    from virtspec_mi.plugins.bsdfs.flipped import PLUGIN_NAME

    return mi.load_dict({"type": PLUGIN_NAME, "nested": NESTED}), mi.load_dict(NESTED)


def directions(mi, seed: int, n: int = 64, up: bool = True):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) * (1 if up else -1) + 0.05 * (1 if up else -1)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return v


def interaction(mi, wi: np.ndarray):
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(wi[:, 0], wi[:, 1], wi[:, 2])
    si.wavelengths = mi.Spectrum(550.0)
    return si


def vector(mi, v: np.ndarray):
    return mi.Vector3f(v[:, 0], v[:, 1], v[:, 2])


def mirrored(v: np.ndarray) -> np.ndarray:
    return v * np.array([1.0, 1.0, -1.0])


def test_eval_and_pdf_are_the_nested_ones_at_the_mirrored_directions(mi, pair):
    flipped, nested = pair
    ctx = mi.BSDFContext()
    wi = directions(mi, 0)
    for wo in (directions(mi, 1), directions(mi, 2, up=False)):
        a = np.array(flipped.eval(ctx, interaction(mi, wi), vector(mi, wo)))
        b = np.array(nested.eval(ctx, interaction(mi, mirrored(wi)), vector(mi, mirrored(wo))))
        np.testing.assert_array_equal(a, b)
        assert np.any(b != 0)
        np.testing.assert_array_equal(np.array(flipped.pdf(ctx, interaction(mi, wi), vector(mi, wo))),
                                      np.array(nested.pdf(ctx, interaction(mi, mirrored(wi)),
                                                          vector(mi, mirrored(wo)))))
        value, pdf = flipped.eval_pdf(ctx, interaction(mi, wi), vector(mi, wo))
        np.testing.assert_array_equal(np.array(value), a)


def test_sample_mirrors_the_nested_sample(mi, pair):
    flipped, nested = pair
    ctx = mi.BSDFContext()
    wi = directions(mi, 3)
    rng = np.random.default_rng(4)
    s1, s2 = mi.Float(rng.random(64)), mi.Point2f(rng.random(64), rng.random(64))
    bs_f, w_f = flipped.sample(ctx, interaction(mi, wi), s1, s2)
    bs_n, w_n = nested.sample(ctx, interaction(mi, mirrored(wi)), s1, s2)
    np.testing.assert_array_equal(np.array(bs_f.wo.z), -np.array(bs_n.wo.z))
    np.testing.assert_array_equal(np.array(bs_f.wo.x), np.array(bs_n.wo.x))
    np.testing.assert_array_equal(np.array(w_f), np.array(w_n))


def test_flags_parameters_and_protocol_follow_the_nested_bsdf(mi, pair):
    flipped, nested = pair
    assert flipped.flags() == nested.flags() and flipped.component_count() == nested.component_count()
    assert any(key.startswith("nested.") for key in mi.traverse(flipped).keys())
    assert flipped.to_string().startswith("FlippedBSDF[nested=")
    slab = mi.load_dict({"type": "virtspec_flipped", "nested": {"type": "abm_b"}})
    assert slab.wavelength_range == (400.0, 2500.0)
    spectral = mi.load_dict({"type": "virtspec_flipped", "nested": {"type": "turbid_slab", "mu_a": {
        "type": "regular", "wavelength_min": 500, "wavelength_max": 600, "values": "1, 5"}}})
    spectral.check_wavelengths([500.0, 600.0])
    with pytest.raises(ValueError, match=r"wavelengths must satisfy 500 <= wavelength <= 600 nm for the specimen "
                                         r"turbid_slab: its 'mu_a'"):
        spectral.check_wavelengths([450.0])


def test_without_a_nested_bsdf_it_is_refused(mi):
    with pytest.raises(Exception, match="virtspec_flipped: give the BSDF to turn over as 'nested'"):
        mi.load_dict({"type": "virtspec_flipped"})
