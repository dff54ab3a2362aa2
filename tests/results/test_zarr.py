"""Tests of virtspec_mi.results.zarr: a sweep's Zarr store filled region by region, read back as a Result."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

import virtspec_mi as vm
from virtspec_mi.engine.checkpoint import Checkpoint
from virtspec_mi.kernel.counts import Counts

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
    from virtspec_mi.results.zarr import ZarrTable

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
    regions = [(len(rows), at, size) for rows, at, size in table._regions(np.arange(3, 3 * n_lam + 2))]
    # a tail of row 0, two whole rows as one region, a head of row 3 (keyed order: theta_i, wavelength)
    assert regions == [(4, (0, 3), (1, 4)), (14, (1, 0), (2, 7)), (2, (3, 0), (1, 2))]


def test_a_run_of_readings_is_a_few_hyper_rectangles_covering_it_exactly():
    from virtspec_mi.results.zarr import regions

    shape = (3, 2, 4, 5)  # two parameter dims, theta_i, wavelength: k in C order
    rng = np.random.default_rng(3)
    for start, stop in [(0, 120), (7, 8), (7, 63), (20, 100), *map(sorted, rng.integers(0, 121, (20, 2)))]:
        covered = []
        blocks = list(regions(int(start), int(stop), shape))
        assert len(blocks) <= 2 * len(shape) - 1
        for at, size in blocks:
            index = np.indices(size).reshape(len(shape), -1).T + np.asarray(at)
            assert (index < np.asarray(shape)).all()
            covered.extend(np.ravel_multi_index(index.T, shape).tolist())
        assert covered == list(range(start, stop))  # every reading once, in order


PARAMETRIC = {"theta_i": [8, 40], "wavelengths": "450:650:100", "rays": 5000, "progress": False}
"""6 readings per parameter point."""


@pytest.mark.parametrize("scene, parameters, points", [
    ("dict", {"specimen.eta": [1.3, 1.5, 1.7]}, False),
    ("scenes/soybean_abmb.xml", {"specimen.thickness": [1.2e-4, 2e-4], "specimen.chlorophyll_a": [2, 4, 6]},
     False),
    ("scenes/soybean_abmb.xml", {"specimen.thickness": [1.2e-4, 2e-4, 1.6e-4, 1.3e-4],
                                 "specimen.chlorophyll_a": [2, 6, 4, 5]}, True),
], ids=["dielectric-rows", "leaf-grid", "leaf-points"])
def test_an_interrupted_parameter_sweep_into_zarr_resumes_and_equals_the_nc_result(dielectric, monkeypatch,
                                                                                    tmp_path, scene, parameters,
                                                                                    points):
    scene = dielectric if scene == "dict" else scene
    settings = {**PARAMETRIC, "parameters": parameters, "points": points}
    vm.sweep(scene, out=tmp_path / "whole.nc", **settings)
    whole = vm.read_result(tmp_path / "whole.nc")
    out = tmp_path / "table.zarr"
    record = Checkpoint.record
    calls = []

    def interrupting(self, batch, *args):
        calls.append(batch)
        if len(calls) == 4:
            raise KeyboardInterrupt
        record(self, batch, *args)

    monkeypatch.setattr(Checkpoint, "record", interrupting)
    with pytest.raises(KeyboardInterrupt):
        vm.sweep(scene, out=out, chunk_size=1024, **settings)  # one reading (or one theta_i row) per batch
    monkeypatch.undo()
    with xr.open_zarr(out, consolidated=False) as partial:
        assert tuple(partial["done"].dims) == whole.dims
        done = partial["done"].values
        assert done.sum() == sum(len(b) for b in calls) and 0 < done.sum() < done.size
        for name in Counts.names():  # the finished readings in their cells, nothing elsewhere
            assert np.array_equal(partial[name].values[done], getattr(whole, name)[done], equal_nan=True)
        assert not np.any(partial["rays"].values[~done])
        for name in (*parameters, "point"):
            if name in whole.coords:
                assert np.array_equal(partial[name].values, whole.coords[name])
    with pytest.raises(ValueError, match="not a complete virtspec-mi Zarr result"):
        vm.read_result(out)
    resumed = vm.sweep(scene, out=out, chunk_size=1024, **settings)
    back = vm.read_result(out)
    for result in (resumed, back):
        same_counts(result, whole)
        assert result.dims == whole.dims and result.parameters == whole.parameters
        assert all(np.array_equal(result.coords[name], whole.coords[name]) for name in whole.coords)
    assert back.settings == resumed.settings and back.scene == whole.scene
    fresh = vm.read_result(whole.write(tmp_path / "fresh.zarr"))  # Result.write of a parameter sweep, no sweep
    same_counts(fresh, whole)
    assert fresh.dims == whole.dims and fresh.parameters == whole.parameters
    assert back.sel(theta_i=40).isel(**{whole.dims[2]: 1}).reflectance.shape == (3,) + whole.shape[3:]
    with xr.open_zarr(out, consolidated=False) as table:
        assert np.allclose(table["reflectance"].transpose(*whole.dims).values, whole.reflectance)


# --- nothing the project did not write is ever removed (issue 22: a user's file was lost) -------------------------


def _tree(path):
    return sorted((str(p.relative_to(path)), p.read_bytes() if p.is_file() else None) for p in path.rglob("*"))


@pytest.mark.parametrize("where", ["beside", "inside a store of ours"])
def test_a_directory_holding_a_file_of_someone_elses_is_refused_and_kept(dielectric, tmp_path, where):
    from result_kinds import hemispherical_grid, sphere_grid

    out = tmp_path / "table.zarr"
    if where == "beside":
        out.mkdir()
        (out / "notes.txt").write_text("a user's notes")
        stranger = "notes.txt"
    else:
        sphere_grid().write(out)
        (out / "wall_reflections" / "mine.csv").write_text("1,2")
        stranger = "wall_reflections/mine.csv"
    before = _tree(out)
    message = f"out {out} is a directory holding '{stranger}', which virtspec-mi did not write"
    with pytest.raises(ValueError, match=message):
        vm.sweep(dielectric, out=out, **SMALL)  # refused before any tracing
    for result in (hemispherical_grid(), sphere_grid()):
        with pytest.raises(ValueError, match=message):
            result.write(out)
    assert _tree(out) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.zarr"]  # no store, no temporary beside it


def test_a_store_of_ours_and_an_empty_directory_are_replaced_whole(tmp_path):
    from result_kinds import hemispherical_grid, sphere_grid

    out = tmp_path / "result.zarr"
    out.mkdir()
    sphere_grid().write(out)  # an empty directory: written
    grid = hemispherical_grid()
    grid.write(out)  # a store of ours (another kind): replaced, nothing of the sphere's left
    assert vm.read_result(out).as_dict() == grid.as_dict()
    assert not (out / "wall_reflections").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["result.zarr"]


def test_a_zarr_table_that_cannot_be_written_leaves_the_sweep_its_readings(dielectric, tmp_path, monkeypatch):
    import errno

    from virtspec_mi.base.files import WriteError
    from virtspec_mi.results.zarr import ZarrTable

    whole = vm.sweep(dielectric, **SMALL)

    def full(self):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(ZarrTable, "_write_kept", full)
    out = tmp_path / "table.zarr"
    with pytest.warns(RuntimeWarning, match=f"could not write {out}: No space left on device.*: the sweep goes on "
                                            "without its Zarr table"):
        swept = vm.sweep(dielectric, out=out, **SMALL)
    same_counts(swept, whole)
    same_counts(vm.read_result(out), whole)  # written whole when the sweep completed
    monkeypatch.setattr("virtspec_mi.results.zarr.write_result",  # the table streams; its final write fails
                        lambda result, path: (_ for _ in ()).throw(WriteError(path, "No space left on device")))
    with pytest.raises(WriteError, match=f"could not write {out}: No space left on device; every finished reading is "
                                         f"kept in {out}.partial.json") as caught, pytest.warns(RuntimeWarning):
        vm.sweep(dielectric, out=out, **{**SMALL, "seed": 2})
    assert caught.value.result.rays.shape == whole.rays.shape
    with pytest.raises(ValueError, match="is not a complete virtspec-mi Zarr result"):  # never read as complete
        vm.read_result(out)
    monkeypatch.undo()
    caught.value.result.write(tmp_path / "elsewhere.zarr")
    same_counts(vm.read_result(tmp_path / "elsewhere.zarr"), caught.value.result)
