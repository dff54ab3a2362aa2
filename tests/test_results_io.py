"""Tests of virtspec_mi.results_io: xarray / NetCDF, CSV, JSON and colour-science CSV spectra."""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.api import read_result as read_sweep
from virtspec_mi.results_io import read_spectra_csv, write_spectra_csv


def to_dataset(result):
    return result.to_dataset()


def write_sweep(result, path):
    return result.write(path)


@pytest.fixture(scope="module")
def result(mi):
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": {
        "type": "regular", "wavelength_min": 400.0, "wavelength_max": 700.0, "values": "0.2, 0.8, 0.4"}})
    return vm.sweep(scene, theta_i=[0, 30, 60], wavelengths="400:700:50", rays=3000, seed=2, phi_i=15)


def test_dataset_has_the_grid_counts_and_every_setting(result):
    dataset = to_dataset(result)
    assert dataset["reflectance"].dims == ("wavelength", "theta_i")
    assert dataset.sizes == {"wavelength": 7, "theta_i": 3}
    np.testing.assert_array_equal(dataset["reflected"].values, result.reflected)
    np.testing.assert_array_equal(dataset["rays"].values, 3000)
    np.testing.assert_allclose(dataset["absorptance"].values, result.absorptance)
    for key, value in dict(mu=0.005, delta=0.01, bound="hoeffding", beam="conical", sampling="jittered",
                           seed=2, phi_i=15.0, emitter_radius=8.0, specimen_radius=12.5, distance=100.0,
                           wavelength_independent=0, version=vm.__version__).items():
        assert dataset.attrs[key] == value, key
    assert dataset.attrs["scene"].startswith("sha256:")


@pytest.mark.parametrize("suffix", [".nc", ".csv", ".json"])
def test_every_format_round_trips_exactly(result, tmp_path, suffix):
    path = write_sweep(result, tmp_path / f"sweep{suffix}")
    back = read_sweep(path)
    for name in ("wavelengths", "theta_i", "reflected", "transmitted", "weight_violations", "capped", "rays"):
        np.testing.assert_array_equal(getattr(back, name), getattr(result, name))
    np.testing.assert_array_equal(back.reflectance, result.reflectance)
    assert back.settings == result.settings
    assert back.geometry == result.geometry
    assert (back.seconds, back.scene, back.version) == (result.seconds, result.scene, result.version)


def test_bad_files_give_clear_errors(result, tmp_path):
    with pytest.raises(ValueError, match=r"out must end in one of \.nc, \.csv, \.json"):
        write_sweep(result, tmp_path / "sweep.txt")
    (tmp_path / "other.csv").write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="not a virtspec-mi result CSV"):
        read_sweep(tmp_path / "other.csv")
    (tmp_path / "other.json").write_text('{"a": 1}')
    with pytest.raises(ValueError, match="not a virtspec-mi result"):
        read_sweep(tmp_path / "other.json")
    with pytest.raises(ValueError, match="not found"):
        read_sweep(tmp_path / "missing.nc")


def test_colour_science_csv_spectra_round_trip(result, tmp_path):
    path = write_spectra_csv(result, tmp_path / "spectra.csv", theta_i=30)
    spectra = read_spectra_csv(path)
    assert sorted(spectra) == ["absorptance", "reflectance", "transmittance"]
    np.testing.assert_allclose(spectra["reflectance"].wavelengths, result.wavelengths)
    # colour-science writes 12 significant digits
    np.testing.assert_allclose(spectra["reflectance"].values, result.reflectance[:, 1], rtol=1e-11)
    np.testing.assert_allclose(spectra["absorptance"].values, result.absorptance[:, 1], rtol=1e-11)
