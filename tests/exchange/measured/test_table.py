"""CSV tables of many spectra (EcoSIS style), one column or one row per sample, read back."""

from __future__ import annotations

import numpy as np
import pytest

from measured_files import write_columns, write_rows
from virtspec_mi.exchange.measured import MeasuredFile, format_for, read_samples
from virtspec_mi.exchange.measured.table import layout

WAVELENGTHS = np.array([400.0, 500.0, 600.0, 700.0])
SPECTRA = {"plot 1": [0.05, 0.10, 0.07, 0.40], "plot 2": [0.04, 0.12, 0.06, 0.45], "plot 3": [0.03, 0.11, 0.05, 0.5]}


def test_one_column_per_sample_needs_its_quantity_stated(tmp_path):
    path = write_columns(tmp_path / "c.csv", WAVELENGTHS, SPECTRA)
    assert layout(path) == "columns" and format_for(path).name == "table"
    with pytest.raises(ValueError, match=r"c.csv: it does not tell .*measured_quantity="):
        read_samples(path)
    samples = read_samples(MeasuredFile(path, quantity="reflectance"))
    assert samples.labels == tuple(SPECTRA)
    np.testing.assert_allclose(samples.wavelengths, WAVELENGTHS)
    np.testing.assert_allclose(samples.values, list(SPECTRA.values()))


def test_one_row_per_sample_with_a_quantity_column_and_micrometres_in_the_name(tmp_path):
    path = write_rows(tmp_path / "r.csv", WAVELENGTHS, SPECTRA, quantity="transmittance")
    samples = read_samples(path)
    assert layout(path) == "rows" and samples.quantity == "transmittance" and samples.labels == tuple(SPECTRA)
    assert samples.metadata[0]["species"] == "Glycine max"
    np.testing.assert_allclose(samples.values, list(SPECTRA.values()))
    micro = write_columns(tmp_path / "um.csv", WAVELENGTHS / 1000, SPECTRA, wavelength_name="wavelength (um)")
    np.testing.assert_allclose(read_samples(MeasuredFile(micro, quantity="reflectance")).wavelengths, WAVELENGTHS)


def test_percentages_are_refused_unless_stated(tmp_path):
    path = write_columns(tmp_path / "p.csv", WAVELENGTHS, {k: 100 * np.array(v) for k, v in SPECTRA.items()})
    with pytest.raises(ValueError, match=r"p.csv: its values reach 50 .*measured_scale='percent'"):
        read_samples(MeasuredFile(path, quantity="reflectance"))
    samples = read_samples(MeasuredFile(path, quantity="reflectance", scale="percent"))
    np.testing.assert_allclose(samples.values, list(SPECTRA.values()))


def test_single_spectrum_csvs_are_not_claimed(tmp_path):
    for text in ("wavelength,reflectance\n400,0.1\n", "wavelength,reflectance,transmittance\n400,0.1,0.2\n",
                 "400,0.1,0.01\n500,0.2,0.01\n", "wavelength,leaf\n400,0.1\n",
                 '# virtspec-mi result {"kind": "gonio"}\nwavelength,theta_o,phi_o,brdf\n400,5,10,0.1\n'):
        (tmp_path / "s.csv").write_text(text)
        assert format_for(tmp_path / "s.csv") is None, text


def test_a_cut_row_and_a_bad_number_are_refused(tmp_path):
    path = write_rows(tmp_path / "r.csv", WAVELENGTHS, SPECTRA, quantity="reflectance")
    path.write_text(path.read_text()[:-15])
    with pytest.raises(ValueError, match=r"r.csv: row 4 has \d fields, the header 7"):
        read_samples(path)
    path = write_columns(tmp_path / "x.csv", WAVELENGTHS, SPECTRA)
    path.write_text(path.read_text().replace("0.400000", "n/a"))
    with pytest.raises(ValueError, match=r"x.csv: row 5, column 'plot 1': expected a number \(got 'n/a'\)"):
        read_samples(MeasuredFile(path, quantity="reflectance"))


def test_empty_cells_are_missing_values_of_that_sample(tmp_path):
    path = write_columns(tmp_path / "m.csv", WAVELENGTHS, SPECTRA)
    path.write_text(path.read_text().replace("0.120000", ""))
    samples = read_samples(MeasuredFile(path, quantity="reflectance"))
    wavelengths, values, label = samples.spectrum("plot 2")
    assert label == "plot 2" and list(wavelengths) == [400.0, 600.0, 700.0]
    with pytest.raises(ValueError, match=r"m.csv holds 3 spectra \(plot 1, plot 2, plot 3\): choose one"):
        samples.spectrum()
