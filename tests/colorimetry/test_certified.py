"""
Tests of :mod:`virtspec_mi.colorimetry.certified`: certified colour boxes from tristimulus tolerances.

The weights are the colorimetry's own, by its linearity: W·q equals ``colorimetry(q).XYZ``
on the ASTM E308 grid and on an irregular one, and the perfect reflector has Y = 100. A
box of zero width is the estimate (radii 0); every colour of a wider XYZ box (sampled at
a fixed seed) lies in the certified L*a*b* and sRGB boxes and within the ΔE radii; the box
never leaves what a spectrum in [0, 1] can give; a result that is not a certified
hemispherical reading gets the plain colour with the reason.

References
----------
CIE 015:2018, eqs. 7.1–7.3, 8.11–8.16; ASTM E308-22; IEC 61966-2-1:1999, eqs. (5)–(7).
"""

from __future__ import annotations

from types import SimpleNamespace

import colour
import numpy as np
import pytest

from virtspec_mi.colorimetry.certified import (
    CertifiedColour,
    _uncertifiable,
    certify_colour,
    colour_functionals,
    result_colour,
    tristimulus_weights,
)
from virtspec_mi.colorimetry.cie import colorimetry

GRID = np.arange(400.0, 701.0, 10.0)


def spectrum(grid: np.ndarray, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).uniform(0.05, 0.95, grid.size)


@pytest.mark.parametrize("grid", [GRID, np.array([380.0, 415.0, 452.5, 500.0, 551.0, 600.0, 633.0, 690.0, 780.0])])
def test_weights_reproduce_the_colorimetry(grid):
    weights = tristimulus_weights(grid)
    assert weights.shape == (3, grid.size)
    for seed in range(3):
        q = spectrum(grid, seed)
        expected = colorimetry(colour.SpectralDistribution(q, grid)).XYZ
        np.testing.assert_allclose(weights @ q, expected, rtol=1e-9, atol=1e-9)
    assert (weights @ np.ones(grid.size))[1] == pytest.approx(100.0, rel=1e-9)
    weights[0, 0] = -1.0  # a copy: the cached weights are not changed
    assert tristimulus_weights(grid)[0, 0] != -1.0


def test_functionals_are_x_y_z_of_the_quantity():
    functionals = colour_functionals(GRID, "transmittance")
    assert [f.name for f in functionals] == ["X", "Y", "Z"]
    np.testing.assert_array_equal(np.stack([f.weights for f in functionals]), tristimulus_weights(GRID))
    assert functionals[1].quantity == "transmittance"
    assert "tristimulus value Y of the transmittance" in functionals[1].long_name


def certified(tolerance: float, seed: int = 1) -> tuple[CertifiedColour, np.ndarray]:
    q = spectrum(GRID, seed)
    estimate = colorimetry(colour.SpectralDistribution(q, GRID))
    functionals = colour_functionals(GRID)
    return certify_colour(estimate, functionals, np.full(3, tolerance), 0.01, 12_345), q


def test_a_box_of_no_width_is_the_estimate():
    result, _ = certified(0.0)
    np.testing.assert_allclose(result.XYZ_interval[:, 0], result.XYZ, rtol=1e-12)
    np.testing.assert_allclose(result.XYZ_interval[:, 1], result.XYZ, rtol=1e-12)
    np.testing.assert_allclose(result.Lab_interval[:, 0], result.Lab, atol=1e-9)
    np.testing.assert_allclose(result.Lab_interval[:, 1], result.Lab, atol=1e-9)
    assert result.dE00_radius == pytest.approx(0.0, abs=1e-6) and result.dEab_radius == pytest.approx(0.0, abs=1e-6)


def test_every_colour_of_the_xyz_box_lies_in_the_certified_boxes():
    result, _ = certified(1.5)
    lower, upper = result.XYZ_interval[:, 0], result.XYZ_interval[:, 1]
    points = np.random.default_rng(2).uniform(lower, upper, size=(2000, 3))
    points = np.vstack([points, lower, upper])
    white = colour.XYZ_to_xy(np.array([f.weights.sum() for f in colour_functionals(GRID)]) / 100.0)
    lab = colour.XYZ_to_Lab(points / 100.0, white)
    assert np.all(lab >= result.Lab_interval[:, 0] - 1e-9) and np.all(lab <= result.Lab_interval[:, 1] + 1e-9)
    rgb = colour.XYZ_to_sRGB(points / 100.0, illuminant=white)
    assert np.all(rgb >= result.sRGB_interval[:, 0] - 1e-9) and np.all(rgb <= result.sRGB_interval[:, 1] + 1e-9)
    assert np.max(colour.delta_E(result.Lab, lab, method="CIE 2000")) <= result.dE00_radius + 1e-9
    assert np.max(np.linalg.norm(lab - result.Lab, axis=1)) <= result.dEab_radius + 1e-9
    assert result.dEab_radius > 0 and result.delta == 0.01 and result.rays == 12_345


def test_wider_tolerances_give_larger_radii_and_the_box_stays_reachable():
    radii = [certified(t)[0].dE00_radius for t in (0.2, 1.0, 5.0)]
    assert radii[0] < radii[1] < radii[2]
    huge, _ = certified(1e3)
    weights = tristimulus_weights(GRID)
    ceiling, floor = np.clip(weights, 0, None).sum(axis=1), np.clip(weights, None, 0).sum(axis=1)
    np.testing.assert_allclose(huge.XYZ_interval[:, 1], ceiling, rtol=1e-12)
    np.testing.assert_allclose(huge.XYZ_interval[:, 0], floor, rtol=1e-12)  # ASTM E308 weights dip below 0 a little
    assert np.all(floor <= 0) and np.all(floor > -1e-3)


def test_summary_and_dictionary_state_the_statement():
    result, _ = certified(0.5)
    text = result.summary()
    assert "certified at delta = 0.01 (all together), 12,345 rays: dE00 <= " in text
    assert "XYZ  in [" in text and "Lab  in [" in text and "sRGB in [" in text and "method: Hoeffding" in text
    data = result.as_dict()
    assert data["rays"] == 12_345 and np.shape(data["Lab_interval"]) == (3, 2)
    assert data["dE00_radius"] == result.dE00_radius
    np.testing.assert_array_equal(result.lab_box.lower, result.Lab_interval[:, 0])


def test_a_result_that_is_not_a_certified_hemispherical_reading_gets_the_reason():
    q = spectrum(GRID)
    other = SimpleNamespace(KIND="sphere reading", to_sd=lambda quantity, theta_i: colour.SpectralDistribution(q, GRID))
    plain = result_colour(other)
    assert not isinstance(plain, CertifiedColour)
    np.testing.assert_allclose(plain.XYZ, colorimetry(colour.SpectralDistribution(q, GRID)).XYZ)
    assert plain.note.endswith("no certified interval: intervals are derived for hemispherical readings only "
                               "(this is a sphere reading)")
    escaped = SimpleNamespace(KIND="hemispherical reading", certified=np.array([True, False]))
    assert _uncertifiable(escaped).startswith("some readings escaped their certificate")
    assert _uncertifiable(SimpleNamespace(KIND="hemispherical reading", certified=np.array([True]))) == ""
