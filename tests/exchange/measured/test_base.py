"""
Tests of :mod:`virtspec_mi.exchange.measured.base`: the one set of rules every reader's output goes through.

:func:`settle` converts the wavelength units (µm × 1000, cm⁻¹ → 10⁷/ν̃) and sorts them, scales
percentages, ratios a target/reference pair channel by channel leaving out dark channels, keeps
the file's quantity and refuses a contradicting statement, a file that tells none, values that
look like untold percentages, repeated wavelengths and mismatched shapes, each with the file's
name; labels are made distinct; :class:`Samples` picks a sample by label or index, and
:class:`MeasuredFile` refuses bad options by name. The text helpers refuse a truncated file and
a ragged row.

References
----------
See the module (ASD, SVC, Spectral Evolution, JCAMP-DX, ENVI, EcoSIS).
"""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.exchange.measured.base import (
    MEASURED_QUANTITIES,
    SCALES,
    MeasuredFile,
    MeasuredFormat,
    RawSpectra,
    number_rows,
    refuse,
    settle,
    text_lines,
)

WAVELENGTHS = np.array([700.0, 500.0, 600.0])


def raw(**changes) -> RawSpectra:
    fields = dict(wavelengths=WAVELENGTHS, labels=("leaf",), values=np.array([[0.7, 0.5, 0.6]]),
                  quantity="reflectance", told="line 3")
    fields.update(changes)
    return RawSpectra(**fields)


def test_settled_samples_are_sorted_fractions_in_nanometres():
    samples = settle("dir/leaf.txt", raw(), "table")
    np.testing.assert_array_equal(samples.wavelengths, [500.0, 600.0, 700.0])
    np.testing.assert_array_equal(samples.values, [[0.5, 0.6, 0.7]])
    assert (samples.quantity, samples.source, samples.format, len(samples)) == ("reflectance", "leaf.txt", "table", 1)
    assert samples.metadata == ({},) and samples.note == ""


@pytest.mark.parametrize("unit, given, nm, values", [("um", [0.5, 0.6], [500.0, 600.0], [0.1, 0.2]),
                                                     ("cm-1", [12_500.0, 20_000.0], [500.0, 800.0], [0.2, 0.1])])
def test_wavelength_units_are_converted(unit, given, nm, values):
    samples = settle("a.txt", raw(wavelengths=np.array(given), values=np.array([[0.1, 0.2]]), unit=unit), "t")
    np.testing.assert_allclose(samples.wavelengths, nm)
    np.testing.assert_array_equal(samples.values[0], values)  # wavenumbers fall as nm rise: sorted


def test_percentages_are_scaled_told_or_stated():
    told = settle("a.txt", raw(values=np.array([[70.0, 50.0, 60.0]]), scale="percent"), "t")
    np.testing.assert_allclose(told.values, [[0.5, 0.6, 0.7]])
    stated = settle("a.txt", raw(values=np.array([[70.0, 50.0, 60.0]])), "t", scale="percent")
    np.testing.assert_allclose(stated.values, told.values)
    assert SCALES == {"fraction": 1.0, "percent": 0.01}
    with pytest.raises(ValueError, match=r"measured file a.txt: its values reach 70 and it does not tell their scale: "
                                         r"percentages\? state measured_scale='percent'"):
        settle("a.txt", raw(values=np.array([[70.0, 50.0, 60.0]])), "t")
    with pytest.raises(ValueError, match=r"its values are a percent \(line 3\), stated measured_scale='fraction'"):
        settle("a.txt", raw(values=np.array([[70.0, 50.0, 60.0]]), scale="percent"), "t", scale="fraction")


def test_a_pair_is_ratioed_and_dark_channels_are_left_out():
    pair = raw(values=None, target=np.array([[2.0, 1.0, 3.0]]), reference=np.array([[4.0, 0.0, 6.0]]))
    samples = settle("pair.sig", pair, "sig")  # 700, 500 (dark), 600 nm: sorted, the dark channel first
    np.testing.assert_array_equal(samples.values, [[np.nan, 0.5, 0.5]])
    assert samples.note == "ratioed target / reference channel by channel; 1 channels with a reference <= 0 left out"
    wavelengths, values, label = samples.spectrum()
    np.testing.assert_array_equal(wavelengths, [600.0, 700.0])
    np.testing.assert_array_equal(values, [0.5, 0.5])
    assert label == "leaf"
    with pytest.raises(ValueError, match="neither ratios nor a target/reference pair"):
        settle("pair.sig", raw(values=None), "sig")


def test_the_quantity_is_the_files_else_the_stated_one():
    assert settle("a.txt", raw(quantity=None), "t", quantity="transmittance").quantity == "transmittance"
    with pytest.raises(ValueError, match=r"measured file a.txt: it holds reflectance \(line 3\), stated "
                                         r"measured_quantity='transmittance': a mislabelled file\?"):
        settle("a.txt", raw(), "t", quantity="transmittance")
    with pytest.raises(ValueError, match=r"it does not tell whether it holds reflectance or transmittance: state it "
                                         r"with measured_quantity="):
        settle("a.txt", raw(quantity=None), "t")
    with pytest.raises(ValueError, match=r"it holds absorbance \(line 3\): a measured file must hold reflectance or "
                                         r"transmittance"):
        settle("a.txt", raw(quantity="absorbance"), "t")
    assert MEASURED_QUANTITIES == ("reflectance", "transmittance")


@pytest.mark.parametrize("changes, message", [
    (dict(labels=()), "it holds no spectrum"),
    (dict(values=np.array([[0.1, 0.2]])), r"it holds 1 spectra of 2 values for 1 labels and 3 wavelengths"),
    (dict(wavelengths=np.array([500.0, 600.0, 500.0])), r"its wavelengths must be distinct"),
    (dict(wavelengths=np.array([500.0, -1.0, 600.0])), r"its wavelengths must be finite and > 0"),
    (dict(unit="angstrom"), r"its wavelength unit 'angstrom' is none of nm, um, cm-1"),
    (dict(values=None, target=np.ones((1, 3)), reference=np.ones((1, 2))), r"its target and reference differ"),
])
def test_bad_raw_spectra_are_refused_with_the_files_name(changes, message):
    with pytest.raises(ValueError, match=r"^measured file bad.txt: " + message):
        settle("bad.txt", raw(**changes), "t")


def test_repeated_labels_are_made_distinct_and_samples_are_picked():
    many = raw(labels=("a", "b", "a"), values=np.arange(9.0).reshape(3, 3) / 10)
    samples = settle("m.csv", many, "table")
    assert samples.labels == ("a", "b", "a#2")
    assert samples.index("b") == 1 and samples.index(2) == 2 and samples.index("2") == 2
    with pytest.raises(ValueError, match=r"measured file m.csv holds 3 spectra \(a, b, a#2\): choose one with "
                                         r"sample=LABEL or INDEX \(--sample\)"):
        samples.index(None)
    with pytest.raises(ValueError, match=r"sample must satisfy 0 <= sample < 3 in m.csv \(got 3\)"):
        samples.index(3)
    with pytest.raises(ValueError, match=r"sample must be a label of m.csv \(a, b, a#2\) or an index \(got 'c'\)"):
        samples.index("c")
    assert samples.index(np.int64(1)) == 1
    with pytest.raises(ValueError):
        samples.index(True)  # a bool is no index


def test_measured_file_refuses_bad_options_by_name():
    assert MeasuredFile("x.asd", quantity="reflectance", scale="percent").splice is False
    with pytest.raises(ValueError, match=r"measured_quantity must be one of reflectance, transmittance "
                                         r"\(got 'colour'\)"):
        MeasuredFile("x.asd", quantity="colour")
    with pytest.raises(ValueError, match=r"measured_scale must be one of fraction, percent \(got 'permille'\)"):
        MeasuredFile("x.asd", scale="permille")
    with pytest.raises(ValueError, match=r"splice must be True or False \(got 'yes'\)"):
        MeasuredFile("x.asd", splice="yes")


def test_a_format_reads_its_suffixes_and_its_claims(tmp_path):
    plain = MeasuredFormat("asd", (".asd",), lambda path, splice: raw(), "ASD")
    picky = MeasuredFormat("table", (".csv",), lambda path, splice: raw(), "tables", claims=lambda p: "t" in p.stem)
    assert plain.reads(tmp_path / "X.ASD") and not plain.reads(tmp_path / "x.csv")
    assert picky.reads(tmp_path / "table.csv") and not picky.reads(tmp_path / "leaf.csv")


def test_text_helpers_refuse_truncated_files_and_ragged_rows(tmp_path):
    good = tmp_path / "good.txt"
    good.write_bytes(b"# header \xe9\n400 0.1\n500\t0.2\n")
    lines = text_lines(good)
    assert lines[0] == "# header é" and len(lines) == 3
    np.testing.assert_array_equal(number_rows(good, list(enumerate(lines))[1:]), [[400.0, 0.1], [500.0, 0.2]])
    cut = tmp_path / "cut.txt"
    cut.write_text("400 0.1\n500 0.2")
    with pytest.raises(ValueError, match=r"measured file cut.txt: truncated: its last line has no line end"):
        text_lines(cut)
    with pytest.raises(ValueError, match=r"measured file gone.txt: cannot be read"):
        text_lines(tmp_path / "gone.txt")
    with pytest.raises(ValueError, match=r"line 3: 1 columns, the rows before have 2"):
        number_rows(good, [(2, "400 0.1"), (3, "500")])
    with pytest.raises(ValueError, match=r"line 2: expected numbers \(got 'wavelength value'\)"):
        number_rows(good, [(2, "wavelength value")])
    with pytest.raises(ValueError, match="it holds no rows of data"):
        number_rows(good, [(2, "  ")])
    assert str(refuse("a/b.asd", "why")) == "measured file b.asd: why"
