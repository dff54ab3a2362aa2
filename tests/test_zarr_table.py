"""Tests of virtspec_mi.zarr_table: a sweep's Zarr store filled region by region, read back as a Result."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

import virtspec_mi as vm
from virtspec_mi.checkpoint import Checkpoint
from virtspec_mi.counts import Counts

SMALL = {"theta_i": [0, 40, 75], "wavelengths": "450:650:50", "rays": 20_000, "progress": False}


@pytest.fixture(scope="module")
def dielectric(mi):
    return vm.instrument_scene({"type": "simple_dielectric", "eta": 1.5})


def same_counts(a, b) -> None:
    for name in Counts.names():
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name


@pytest.mark.parametrize("scene", ["dict", "scenes/soybean_abmb.xml"], ids=["rows-of-5", "single-readings"])
def test_an_interrupted_zarr_sweep_holds_its_finished_regions_and_resumes(dielectric, monkeypatch, tmp_path, scene):
    # the dielectric is wavelength-independent: a batch is a theta_i row; the leaf's are single readings
    scene = dielectric if scene == "dict" else scene
    out = tmp_path / "table.zarr"
    whole = vm.sweep(scene, **SMALL)
    record = Checkpoint.record
    calls = []

    def interrupting(self, batch, *args):
        calls.append(batch)
        if len(calls) == 2:
            raise KeyboardInterrupt
        record(self, batch, *args)

    monkeypatch.setattr(Checkpoint, "record", interrupting)
    with pytest.raises(KeyboardInterrupt):
        vm.sweep(scene, out=out, chunk_size=1024, **SMALL)  # one reading (or one row) per batch
    monkeypatch.undo()
    with xr.open_zarr(out, consolidated=False) as partial:
        done = partial["done"].values  # (wavelength, theta_i)
        flat = np.flatnonzero(done.T.ravel())  # reading k = i_theta * n_lam + i_lam
        assert sorted(flat) == sorted(int(k) for b in calls for k in b)  # every batch written as it finished
        for name in Counts.names():
            assert np.array_equal(partial[name].values[done], getattr(whole, name)[done], equal_nan=True)
        assert not np.any(partial["rays"].values[~done])  # nothing else written yet
    recorded = json.loads((tmp_path / "table.zarr.partial.json").read_text())["done"]
    assert set(recorded) == {int(k) for k in calls[0]}
    with pytest.raises(ValueError, match="not a complete virtspec-mi Zarr result"):
        vm.read_result(out)
    resumed = vm.sweep(scene, out=out, chunk_size=1024, **SMALL)
    same_counts(resumed, whole)
    back = vm.read_result(out)
    same_counts(back, whole)
    assert back.dims == whole.dims and back.settings == resumed.settings and back.scene == whole.scene
    with xr.open_zarr(out, consolidated=False) as table:
        assert np.allclose(table["reflectance"].values, whole.reflectance)


def test_a_two_stage_result_round_trips_through_zarr(dielectric, tmp_path):
    reading = vm.measure(dielectric, wavelengths="500 600", bound="two-stage", mu=0.02)
    path = reading.write(tmp_path / "reading.zarr")
    back = vm.read_result(path)
    same_counts(back.squeeze(), reading)
    same_counts(back.pilot.map(lambda v: v.ravel()), reading.pilot)


def test_a_zarr_out_that_is_a_file_is_refused(dielectric, tmp_path):
    (tmp_path / "table.zarr").write_text("")
    with pytest.raises(ValueError, match="is a file; a Zarr store is a directory"):
        vm.sweep(dielectric, out=tmp_path / "table.zarr", **SMALL)


def test_batches_in_any_order_land_in_their_cells_and_whole_rows_merge(tmp_path):
    from virtspec_mi.zarr_table import ZarrTable

    n_lam, n_theta = 7, 4
    table = ZarrTable(tmp_path / "t.zarr", np.arange(n_lam) * 5 + 400.0, np.arange(n_theta) * 10.0, {"test": 1},
                      pilot=False)
    for part in np.array_split(np.random.default_rng(1).permutation(n_lam * n_theta), 5):
        counts = Counts(**{name: (part + 1).astype(np.float64 if name == "largest_weight" else np.int64)
                           for name in Counts.names()})
        table.write(part, counts, None)
    table.flush()
    with xr.open_zarr(tmp_path / "t.zarr", consolidated=False) as store:
        assert np.array_equal(store["rays"].values, (np.arange(n_lam * n_theta) + 1).reshape(n_theta, n_lam).T)
        assert store["done"].values.all()
    regions = [(len(rows), lam, theta, rows_of_theta) for rows, lam, theta, rows_of_theta
               in table._regions(np.arange(3, 3 * n_lam + 2))]
    assert regions == [(4, 3, 0, 1), (14, 0, 1, 2), (2, 0, 3, 1)]  # a tail, two whole rows as one, a head
