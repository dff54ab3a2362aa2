"""
Tests of :mod:`virtspec_mi.instruments.integrator`: the ``spectrophotometer`` Mitsuba integrator.

It reads its settings and its instrument's options from its parameters (a bad one refused
naming the plugin and the parameter), picks the instrument from ``instrument`` or from the
options given, and ``mi.render`` returns per wavelength ρ, τ and α of exactly ``spp`` rays
(adding up to 1 for a lossless specimen), the full reading kept; ``spp`` is checked; the
``mi.render`` wrapper lets only this integrator's ``ValueError`` through as itself.

References
----------
Mitsuba 3, ``mi.SamplingIntegrator`` (Python integrators), ``mi.render``.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.instruments import INSTRUMENTS


@pytest.fixture(scope="module")
def integrator(mi):
    """The module (it subclasses ``mi.SamplingIntegrator``: imported once Mitsuba's variant is set)."""

    from virtspec_mi.instruments import integrator

    return integrator


def test_the_instrument_is_named_or_found_from_its_options(integrator):
    instrument_of = integrator.instrument_of
    assert instrument_of({}) == next(iter(INSTRUMENTS)) == "hemispherical"
    assert instrument_of({"instrument": "gloss"}) == "gloss"
    assert instrument_of({"theta_o_bins": 9}) == "goniophotometer"  # a scene written before 'instrument'
    with pytest.raises(ValueError, match=r"instrument must be one of hemispherical, goniophotometer.* \(got 'lidar'\)"):
        instrument_of({"instrument": "lidar"})
    with pytest.raises(ValueError, match=r"the parameters are options of several instruments \(goniophotometer, "
                                         r"sphere, double_sphere\): name one with the parameter instrument"):
        instrument_of({"theta_o_bins": 9, "diameter": 150.0})


def test_spp_is_a_whole_number_of_rays(integrator):
    check_spp = integrator.check_spp
    assert check_spp(0) == 0 and check_spp(np.int64(500)) == 500 and check_spp(2**32 - 1) == 2**32 - 1
    for bad in (-1, 2**32, 1.5, True, "100"):
        with pytest.raises(ValueError, match=r"spectrophotometer: spp must be a whole number with 0 <= spp <= "
                                             r"4294967295 \(the rays per reading; 0: from the settings\) \(got "):
            check_spp(bad)


def test_parameters_are_read_and_refused_naming_the_plugin(mi, integrator):
    loaded = mi.load_dict({"type": "spectrophotometer", "mu": 0.01, "wavelengths": "500, 600", "seed": 4})
    assert isinstance(loaded, integrator.Spectrophotometer) and loaded.instrument.name == "hemispherical"
    assert loaded.settings.mu == 0.01 and loaded.settings.wavelengths == (500.0, 600.0)
    assert loaded.to_string().startswith("Spectrophotometer[hemispherical; ")
    with pytest.raises(Exception, match=r"spectrophotometer: mu must satisfy 0 < mu < 0.5 \(got 0.7\)"):
        mi.load_dict({"type": "spectrophotometer", "mu": 0.7})


def test_render_returns_the_fractions_of_spp_rays(mi):
    scene = mi.load_dict(vm.instrument_scene({"type": "simple_dielectric"},
                                             integrator={"type": "spectrophotometer", "wavelengths": "500, 600"}))
    table = np.array(mi.render(scene, spp=2000, seed=1))
    reading = scene.integrator().last_reading
    assert table.shape == (2, 3) and np.all(np.asarray(reading.rays) == 2000)
    np.testing.assert_allclose(table.sum(axis=1), 1.0, atol=1e-6)  # a lossless dielectric: rho + tau = 1
    np.testing.assert_allclose(table[:, 0], np.ravel(reading.reflectance), rtol=1e-6)
    assert np.all(np.rint(table[:, 0] * 2000) == np.ravel(reading.counts.reflected))
    again = np.array(mi.render(scene, spp=2000, seed=1))
    np.testing.assert_array_equal(again, table)  # the counts are a function of the seed


def test_the_wrapper_clears_only_this_integrators_value_errors(mi, integrator):
    clear_render_errors = integrator.clear_render_errors
    ours = mi.load_dict({"type": "spectrophotometer"})

    def render(scene, *args, **kwargs):
        try:
            raise kwargs.pop("cause")
        except Exception as cause:
            raise RuntimeError("error while performing a custom differentiable operation") from cause

    wrapped = clear_render_errors(render)
    assert clear_render_errors(wrapped) is wrapped and wrapped.clears_spectrophotometer_errors
    with pytest.raises(ValueError, match="^spp is bad$"):
        wrapped(None, integrator=ours, cause=ValueError("spp is bad"))
    with pytest.raises(RuntimeError, match="custom differentiable operation"):
        wrapped(None, integrator=ours, cause=TypeError("another error"))
    with pytest.raises(RuntimeError, match="custom differentiable operation"):
        wrapped(None, integrator=mi.load_dict({"type": "path"}), cause=ValueError("not ours"))
