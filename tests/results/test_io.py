"""Tests of virtspec_mi.results.io: xarray / NetCDF, CSV, JSON and colour-science CSV spectra."""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.api import read_result as read_sweep
from virtspec_mi.results.io import read_spectra_csv, write_spectra_csv


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
    with pytest.raises(ValueError, match=r"out must end in one of \.nc, \.csv, \.json, \.zarr"):
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


# --- atomic writes, large CSVs ------------------------------------------------------------


def _grid_result(n_lam: int, n_theta: int, seed: int = 0):
    """A sweep result built from counts (no tracing): random R, T counts of 10^5 rays."""

    from dataclasses import replace

    from virtspec_mi.kernel.counts import Counts
    from virtspec_mi.results.readings import Result
    from virtspec_mi.settings import Settings

    rng = np.random.default_rng(seed)
    shape = (n_lam, n_theta)
    reflected = rng.integers(0, 50_000, shape)
    counts = replace(Counts.zeros(shape), rays=np.full(shape, 10**5, dtype=np.int64), reflected=reflected,
                     transmitted=rng.integers(0, 50_000, shape), specular_reflected=reflected // 3)
    wavelengths = 400.0 + np.arange(n_lam)
    return Result(("wavelength", "theta_i"), {"wavelength": wavelengths, "theta_i": np.linspace(0, 90, n_theta)},
                  counts, None, Settings(wavelengths=list(wavelengths)), vm.InstrumentGeometry(8, 12.5, 100), 1.5)


@pytest.mark.parametrize("legacy", [False, "1.13"])  # numpy's print options: its own, and colour-science's
def test_csv_of_a_large_grid_has_every_reading_and_exact_numbers(tmp_path, legacy):
    import csv

    result = _grid_result(60, 91)
    dataset = result.to_dataset()
    with np.printoptions(legacy=legacy):
        path = result.write(tmp_path / "large.csv")
    with path.open(newline="") as handle:
        assert handle.readline().startswith("# virtspec-mi result {")
        rows = list(csv.reader(handle))
    header, rows = rows[0], rows[1:]
    assert set(header) == {"wavelength", "theta_i", *dataset.data_vars} and len(header) == len(set(header))
    assert len(rows) == 60 * 91 and {len(row) for row in rows} == {len(header)}
    flat = dataset.to_dataframe().reset_index()
    for k, column in enumerate(header):  # every number as written reads back exactly (NaN: an empty field)
        written = np.array([float(row[k]) if row[k] else np.nan for row in rows])
        np.testing.assert_array_equal(written, flat[column].to_numpy(dtype=np.float64), err_msg=column)
    assert flat["wavelength"].iloc[1] == 400.0 and flat["theta_i"].iloc[1] == 1.0  # one row per (wavelength, theta_i)


@pytest.mark.parametrize("suffix", [".nc", ".csv", ".json"])
@pytest.mark.parametrize("fault", ["rename", "mid-write"])
def test_a_failed_write_leaves_the_old_file_and_no_temporary(result, tmp_path, monkeypatch, suffix, fault):
    import errno
    import os

    import xarray as xr

    import virtspec_mi.results.io as results_io

    path = write_sweep(result, tmp_path / f"sweep{suffix}")
    before = path.read_bytes()
    full = OSError(errno.ENOSPC, "No space left on device")
    if fault == "rename":
        def replace(source, target):
            raise full

        monkeypatch.setattr(results_io.os, "replace", replace)
    else:
        def half_text(self, text, *args, **kwargs):
            os.truncate(self, 0) if self.exists() else None
            with open(self, "a") as handle:
                handle.write(text[: len(text) // 2])
            raise full

        def half_netcdf(self, target, *args, **kwargs):
            with open(target, "wb") as handle:
                handle.write(b"CDF\x01 half")
            raise full

        monkeypatch.setattr(type(path), "write_text", half_text)
        monkeypatch.setattr(xr.Dataset, "to_netcdf", half_netcdf)
    with pytest.raises(OSError, match="No space left"):
        write_sweep(result, path)
    monkeypatch.undo()
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == [path.name]


def test_concurrent_writers_never_show_a_partial_file(tmp_path):
    import json
    import threading

    path = tmp_path / "shared.json"
    results = [_grid_result(30, 91, seed) for seed in range(2)]
    from virtspec_mi.results.io import write

    write(results[0], path)
    errors, stop = [], threading.Event()

    def writer(k: int) -> None:
        try:
            for _ in range(10):
                write(results[k], path)
        except Exception as error:  # noqa: BLE001 - any failure fails the test
            errors.append(error)

    def reader() -> None:
        while not stop.is_set():
            try:
                json.loads(path.read_text())
            except Exception as error:  # noqa: BLE001
                errors.append(error)
                return

    threads = [threading.Thread(target=writer, args=(k,)) for k in (0, 1, 0, 1)]
    watcher = threading.Thread(target=reader)
    watcher.start()
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    stop.set()
    watcher.join()
    assert errors == []
    assert read_sweep(path).as_dict() in [r.as_dict() for r in results]
    assert [p.name for p in tmp_path.iterdir()] == ["shared.json"]


def test_a_plain_csv_is_columns_and_rows_and_pandas_reads_both(result, tmp_path):
    import pandas as pd

    full, plain = result.write(tmp_path / "full.csv"), result.write(tmp_path / "plain.csv", plain=True)
    assert full.read_text().startswith("# virtspec-mi result {")
    assert plain.read_text().splitlines()[0].startswith("wavelength,theta_i,reflectance,")
    assert plain.read_text().splitlines()[1:] == full.read_text().splitlines()[2:]
    table, commented = pd.read_csv(plain), pd.read_csv(full, comment="#")  # as the manual says
    assert list(table.columns) == list(commented.columns) and table.shape == (7 * 3, commented.shape[1])
    np.testing.assert_array_equal(table["reflected"].to_numpy(), result.to_dataset()["reflected"].values.ravel())
    assert np.array_equal(read_sweep(full).reflected, result.reflected)
    with pytest.raises(ValueError, match="a plain CSV, written for a spreadsheet, holds no settings"):
        read_sweep(plain)
    with pytest.raises(ValueError, match="out must end in .csv: a plain CSV holds columns and rows"):
        result.write(tmp_path / "plain.nc", plain=True)
    with pytest.raises(ValueError, match="plain must be True or False"):
        result.write(tmp_path / "plain.csv", plain="yes")
