"""ENVI spectral libraries (.sli + .hdr) written from ENVI's header keywords read back to the same numbers."""

from __future__ import annotations

import numpy as np
import pytest

from measured_files import write_envi
from virtspec_mi.exchange.measured import MeasuredFile, read_samples

WAVELENGTHS = np.array([0.40, 0.45, 0.50, 0.55, 0.60])
SPECTRA = {"leaf a": [0.05, 0.08, 0.10, 0.12, 0.09], "leaf b": [0.04, 0.06, 0.09, 0.11, 0.08],
           "leaf c": [0.03, 0.05, 0.07, 0.10, 0.07]}


@pytest.mark.parametrize("dtype", ["<f4", "<f8", ">f4"])
def test_many_labelled_spectra_in_micrometres(tmp_path, dtype):
    path = write_envi(tmp_path / "lib.sli", WAVELENGTHS, SPECTRA, units="Micrometers", dtype=dtype,
                      extra="z plot titles = {Wavelength, Reflectance}", offset=16)
    for given in (path, path.with_suffix(".hdr")):
        samples = read_samples(given)
        assert samples.labels == ("leaf a", "leaf b", "leaf c") and samples.quantity == "reflectance"
        np.testing.assert_allclose(samples.wavelengths, 1000 * WAVELENGTHS)
        np.testing.assert_allclose(samples.values, list(SPECTRA.values()), rtol=1e-6)


def test_a_reflectance_scale_factor_tells_quantity_and_scale(tmp_path):
    samples = read_samples(write_envi(tmp_path / "s.sli", 1000 * WAVELENGTHS, SPECTRA, dtype="<i2", scale=10000))
    assert samples.quantity == "reflectance"
    np.testing.assert_allclose(samples.values, list(SPECTRA.values()), atol=1e-4)


def test_an_untold_quantity_is_refused_naming_the_option(tmp_path):
    path = write_envi(tmp_path / "u.sli", 1000 * WAVELENGTHS, SPECTRA)
    with pytest.raises(ValueError, match=r"u.sli: it does not tell .*--measured-quantity"):
        read_samples(path)
    assert read_samples(MeasuredFile(path, quantity="transmittance")).quantity == "transmittance"


def test_truncated_and_inconsistent_libraries_are_refused(tmp_path):
    path = write_envi(tmp_path / "t.sli", 1000 * WAVELENGTHS, SPECTRA, extra="z plot titles = {Wavelength, Reflectance}")
    path.write_bytes(path.read_bytes()[:-7])
    with pytest.raises(ValueError, match=r"t.sli: truncated: 3 spectra of 5 float32 values after a 0-byte offset "
                                         r"need 60 bytes, the file has 53"):
        read_samples(path)
    other = write_envi(tmp_path / "n.sli", 1000 * WAVELENGTHS, {"x": [0.1] * 5})
    header = other.with_suffix(".hdr")
    header.write_text(header.read_text().replace("wavelength = {400, ", "wavelength = {"))
    with pytest.raises(ValueError, match=r"n.hdr: 4 wavelengths for samples = 5"):
        read_samples(MeasuredFile(other, quantity="reflectance"))
    (tmp_path / "lone.sli").write_bytes(b"\0" * 8)
    with pytest.raises(ValueError, match=r"lone.sli: no ENVI header beside the library"):
        read_samples(tmp_path / "lone.sli")
    (tmp_path / "bad.hdr").write_text("not a header\n")
    (tmp_path / "bad.sli").write_bytes(b"\0" * 8)
    with pytest.raises(ValueError, match=r"bad.hdr: not a readable ENVI header"):
        read_samples(tmp_path / "bad.sli")
