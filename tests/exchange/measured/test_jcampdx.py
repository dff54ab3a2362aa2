"""JCAMP-DX files written from the published layout (AFFN, XY pairs, compound LINK files) read back."""

from __future__ import annotations

import numpy as np
import pytest

from measured_files import write_jcamp
from virtspec_mi.exchange.measured import MeasuredFile, read_samples

WAVELENGTHS = np.arange(400.0, 420.0, 2.0)
A = np.linspace(0.05, 0.45, 10)
B = np.linspace(0.30, 0.10, 10)


@pytest.mark.parametrize("form", ["(X++(Y..Y))", "(XY..XY)"])
def test_one_spectrum_reads_back_with_its_yfactor(tmp_path, form):
    samples = read_samples(write_jcamp(tmp_path / "leaf.jdx", WAVELENGTHS, {"soybean leaf": A}, form=form))
    assert samples.quantity == "reflectance" and samples.labels == ("soybean leaf",) and samples.format == "jcamp"
    np.testing.assert_allclose(samples.wavelengths, WAVELENGTHS)
    np.testing.assert_allclose(samples.values[0], A, atol=1e-5)  # YFACTOR 1e-5: the file's integers


def test_a_compound_file_is_many_labelled_spectra(tmp_path):
    path = write_jcamp(tmp_path / "lib.dx", WAVELENGTHS, {"a": A, "b": B}, yunits="TRANSMITTANCE")
    samples = read_samples(path)
    assert samples.labels == ("a", "b") and samples.quantity == "transmittance"
    np.testing.assert_allclose(samples.values, [A, B], atol=1e-5)


def test_units_percent_micrometres_and_wavenumbers(tmp_path):
    percent = read_samples(write_jcamp(tmp_path / "p.jdx", WAVELENGTHS / 1000, {"p": 100 * A}, xunits="MICROMETERS",
                                       yunits="%R", yfactor=1e-3))
    np.testing.assert_allclose(percent.wavelengths, WAVELENGTHS)
    np.testing.assert_allclose(percent.values[0], A, atol=1e-5)
    numbers = 1e7 / WAVELENGTHS[::-1]
    wavenumbers = read_samples(write_jcamp(tmp_path / "k.jdx", numbers, {"k": A[::-1]}, xunits="1/CM",
                                           form="(XY..XY)"))
    np.testing.assert_allclose(wavenumbers.wavelengths, WAVELENGTHS, rtol=1e-5)
    np.testing.assert_allclose(wavenumbers.values[0], A, atol=1e-5)


def test_an_ordinate_that_is_no_factor_or_is_untold(tmp_path):
    with pytest.raises(ValueError, match=r"ab.jdx: it holds absorbance .*must hold reflectance or transmittance"):
        read_samples(write_jcamp(tmp_path / "ab.jdx", WAVELENGTHS, {"x": A}, yunits="ABSORBANCE"))
    path = write_jcamp(tmp_path / "arb.jdx", WAVELENGTHS, {"x": A}, yunits="ARBITRARY UNITS")
    with pytest.raises(ValueError, match=r"arb.jdx: it does not tell .*measured_quantity="):
        read_samples(path)
    assert read_samples(MeasuredFile(path, quantity="reflectance")).quantity == "reflectance"


def test_truncated_files_are_refused(tmp_path):
    text = write_jcamp(tmp_path / "w.jdx", WAVELENGTHS, {"x": A}).read_text()
    (tmp_path / "end.jdx").write_text(text.replace("##END=\n", ""))
    with pytest.raises(ValueError, match=r"end.jdx: truncated: 1 ##TITLE= records, 0 ##END="):
        read_samples(tmp_path / "end.jdx")
    lines = text.splitlines()
    (tmp_path / "short.jdx").write_text("\n".join(lines[:-2] + ["##END="]) + "\n")
    with pytest.raises(ValueError, match=r"short.jdx: block 'x': 5 values for 10 abscissae and ##NPOINTS= 10"):
        read_samples(tmp_path / "short.jdx")
    (tmp_path / "none.jdx").write_text("hello\n")
    with pytest.raises(ValueError, match=r"none.jdx: not a JCAMP-DX file"):
        read_samples(tmp_path / "none.jdx")


DIF = """##TITLE= dif leaf
##JCAMP-DX= 4.24
##XUNITS= NANOMETERS
##YUNITS= %T
##YFACTOR= 0.1
##FIRSTX= 400
##LASTX= 409
##NPOINTS= 10
##XYDATA= (X++(Y..Y))
400A00KL%k
404A03JJJJ
408A07J
##END=
"""


def test_the_compressed_difference_form_and_its_y_checks(tmp_path):
    """ASDF (SQZ + DIF, McDonald & Wilks 1988): each line's first value repeats the last of the line before."""

    (tmp_path / "dif.jdx").write_text(DIF)
    samples = read_samples(tmp_path / "dif.jdx")
    assert samples.quantity == "transmittance"  # %T: transmittance in percent
    np.testing.assert_allclose(samples.values[0], [0.1, 0.102, 0.105, 0.105, 0.103, 0.104, 0.105, 0.106, 0.107,
                                                   0.108])
    (tmp_path / "bad.jdx").write_text(DIF.replace("404A03", "404A09"))
    with pytest.raises(ValueError, match=r"bad.jdx: damaged data \(Y-Check failed"):
        read_samples(tmp_path / "bad.jdx")
