"""
Tests of :mod:`virtspec_mi.applications.comparison.result`: a result held to a measured spectrum.

A reading with exact counts (so its values and certified tolerances are known) is compared
with spectra built from them: the measured values are interpolated linearly onto the result's
wavelengths inside the measured range (the others left out and listed), a point is within
when |simulated − measured| ≤ certified μ' + u, exactly the moved points are flagged, the
statistics are those of the residuals, ΔE2000 is that of colour-science on the two spectra
(not computed for one point or an absorptance), and the comparison's files rebuild it.

References
----------
Baranoski et al. (2001), Sect. 5; CIE 015:2018, §8.3 (CIEDE2000).
"""

from __future__ import annotations

from dataclasses import replace

import colour
import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.applications.comparison.result import Comparison, compare
from virtspec_mi.colorimetry.cie import colorimetry
from virtspec_mi.kernel.counts import Counts

WAVELENGTHS = np.arange(400.0, 701.0, 20.0)  # 16 wavelengths
RAYS = 10**6


def reading(values, wavelengths=WAVELENGTHS, violations=0) -> vm.Result:
    """A one-angle reading of given reflectance with exact counts."""

    shape = (len(wavelengths), 1)
    counts = replace(Counts.zeros(shape), rays=np.full(shape, RAYS, dtype=np.int64),
                     reflected=np.round(np.asarray(values)[:, None] * RAYS).astype(np.int64),
                     weight_violations=np.full(shape, violations, dtype=np.int64))
    return vm.Result(("wavelength", "theta_i"), {"wavelength": np.asarray(wavelengths, float),
                                                 "theta_i": np.array([8.0])},
                     counts, None, vm.Settings(wavelengths=tuple(wavelengths), theta_i=8.0),
                     vm.InstrumentGeometry(8, 12.5, 100), 0.0, scene="sha256:0123456789abcdef")


VALUES = 0.2 + 0.5 * (WAVELENGTHS - 400.0) / 300.0  # a linear reflectance 0.2 … 0.7


@pytest.fixture(scope="module")
def result():
    return reading(VALUES)


def test_the_same_spectrum_is_within_everywhere(result):
    comparison = compare(result, (WAVELENGTHS, VALUES))
    assert isinstance(comparison, Comparison)
    assert comparison.points_within == 16 and comparison.share_within == 1.0
    assert comparison.rmse == pytest.approx(0.0, abs=1e-6) and comparison.delta_E == pytest.approx(0.0, abs=1e-3)
    assert comparison.interpolated == 0 and comparison.left_out.size == 0
    np.testing.assert_allclose(comparison.certified_mu, result.spectrum("reflectance").tolerance)


def test_exactly_the_moved_points_are_flagged(result):
    measured = VALUES.copy()
    mu = result.spectrum("reflectance").tolerance
    measured[3] += 2 * mu[3]
    measured[9] += 3 * mu[9]
    measured[5] += 0.5 * mu[5]
    comparison = compare(result, (WAVELENGTHS, measured))
    assert np.flatnonzero(~comparison.within).tolist() == [3, 9]
    assert comparison.largest_difference == pytest.approx((3 * mu[9], WAVELENGTHS[9]), rel=1e-5)
    np.testing.assert_allclose(comparison.residuals, VALUES - measured, atol=1e-6)
    assert comparison.rmse == pytest.approx(float(np.sqrt(np.mean((VALUES - measured) ** 2))), abs=1e-6)
    # an uncertainty as large as the move brings them within
    widened = compare(result, (WAVELENGTHS, measured), measurement_uncertainty=3 * mu.max())
    assert widened.points_within == 16


def test_measured_values_are_interpolated_and_the_rest_left_out(result):
    coarse = np.array([450.0, 550.0, 650.0])
    comparison = compare(result, (coarse, 0.2 + 0.5 * (coarse - 400.0) / 300.0))
    np.testing.assert_array_equal(comparison.wavelengths, WAVELENGTHS[(WAVELENGTHS >= 450) & (WAVELENGTHS <= 650)])
    np.testing.assert_array_equal(comparison.left_out, [400.0, 420.0, 440.0, 660.0, 680.0, 700.0])
    np.testing.assert_allclose(comparison.measured, 0.2 + 0.5 * (comparison.wavelengths - 400.0) / 300.0)
    assert comparison.interpolated == 10 and comparison.interpolation_distance == 50.0  # 500 nm
    with pytest.raises(ValueError, match=r"the result's wavelengths \(400-700 nm\) lie outside the measured range "
                                         r"800-900 nm of measured: nothing to compare"):
        compare(result, ([800.0, 900.0], [0.1, 0.2]))


def test_delta_e_is_colour_sciences_or_says_why_not(result):
    measured = VALUES * 0.9
    comparison = compare(result, (WAVELENGTHS, measured))
    simulated = colorimetry(colour.SpectralDistribution(comparison.simulated, WAVELENGTHS)).Lab
    other = colorimetry(colour.SpectralDistribution(measured, WAVELENGTHS)).Lab
    assert comparison.delta_E == pytest.approx(float(colour.delta_E(simulated, other, method="CIE 2000")))
    one = compare(result, ([500.0, 510.0], [0.4, 0.4]))
    assert np.isnan(one.delta_E) and "at least two wavelengths (1 compared)" in one.delta_E_note
    with pytest.raises(ValueError, match=r"illuminant must be a name of colour.SDS_ILLUMINANTS"):
        compare(result, (WAVELENGTHS, VALUES), illuminant="sunset")


def test_an_uncertified_point_is_never_within():
    broken = reading(VALUES, violations=1)
    comparison = compare(broken, (WAVELENGTHS, VALUES))
    assert not comparison.certified.any() and comparison.points_within == 0 and np.isnan(comparison.share_within)


def test_the_files_rebuild_the_comparison(result, tmp_path):
    comparison = compare(result, (WAVELENGTHS, VALUES * 1.01, np.full(16, 0.002)))
    back = vm.read_result(comparison.write(tmp_path / "comparison.json"))
    assert isinstance(back, Comparison)
    np.testing.assert_array_equal(back.within, comparison.within)
    np.testing.assert_allclose(back.measured, comparison.measured)
    assert back.delta_E == pytest.approx(comparison.delta_E)
    assert "residuals" in comparison.to_dataset() and comparison.summary()


def test_what_is_no_result_is_refused():
    with pytest.raises(ValueError, match=r"result must be a virtspec-mi result .* \(got list\)"):
        compare([0.1, 0.2], (WAVELENGTHS, VALUES))
