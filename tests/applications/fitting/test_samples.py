"""Every spectrum of a measured file of many fitted (virtspec_mi/applications/fitting/samples.py): a table of fits."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

import virtspec_mi as vm
from measured_files import write_rows
from virtspec_mi.plugins.bsdfs.prospect_model import prospect_d

GRID = np.arange(450.0, 2400.0, 150.0)
TRUTHS = {"young": 20.0, "mature": 45.0, "dark": 70.0}
FAST = dict(evaluations=(8, 4, 2), profile_points=3, table_points=5, theta_i=8.0, beam="collimated", delta=0.1,
            measurement_uncertainty=0.01, seed=3)


@pytest.fixture
def library(tmp_path):
    return write_rows(tmp_path / "leaves.csv", GRID, {name: prospect_d(GRID, Cab=cab)[0] for name, cab in TRUTHS.items()},
                      quantity="reflectance")


def test_every_sample_is_fitted_and_shares_one_table(library, tmp_path):
    table = vm.fit_samples(library, "prospect_d", {"Cab": (10, 90)}, directory=tmp_path / "work", **FAST)
    assert table.labels == tuple(TRUTHS) and table.names == ("Cab",)
    for (label, truth), (low, high), consistent in zip(TRUTHS.items(), table.intervals[:, 0], table.consistent):
        assert consistent and low <= truth <= high and high - low < 40, (label, low, high)
    assert np.all(np.diff(table.estimate[:, 0]) > 0)  # the three leaves in order of their chlorophyll
    assert (tmp_path / "work" / "table.zarr").is_dir() and (tmp_path / "work" / "0").is_dir()
    one = vm.fit(vm.MeasuredFile(library, sample="mature"), "prospect_d", {"Cab": (10, 90)},
                 table=tmp_path / "work" / "table.zarr", **FAST)
    np.testing.assert_array_equal(one.intervals, table.fits[1].intervals)  # a row is that spectrum's own fit
    for name in ("fits.nc", "fits.csv"):
        table.write(tmp_path / name)
    back = xr.open_dataset(tmp_path / "fits.nc")
    np.testing.assert_allclose(back["lowest"].values[:, 0], table.intervals[:, 0, 0])
    assert "no joint level" in table.summary() and "young: Cab = " in table.summary()
    with pytest.raises(ValueError, match="a fit table is .csv or .nc"):
        table.write(tmp_path / "fits.json")
    with pytest.raises(ValueError, match="table= is not taken"):
        vm.fit_samples(library, "prospect_d", {"Cab": (10, 90)}, table="x.zarr", **FAST)


def test_samples_by_label_or_index(library):
    table = vm.fit_samples(library, "prospect_d", {"Cab": (10, 90)}, samples=["dark", 0], **FAST)
    assert table.labels == ("dark", "young")
    with pytest.raises(ValueError, match=r"sample must be a label of leaves.csv"):
        vm.fit_samples(library, "prospect_d", {"Cab": (10, 90)}, samples=["old"], **FAST)


@pytest.mark.slow
def test_on_dask_workers_the_rows_are_the_in_process_ones(library):
    here = vm.fit_samples(library, "prospect_d", {"Cab": (10, 90)}, **FAST)
    there = vm.fit_samples(library, "prospect_d", {"Cab": (10, 90)}, workers=2, **FAST)
    np.testing.assert_array_equal(here.intervals, there.intervals)
    np.testing.assert_array_equal(here.estimate, there.estimate)


def test_cli_fits_every_spectrum_of_a_file_of_many(library, tmp_path, capsys):
    from virtspec_mi.cli import main

    common = ["--specimen", "prospect_d", "--free", "Cab=10:90", "--uncertainty", "0.01", "--profile-points", "3",
              "--theta-i", "8", "--beam", "collimated", "--delta", "0.1", "--seed", "3"]
    assert main(["fit", str(library), *common, "--out", str(tmp_path / "fits.csv"), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["samples"] == list(TRUTHS)
    for truth, interval in zip(TRUTHS.values(), data["intervals"]):
        assert interval[0][0] <= truth <= interval[0][1]
    assert (tmp_path / "fits.csv").read_text().startswith("sample,parameter,")
    assert main(["fit", str(library), *common, "--out", str(tmp_path / "fit.json")]) == 1
    assert "the fits of a file of many spectra are a table" in capsys.readouterr().err
