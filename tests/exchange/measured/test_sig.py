"""SVC .sig files written from the published layout read back to the same numbers."""

from __future__ import annotations

import numpy as np
import pytest

from measured_files import write_sig
from virtspec_mi.exchange.measured import MeasuredFile, read_samples

WAVELENGTHS = np.array([338.5, 340.0, 341.6, 343.1, 344.6, 346.2])
REFERENCE = np.array([8473.45, 8500.0, 8620.5, 8700.25, 8800.0, 8900.75])
RATIO = np.array([0.7775, 0.70, 0.65, 0.60, 0.55, 0.5])


def test_the_reflectance_column_is_a_percentage_of_reflectance(tmp_path):
    path = write_sig(tmp_path / "HR.0001.sig", WAVELENGTHS, REFERENCE, RATIO * REFERENCE, 100 * RATIO)
    samples = read_samples(path)
    assert samples.quantity == "reflectance" and samples.labels == ("HR.0001",) and samples.format == "sig"
    np.testing.assert_allclose(samples.wavelengths, WAVELENGTHS)
    np.testing.assert_allclose(samples.values[0], RATIO, atol=1e-6)
    assert samples.metadata[0]["instrument"] == "HI: 1012064 (HR-1024i)"


def test_without_the_ratio_column_the_pair_is_ratioed(tmp_path):
    path = write_sig(tmp_path / "pair.sig", WAVELENGTHS, REFERENCE, RATIO * REFERENCE, None)
    samples = read_samples(path)
    np.testing.assert_allclose(samples.values[0], RATIO, rtol=1e-6)
    assert "ratioed target / reference" in samples.note


def test_a_row_cut_short_and_a_missing_data_line_are_refused(tmp_path):
    text = write_sig(tmp_path / "w.sig", WAVELENGTHS, REFERENCE, RATIO * REFERENCE, 100 * RATIO).read_text()
    (tmp_path / "cut.sig").write_text(text[:-12] + "\n")
    with pytest.raises(ValueError, match=r"cut.sig: line 14: 3 columns, the rows before have 4"):
        read_samples(tmp_path / "cut.sig")
    (tmp_path / "end.sig").write_text(text[:-3])
    with pytest.raises(ValueError, match=r"end.sig: truncated: its last line has no line end"):
        read_samples(tmp_path / "end.sig")
    (tmp_path / "head.sig").write_text(text.split("data=")[0])
    with pytest.raises(ValueError, match=r"head.sig: no 'data=' line"):
        read_samples(tmp_path / "head.sig")
    (tmp_path / "other.sig").write_text("hello\nworld\n")
    with pytest.raises(ValueError, match=r"other.sig: not an SVC .sig file"):
        read_samples(tmp_path / "other.sig")


def test_a_statement_of_transmittance_is_refused_as_mislabelled(tmp_path):
    path = write_sig(tmp_path / "a.sig", WAVELENGTHS, REFERENCE, RATIO * REFERENCE, 100 * RATIO)
    with pytest.raises(ValueError, match="mislabelled"):
        read_samples(MeasuredFile(path, quantity="transmittance"))
    with pytest.raises(ValueError, match=r"its values are a percent .* stated measured_scale='fraction'"):
        read_samples(MeasuredFile(path, scale="fraction"))
