"""ASD binary files written from the v8 header's layout read back to the same numbers."""

from __future__ import annotations

import numpy as np
import pytest

from measured_files import write_asd
from virtspec_mi.exchange.measured import MeasuredFile, read_samples
from virtspec_mi.exchange.measured.asd import splice_correct

CHANNELS = 2151
WAVELENGTHS = 350.0 + np.arange(CHANNELS)


def _pair(rng=np.random.default_rng(7)):
    reference = rng.uniform(2000, 30000, CHANNELS)
    ratio = 0.05 + 0.5 * (WAVELENGTHS > 700) * (WAVELENGTHS < 1300)
    return ratio * reference, reference, ratio


@pytest.mark.parametrize("data_format", [0, 2])
def test_a_reflectance_file_is_the_ratio_of_target_and_reference(tmp_path, data_format):
    target, reference, ratio = _pair()
    path = write_asd(tmp_path / "leaf00001.asd", 350.0, 1.0, target, reference, data_format=data_format)
    samples = read_samples(path)
    assert samples.quantity == "reflectance" and samples.labels == ("leaf00001",) and samples.format == "asd"
    np.testing.assert_allclose(samples.wavelengths, WAVELENGTHS)
    expected = (np.asarray(target, dtype=np.float32) / np.asarray(reference, dtype=np.float32)
                if data_format == 0 else ratio)
    np.testing.assert_allclose(samples.values[0], expected, rtol=1e-6 if data_format == 0 else 1e-12)
    assert samples.metadata[0]["comment"] == "virtspec test"


def test_a_transmittance_file_tells_its_quantity(tmp_path):
    target, reference, ratio = _pair()
    samples = read_samples(write_asd(tmp_path / "t.asd", 350.0, 1.0, target, reference, data_type=6))
    assert samples.quantity == "transmittance"
    np.testing.assert_allclose(samples.values[0], ratio)


def test_a_raw_file_needs_its_quantity_stated_and_then_is_ratioed(tmp_path):
    target, reference, ratio = _pair()
    path = write_asd(tmp_path / "raw.asd", 350.0, 1.0, target, reference, data_type=0)
    with pytest.raises(ValueError, match=r"raw.asd: .*measured_quantity="):
        read_samples(path)
    samples = read_samples(MeasuredFile(path, quantity="transmittance"))
    assert samples.quantity == "transmittance"
    np.testing.assert_allclose(samples.values[0], ratio)


def test_a_statement_against_the_file_is_refused_as_mislabelled(tmp_path):
    target, reference, _ = _pair()
    path = write_asd(tmp_path / "r.asd", 350.0, 1.0, target, reference, data_type=1)
    with pytest.raises(ValueError, match=r"r.asd: it holds reflectance \(its header's data type 1.*mislabelled"):
        read_samples(MeasuredFile(path, quantity="transmittance"))


def test_radiance_and_version_1_are_refused(tmp_path):
    target, reference, _ = _pair()
    with pytest.raises(ValueError, match="holds radiance"):
        read_samples(write_asd(tmp_path / "rad.asd", 350.0, 1.0, target, reference, data_type=2))
    with pytest.raises(ValueError, match="version 1 holds no white reference"):
        read_samples(write_asd(tmp_path / "v1.asd", 350.0, 1.0, target, None, version=b"ASD"))


@pytest.mark.parametrize("keep, message", [
    (100, r"t.asd: truncated: 100 bytes, shorter than the 484-byte ASD header"),
    (484 + 8 * 1000, r"t.asd: truncated in its spectrum data"),
    (484 + 8 * CHANNELS + 5, r"t.asd: truncated before its reference"),
    (484 + 8 * CHANNELS + 20 + 15 + 8 * 10, r"t.asd: truncated in its reference data"),
])
def test_a_truncated_file_is_refused_naming_what_is_cut(tmp_path, keep, message):
    target, reference, _ = _pair()
    whole = write_asd(tmp_path / "whole.asd", 350.0, 1.0, target, reference).read_bytes()
    (tmp_path / "t.asd").write_bytes(whole[:keep])
    with pytest.raises(ValueError, match=message):
        read_samples(tmp_path / "t.asd")


def test_not_an_asd_file_is_refused(tmp_path):
    (tmp_path / "x.asd").write_bytes(b"PK\x03\x04" + bytes(600))
    with pytest.raises(ValueError, match=r"x.asd: not an ASD file"):
        read_samples(tmp_path / "x.asd")


def test_splice_correction_only_on_request_removes_the_detector_jumps(tmp_path):
    reference = np.full(CHANNELS, 10000.0)
    smooth = 0.3 + 1e-4 * (WAVELENGTHS - 350)
    jumped = smooth + 0.02 * (WAVELENGTHS > 1000) - 0.01 * (WAVELENGTHS > 1800)
    path = write_asd(tmp_path / "s.asd", 350.0, 1.0, jumped * reference, reference)
    plain = read_samples(path)
    np.testing.assert_allclose(plain.values[0], jumped)  # not on request: the data as they are
    corrected = read_samples(MeasuredFile(path, splice=True))
    np.testing.assert_allclose(corrected.values[0], smooth, atol=1e-12)
    assert corrected.note.startswith("splice-corrected: -0.02 above 1000 nm, +0.01 above 1800 nm")
    (tmp_path / "s.csv").write_text("wavelength,a,b\n400,0.1,0.2\n500,0.1,0.2\n")
    with pytest.raises(ValueError, match="splice correction applies to formats with detector splices"):
        read_samples(MeasuredFile(tmp_path / "s.csv", splice=True))


def test_splice_correct_continues_the_line_through_the_last_two_channels():
    w = np.array([998.0, 999.0, 1000.0, 1001.0, 1002.0])
    values, note = splice_correct(w, np.array([1.0, 2.0, 3.0, 10.0, 11.0]), (1000.0,))
    np.testing.assert_allclose(values, [1, 2, 3, 4, 5])
    assert note == "splice-corrected: -6 above 1000 nm"


def test_integer_data_and_the_default_splices_of_an_older_header(tmp_path):
    target, reference = np.full(CHANNELS, 300), np.full(CHANNELS, 1200)
    jumped = target + 60 * (WAVELENGTHS > 1000)
    path = write_asd(tmp_path / "i.asd", 350.0, 1.0, jumped, reference, data_format=1, splices=(0.0, 0.0),
                     version=b"as6")
    np.testing.assert_allclose(read_samples(path).values[0], jumped / 1200)
    corrected = read_samples(MeasuredFile(path, splice=True))  # no splice in the header: 1000 and 1800 nm
    np.testing.assert_allclose(corrected.values[0], 0.25)
    assert corrected.note.startswith("splice-corrected: -0.05 above 1000 nm, +0 above 1800 nm")
