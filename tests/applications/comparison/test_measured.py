"""
Tests of :mod:`virtspec_mi.applications.comparison.measured`: measured spectra, checked and read.

:meth:`MeasuredSpectrum.of` sorts, keeps every point and refuses what a measured fraction can
not be, naming the source, the column and the wavelength (a value beyond [0, 1] passes only
within its own uncertainty); :func:`read_measured` reads arrays, spectral distributions,
plain and headed tables (``;`` and tab separated with decimal commas), NetCDF and an earlier
result (its certified tolerance as the uncertainty); a file's gaps and stray rows are refused
by line, never dropped. ``tests/applications/comparison/test_comparison.py`` reads every
measured format through it on the way to a comparison.

References
----------
colour-science ``colour.io`` CSV spectral files; Baranoski et al. (2001), Sect. 5.
"""

from __future__ import annotations

import colour
import numpy as np
import pytest

from virtspec_mi.applications.comparison.measured import (
    MEASURED_SUFFIXES,
    MeasuredSpectrum,
    _split,
    check_quantity,
    read_measured,
)


def test_a_spectrum_is_sorted_and_kept_whole():
    spectrum = MeasuredSpectrum.of([600, 400, 500], [0.3, 0.1, 0.2], [0.01, 0.03, 0.02], source="leaf")
    np.testing.assert_array_equal(spectrum.wavelengths, [400, 500, 600])
    np.testing.assert_array_equal(spectrum.values, [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(spectrum.uncertainty, [0.03, 0.02, 0.01])  # moved with its points
    again = spectrum.with_uncertainty(0.05)
    np.testing.assert_array_equal(again.uncertainty, 0.05)
    assert spectrum.uncertainty[0] == 0.03 and again.values is spectrum.values


@pytest.mark.parametrize("arguments, keywords, message", [
    (([400, 500], [0.1]), {}, r"measured wavelengths and values must have one length \(got 2 and 1\)"),
    (([], []), {}, r"measured spectrum measured holds no points"),
    (([400, -5], [0.1, 0.2]), {}, r"measured wavelengths must be finite and > 0 nm"),
    (([400, 500], [0.1, np.nan]), {}, r"measured values must be finite"),
    (([400, 500], [10.0, 20.0]), {}, r"measured values must be fractions in \[0, 1\] \(got up to 20 in measured: "
                                     r"percentages\? divide by 100\)"),
    (([400, 400], [0.1, 0.2]), {}, r"measured wavelengths must be distinct"),
    (([400, 500, 600], [0.1, 1.05, 1.2]), {"source": "leaf.csv", "column": "R"},
     r"measured reflectance must lie in \[0, 1\] \(leaf.csv, column 'R': 1.05 at 500 nm is above 1; 2 such points\)"),
    (([400, 500], [0.1, 0.2], [0.01]), {}, r"one value per measured point \(2 in measured; got shape \(1,\)\)"),
    (([400, 500], [0.1, 0.2], -0.1), {}, r"measurement_uncertainty must be finite and >= 0"),
    (([400, 500], [0.1, 0.2], "small"), {}, r"measurement_uncertainty must be a number or one value per measured "
                                           r"point \(got 'small'\)"),
])
def test_what_a_measured_fraction_cannot_be_is_refused(arguments, keywords, message):
    with pytest.raises(ValueError, match=message):
        MeasuredSpectrum.of(*arguments, **keywords)


def test_noise_beyond_the_range_passes_within_its_uncertainty():
    spectrum = MeasuredSpectrum.of([400, 500], [-0.01, 1.02], 0.03)
    np.testing.assert_array_equal(spectrum.values, [-0.01, 1.02])
    with pytest.raises(ValueError, match=r"1.02 at 500 nm is above 1 by more than its uncertainty 0.01"):
        MeasuredSpectrum.of([400, 500], [-0.01, 1.02], 0.01)


def test_arrays_distributions_and_spectra_are_read():
    assert read_measured(([500, 400], [0.2, 0.1])).values.tolist() == [0.1, 0.2]
    sd = colour.SpectralDistribution({400: 0.1, 410: 0.2}, name="patch")
    read = read_measured(sd, "transmittance")
    assert read.source == "patch" and read.quantity == "transmittance" and read.uncertainty is None
    assert read_measured(read) is read
    with pytest.raises(ValueError, match=r"measured must be a file path, a colour.SpectralDistribution, "
                                         r".* \(got int\)"):
        read_measured(42)
    with pytest.raises(ValueError, match=r"quantity must be one of reflectance, transmittance, absorptance "
                                         r"\(got 'colour'\)"):
        check_quantity("colour")
    assert {".csv", ".txt", ".nc", ".json"} <= set(MEASURED_SUFFIXES)


def test_tables_plain_headed_and_in_a_locales_csv(tmp_path):
    plain = tmp_path / "plain.txt"
    plain.write_text("# a leaf\n500 0.2 0.01\n400 0.1 0.02\n")
    spectrum = read_measured(plain)
    np.testing.assert_array_equal(spectrum.wavelengths, [400, 500])
    np.testing.assert_array_equal(spectrum.uncertainty, [0.02, 0.01])
    headed = tmp_path / "headed.csv"
    headed.write_text("wavelength,reflectance,transmittance,transmittance_uncertainty\n400,0.1,0.5,0.02\n"
                      "500,0.2,0.4,0.03\n")
    transmittance = read_measured(headed, "transmittance")
    np.testing.assert_array_equal(transmittance.values, [0.5, 0.4])
    np.testing.assert_array_equal(transmittance.uncertainty, [0.02, 0.03])
    assert read_measured(headed).uncertainty is None
    locale = tmp_path / "locale.csv"
    locale.write_text("wavelength;reflectance\n400;0,12\n500;0,25\n")
    np.testing.assert_array_equal(read_measured(locale).values, [0.12, 0.25])
    assert _split("400\t0,5") == ["400", "0.5"] and _split("400,0.5") == ["400", "0.5"]
    assert _split("400  0.5") == ["400", "0.5"] and _split('"400";"0,5";x') == ["400", "0.5", "x"]


@pytest.mark.parametrize("text, message", [
    ("400,0.1\n500,\n", r"line 2: no reflectance value \(empty or NaN: '500,'\); give a number or remove the row"),
    ("400,0,52\n500,0,61\n", r"its numbers look written with decimal commas in a comma-separated file"),
    ("wavelength,reflectance\n400,0.1\n7,0.2\n500,0.3\n", r"line 3: '7,0.2' is not a row of a wavelength in nm"),
    ("400,0.1\nhello,0.2\n", r"line 2: expected numbers \(got 'hello,0.2'\)"),
    ("400,0.1,0.01,7\n500,0.2,0.01,7\n", r"plain rows must be wavelength,value\[,uncertainty\] \(got 4 columns"),
    ("wavelength,transmittance\n400,0.1\n", r"holds transmittance, no reflectance column"),
])
def test_a_files_faults_are_refused_by_line(tmp_path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        read_measured(path)


def test_files_that_are_not_there_or_of_no_format(tmp_path):
    with pytest.raises(ValueError, match=r"measured file not found: .*absent.csv"):
        read_measured(tmp_path / "absent.csv")
    with pytest.raises(ValueError, match=r"measured must end in one of .*\(got 'leaf.xlsx'\)"):
        read_measured(tmp_path / "leaf.xlsx")


def test_netcdf_spectra_and_their_gaps(tmp_path):
    import xarray as xr

    good = xr.Dataset({"reflectance": ("wavelength", [0.1, 0.2]), "uncertainty": ("wavelength", [0.01, 0.02])},
                      coords={"wavelength": [400.0, 500.0]})
    good.to_netcdf(tmp_path / "good.nc")
    spectrum = read_measured(tmp_path / "good.nc")
    np.testing.assert_array_equal(spectrum.uncertainty, [0.01, 0.02])
    gap = good.copy(deep=True)
    gap["reflectance"][1] = np.nan
    gap.to_netcdf(tmp_path / "gap.nc")
    with pytest.raises(ValueError, match=r"gap.nc: reflectance is NaN at 1 wavelength \(the first 500 nm, index 1\)"):
        read_measured(tmp_path / "gap.nc")


def test_a_certified_result_is_a_measured_spectrum_with_its_tolerance(mi):
    import virtspec_mi as vm

    result = vm.measure("diamond_collimated", wavelengths=[450, 650], rays=4000, seed=1)
    spectrum = read_measured(result, "transmittance")
    tolerance = result.spectrum("transmittance").tolerance
    np.testing.assert_array_equal(spectrum.uncertainty, tolerance)
    np.testing.assert_array_equal(spectrum.values, result.spectrum("transmittance").values)
