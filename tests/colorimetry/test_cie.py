"""
Tests of virtspec_mi.colorimetry.cie, with the end-to-end ColorChecker check: a Mitsuba
``diffuse`` specimen whose reflectance is a ColorChecker patch spectrum, measured
380–780 nm, reproduces the patch's L*a*b* within ΔE2000 < 0.5.
"""

from __future__ import annotations

import colour
import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.colorimetry.cie import colorimetry

CHART = "ColorChecker N Ohta"


def _sweep_of(values, wavelengths, **kwargs):
    from dataclasses import replace

    from virtspec_mi.kernel.counts import Counts
    from virtspec_mi.geometry.disks import InstrumentGeometry
    from virtspec_mi.results.readings import Result
    from virtspec_mi.settings import Settings

    shape = (len(wavelengths), 1)
    counts = replace(Counts.zeros(shape), rays=np.full(shape, 10**6, dtype=np.int64),
                     reflected=np.round(np.asarray(values)[:, None] * 10**6).astype(np.int64))
    return Result(("wavelength", "theta_i"), {"wavelength": np.asarray(wavelengths, float), "theta_i": np.array([0.0])},
                  counts, None, Settings(wavelengths=wavelengths), InstrumentGeometry(8, 12.5, 100), 0.0)


def test_a_grey_spectrum_is_neutral_and_its_lightness_follows_y():
    wavelengths = np.arange(380.0, 781.0, 10.0)
    result = _sweep_of(np.full(len(wavelengths), 0.18), wavelengths)
    grey = colorimetry(result.to_sd())
    assert grey.XYZ[1] == pytest.approx(18.0, rel=1e-6)
    assert grey.Lab[0] == pytest.approx(116 * 0.18 ** (1 / 3) - 16, rel=1e-6)
    np.testing.assert_allclose(grey.Lab[1:], 0.0, atol=1e-9)
    # sRGB: chromatic adaptation from this white (xy from the 10 nm sums) to sRGB's D65 shifts < 1e-4
    np.testing.assert_allclose(grey.sRGB, grey.sRGB[0], atol=2e-4)
    assert grey.note == ""


def test_wavelengths_outside_the_cmfs_stay_in_the_data_but_not_in_the_colour():
    wavelengths = np.arange(300.0, 901.0, 10.0)
    values = np.where((wavelengths < 360) | (wavelengths > 830), 0.9, 0.3)  # out-of-range values differ
    result = _sweep_of(values, wavelengths)
    assert len(result.to_sd().wavelengths) == len(wavelengths)
    colour_ = colorimetry(result.to_sd())
    assert "left out of the colorimetry" in colour_.note and "300" in colour_.note
    assert colour_.wavelengths.min() >= 360 and colour_.wavelengths.max() <= 830
    assert colour_.XYZ[1] == pytest.approx(30.0, rel=1e-6)  # the 0.9 values were not used


def test_uneven_spectra_are_interpolated_with_a_note():
    wavelengths = np.array([400.0, 450.0, 520.0, 600.0, 700.0])  # not 1, 5, 10 or 20 nm apart
    grey = colorimetry(_sweep_of(np.full(5, 0.5), wavelengths).to_sd())
    assert "linearly interpolated to 1 nm" in grey.note
    assert grey.XYZ[1] == pytest.approx(50.0, rel=1e-6)
    np.testing.assert_allclose(grey.Lab[1:], 0.0, atol=1e-9)


def test_bad_colorimetry_input(diamond):
    result = vm.sweep(diamond, theta_i=[0, 10], wavelengths=[500, 600], rays=100)
    with pytest.raises(ValueError, match="theta_i must be given"):
        result.to_sd()
    with pytest.raises(ValueError, match="theta_i must be one of"):
        result.to_sd(theta_i=20)
    with pytest.raises(ValueError, match="quantity must be one of"):
        result.to_sd("colour", theta_i=0)
    with pytest.raises(ValueError, match="illuminant must be"):
        colorimetry(result.to_sd(theta_i=0), illuminant="D99")
    with pytest.raises(ValueError, match="at least two wavelengths"):
        vm.sweep(diamond, theta_i=[0], rays=10).to_sd()


def test_multi_spectral_distributions_hold_r_t_a(diamond):
    result = vm.sweep(diamond, theta_i=[45], wavelengths=[500, 600], rays=1000)
    msds = result.to_msds()
    assert list(msds.labels) == ["reflectance", "transmittance", "absorptance"]
    np.testing.assert_array_equal(msds.values[:, 1], result.transmittance[:, 0])


@pytest.mark.slow
def test_colorchecker_patches_are_reproduced_within_delta_e_2000_of_0_5(mi):
    """
    One sweep per patch (24 scenes, each one take_readings call over 41 wavelengths,
    380–780 nm every 10 nm, certified N = 105,967 rays each, collimated at 8°).
    Reference: the patch's own 5 nm spectrum through the same colorimetry.
    Each reading is within μ = 0.005 with probability ≥ 0.99 but the colour averages
    41 independent readings, so ΔE2000 of the noise is ~0.1 (max over 24 patches
    observed 0.19 at seed 1): 0.5 is the issue's requirement, not a tuned tolerance.
    """

    worst = 0.0
    for name, sd in colour.SDS_COLOURCHECKERS[CHART].items():
        spectrum = {"type": "regular", "wavelength_min": float(sd.wavelengths[0]),
                    "wavelength_max": float(sd.wavelengths[-1]), "values": ", ".join(f"{v:.6g}" for v in sd.values)}
        scene = vm.instrument_scene({"type": "diffuse", "reflectance": spectrum})
        result = vm.sweep(scene, theta_i=[8], wavelengths="380:780:10", beam="collimated", seed=1)
        measured, reference = colorimetry(result.to_sd()), colorimetry(sd)
        delta_e = float(colour.delta_E(measured.Lab, reference.Lab, method="CIE 2000"))
        assert delta_e < 0.5, (name, delta_e)
        worst = max(worst, delta_e)
    assert worst > 0  # the measurement is noisy: a zero would mean the reference was compared with itself


def test_a_sparse_spectrum_states_its_coverage_and_too_little_is_refused():
    from virtspec_mi.colorimetry.cie import MIN_COVERAGE, colorimetry

    wide = colorimetry(_sweep_of([0.5] * 31, np.arange(400, 701, 10)).to_sd())
    assert wide.coverage > 0.99 and "covering 99.8% of the colour-matching weight" in wide.summary()
    sparse = _sweep_of([0.4, 0.5, 0.6, 0.5, 0.4], [465, 550, 620, 700, 800]).to_sd()
    with pytest.raises(ValueError, match=r"covers 465-800 nm, only 70\.5% of the colour-matching weight"):
        colorimetry(sparse)
    assert MIN_COVERAGE == 0.95


def test_spectra_csv_needs_six_wavelengths(tmp_path):
    from virtspec_mi.results.io import write_spectra_csv

    with pytest.raises(ValueError, match="colour-science CSV spectra need at least 6 wavelengths"):
        write_spectra_csv(_sweep_of([0.1, 0.2, 0.3], [400, 500, 600]), tmp_path / "few.csv")
