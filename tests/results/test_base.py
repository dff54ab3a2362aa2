"""
Tests of virtspec_mi.results.base: the spectra (``spectrum``, ``to_sd``, ``colour``) of
every kind, with the clear error of what a kind cannot do.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from result_kinds import ANGLES, WAVELENGTHS


# --- spectra, colour and what a kind cannot do ---------------------------------------------


def test_a_sphere_spectrum_is_its_reading_with_a_tolerance_covering_the_interval(sphere):
    reading = sphere.sel(point=0, theta_i=8)
    spectrum = reading.spectrum()
    assert spectrum.quantity == "reading" and spectrum.measures == "reflectance" and spectrum.delta == 0.01
    np.testing.assert_array_equal(spectrum.values, reading.reading)
    interval = reading.reading_interval
    assert np.all(spectrum.values - spectrum.tolerance <= interval[:, 0] + 1e-15)
    assert np.all(spectrum.values + spectrum.tolerance >= interval[:, 1] - 1e-15)
    assert np.any(np.isclose(spectrum.values - spectrum.tolerance, interval[:, 0]) |
                  np.isclose(spectrum.values + spectrum.tolerance, interval[:, 1]))
    hemispherical = reading.spectrum("hemispherical")
    np.testing.assert_array_equal(hemispherical.values, reading.hemispherical)
    with pytest.raises(ValueError, match=r"quantity must be one of reading, corrected, hemispherical "
                                         r"\(got 'absorptance'\): a sphere reading has no R, T, A triple"):
        reading.spectrum("absorptance")
    with pytest.raises(ValueError, match="a integrating-sphere reading has no reflectance, transmittance and "
                                         "absorptance triple: use to_sd"):
        reading.to_msds()
    with pytest.raises(ValueError, match="carries no sphere description"):  # made from counts: no sphere kept
        reading.spectrum("corrected")


def test_a_gonio_result_gives_spectra_and_colour_through_its_r_and_t(gonio):
    sd = gonio.to_sd("transmittance", theta_i=50)
    np.testing.assert_array_equal(sd.values, gonio.result.transmittance[:, 1])
    assert gonio.colour(theta_i=10).XYZ.shape == (3,)
    np.testing.assert_allclose(gonio.colour(theta_i=10).XYZ, gonio.result.colour(theta_i=10).XYZ)
    np.testing.assert_array_equal(gonio.to_msds(theta_i=10).values, gonio.result.to_msds(theta_i=10).values)
    bin_sd = gonio.to_sd(theta_o=40, phi_o=100, theta_i=50)
    np.testing.assert_array_equal(bin_sd.values, gonio.brdf[:, 1, 1, 0])  # theta_o 30-60, phi_o 0-180
    with pytest.raises(ValueError, match=r"quantity must be one of reflectance, transmittance, absorptance "
                                         r"\(got 'brdf'\): a goniophotometer reading's spectra are its R, T and A"):
        gonio.spectrum("brdf")


def test_every_kind_colours_its_first_quantity(hemispherical, gonio, sphere):
    colours = [hemispherical.sel(theta_i=0, **{"specimen.thickness": 1e-4}).colour(),
               gonio.colour(theta_i=10), sphere.sel(point=0, theta_i=8).colour()]
    for colour in colours:
        assert colour.XYZ.shape == (3,) and np.all(np.isfinite(colour.Lab))
    sphere_sd = sphere.sel(point=0, theta_i=8).to_sd()
    assert sphere_sd.name == "reading theta_i=8"
    np.testing.assert_array_equal(sphere_sd.values, sphere.reading[:, 0, 0])


def test_wavelengths_and_angles_of_the_fixtures():
    assert WAVELENGTHS == [400.0, 550.0, 700.0] and ANGLES == [0.0, 30.0, 60.0]
    assert vm.Result.QUANTITIES == ("reflectance", "transmittance", "absorptance")
