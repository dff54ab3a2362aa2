"""Spectral Evolution .sed files written from the published layout read back to the same numbers."""

from __future__ import annotations

import numpy as np
import pytest

from measured_files import write_sed
from virtspec_mi.exchange.measured import MeasuredFile, read_samples

WAVELENGTHS = np.arange(350.0, 360.0)
REFERENCE = np.linspace(1000, 1500, 10)
RATIO = np.linspace(0.05, 0.5, 10)


def _columns(ratio_name: str | None):
    columns = {"Rad. (Ref.)": REFERENCE, "Rad. (Target)": RATIO * REFERENCE}
    if ratio_name:
        columns[ratio_name] = RATIO * (100 if "%" in ratio_name else 1)
    return columns


@pytest.mark.parametrize("name, measurement, quantity", [
    ("Reflect. %", "REFLECTANCE", "reflectance"), ("Reflect. [1.0]", "REFLECTANCE", "reflectance"),
    ("Tgt./Ref. %", "TRANSMITTANCE", "transmittance"), ("Trans. %", "TRANSMITTANCE", "transmittance"),
    (None, "REFLECTANCE", "reflectance")])
def test_the_ratio_column_or_the_pair_with_the_quantity_told(tmp_path, name, measurement, quantity):
    path = write_sed(tmp_path / "leaf_00001.sed", WAVELENGTHS, _columns(name), measurement=measurement)
    samples = read_samples(path)
    assert samples.quantity == quantity and samples.labels == ("leaf_00001",) and samples.format == "sed"
    np.testing.assert_allclose(samples.wavelengths, WAVELENGTHS)
    np.testing.assert_allclose(samples.values[0], RATIO, rtol=1e-5)


def test_a_pair_under_radiance_needs_its_quantity_stated(tmp_path):
    path = write_sed(tmp_path / "rad.sed", WAVELENGTHS, _columns(None), measurement="RADIANCE")
    with pytest.raises(ValueError, match=r"rad.sed: it does not tell .*--measured-quantity"):
        read_samples(path)
    np.testing.assert_allclose(read_samples(MeasuredFile(path, quantity="reflectance")).values[0], RATIO, rtol=1e-5)


def test_a_column_against_the_measurement_line_is_refused(tmp_path):
    path = write_sed(tmp_path / "bad.sed", WAVELENGTHS, _columns("Reflect. %"), measurement="TRANSMITTANCE")
    with pytest.raises(ValueError, match=r"bad.sed: its column 'Reflect. %' holds reflectance, its header says "
                                         "Measurement: TRANSMITTANCE: a mislabelled file"):
        read_samples(path)


def test_truncated_files_are_refused(tmp_path):
    text = write_sed(tmp_path / "w.sed", WAVELENGTHS, _columns("Reflect. %")).read_text()
    lines = text.splitlines()
    (tmp_path / "short.sed").write_text("\n".join(lines[:-3]) + "\n")
    with pytest.raises(ValueError, match=r"short.sed: truncated or damaged: its header says Channels: 10, it holds 7"):
        read_samples(tmp_path / "short.sed")
    (tmp_path / "cut.sed").write_text(text[:-9])
    with pytest.raises(ValueError, match=r"cut.sed: truncated: its last line has no line end \('359.0\\t"):
        read_samples(tmp_path / "cut.sed")
    (tmp_path / "row.sed").write_text(text[:-20] + "\n")
    with pytest.raises(ValueError, match=r"row.sed: line \d+: 3 columns, the rows before have 4"):
        read_samples(tmp_path / "row.sed")
    (tmp_path / "head.sed").write_text("\n".join(lines[:6]) + "\n")
    with pytest.raises(ValueError, match=r"head.sed: not a Spectral Evolution .sed file, or truncated"):
        read_samples(tmp_path / "head.sed")
