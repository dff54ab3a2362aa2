"""
Tests of virtspec_mi.results.kinds and the files of every result kind: ``vm.read_result``
reads each kind in each format back exactly (``as_dict()``-equal), by its format tag;
files written before the result family (``tests/data/results_before_21``, made by
cff7fea) still read, with the same counts and derived values; so do the instruments'
files of d42bf42 (``tests/data/results_d42bf42``) and the applications' files of 04d2580
(``tests/data/results_04d2580``: a certified target and its sweep, a fit, an albedo table
with its exports, Klems matrices, a comparison), and an edited one is refused; a file of
another kind or of a newer format is refused with the reason.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import virtspec_mi as vm
from result_kinds import gonio_reading, hemispherical_grid, sphere_grid, sphere_reading
from virtspec_mi.results.kinds import KINDS, read_result

BEFORE = Path(__file__).resolve().parents[1] / "data" / "results_before_21"
SUFFIXES = (".nc", ".csv", ".json", ".zarr")


@pytest.fixture(scope="module")
def results(mi):
    """One result of every kind, and the kinds' labels selected down (scalar labels in the files)."""

    hemispherical, sphere = hemispherical_grid(), sphere_grid()
    return {"hemispherical sweep": hemispherical, "hemispherical reading": hemispherical.sel(
        theta_i=30, **{"specimen.thickness": 2e-4}),
        "gonio": gonio_reading(), "sphere": sphere_reading(), "sphere grid": sphere,
        "sphere point": sphere.sel(point=1, wavelength=550),
        "double sphere": vm.double_sphere("double_sphere_leaf", rays=500, wavelengths=[550, 850], seed=2)}


def test_every_kind_measured_through_the_api_records_its_scene_and_defines(results, tmp_path):
    assert results["gonio"].source == {"scene": "mi.Scene, specimen RoughDielectric", "defines": {}}
    assert results["sphere"].source == {"scene": "sphere_150mm_8d", "defines": {}}  # a shipped scene by its path
    reading = vm.measure("diamond_conical", defines={"theta_i": 30}, rays=300)  # a shipped scene by name
    assert reading.source == {"scene": "diamond_conical", "defines": {"theta_i": "30"}}
    attrs = vm.read_result(reading.write(tmp_path / "reading.nc")).to_dataset().attrs
    assert attrs["scene_name"] == "diamond_conical" and json.loads(attrs["defines"]) == {"theta_i": "30"}


@pytest.mark.parametrize("suffix", SUFFIXES)
@pytest.mark.parametrize("name", ["hemispherical sweep", "hemispherical reading", "gonio", "sphere", "sphere grid",
                                  "sphere point", "double sphere"])
def test_every_kind_round_trips_exactly_in_every_format(results, tmp_path, name, suffix):
    result = results[name]
    path = result.write(tmp_path / f"result{suffix}")
    back = vm.read_result(path)
    assert type(back) is type(result) and back.dims == result.dims
    assert back.as_dict() == result.as_dict(), (name, suffix)
    assert type(result).read(path).as_dict() == result.as_dict()
    assert read_result(path).as_dict() == result.as_dict()


def test_the_format_tags_of_the_kinds():
    from virtspec_mi.applications import APPLICATIONS  # every application's kinds register with its row
    from virtspec_mi.instruments import INSTRUMENTS  # every instrument's kind registers when its class is defined

    assert {word: kind.FORMAT for word, kind in KINDS.items()} == {
        "result": "virtspec-mi result 1", "gonio": "virtspec-mi gonio 1", "sphere": "virtspec-mi sphere 1",
        "gloss": "virtspec-mi gloss 1", "double sphere": "virtspec-mi double sphere 1",
        "derived": "virtspec-mi derived 1",
        "derived sweep": "virtspec-mi derived sweep 1", "fit": "virtspec-mi fit 1",
        "albedo table": "virtspec-mi albedo table 1", "table comparison": "virtspec-mi table comparison 1",
        "klems": "virtspec-mi klems 1", "comparison": "virtspec-mi comparison 1",
        "rgl": "virtspec-mi rgl 1"}
    assert {instrument.result for instrument in INSTRUMENTS.values()} <= set(KINDS.values())
    assert {kind for application in APPLICATIONS.values() for kind in application.results} == \
        set(KINDS.values()) - {kind for kind in KINDS.values() if kind.__module__.startswith("virtspec_mi.results")
                               or kind.__module__.startswith("virtspec_mi.instruments")}


@pytest.mark.parametrize("suffix", [".nc", ".csv", ".json"])
def test_a_file_of_another_kind_is_refused_by_name(results, tmp_path, suffix):
    sphere = results["sphere"].write(tmp_path / f"sphere{suffix}")
    with pytest.raises(ValueError, match=r"this file holds a integrating-sphere reading \(virtspec_mi.SphereResult\) "
                                         r"\(format 'virtspec-mi sphere 1'\), not a hemispherical reading: read it "
                                         "with virtspec_mi.read_result"):
        vm.Result.read(sphere)
    with pytest.raises(ValueError, match="not a goniophotometer reading"):
        vm.read_gonio(sphere)
    gonio = results["gonio"].write(tmp_path / f"gonio{suffix}")
    with pytest.raises(ValueError, match="holds a goniophotometer reading.*not a integrating-sphere reading"):
        vm.SphereResult.read(gonio)
    assert isinstance(vm.read_gonio(gonio), vm.GonioResult)  # read_gonio: the goniophotometer's own reader


def test_a_newer_or_unknown_format_is_refused_with_the_reason(results, tmp_path):
    data = results["sphere"].as_dict()
    for tag, message in (("virtspec-mi sphere 2", "written in format 'virtspec-mi sphere 2' by a newer virtspec-mi; "
                                                  "this version reads up to 'virtspec-mi sphere 1': upgrade"),
                         ("virtspec-mi lamp 1", "not a virtspec-mi result kind: format 'virtspec-mi lamp 1'"),
                         ("sphere", "not a virtspec-mi result \\(format 'sphere'\\)")):
        path = tmp_path / "future.json"
        path.write_text(json.dumps({**data, "format": tag}))
        with pytest.raises(ValueError, match=message):
            vm.read_result(path)


# --- files written before the result family --------------------------------------------------


@pytest.mark.parametrize("name", ["reading", "sweep", "gonio"])
@pytest.mark.parametrize("suffix", [".nc", ".csv", ".json"])
def test_hemispherical_and_gonio_files_of_cff7fea_read_as_they_were_written(name, suffix):
    written = json.loads((BEFORE / f"{name}.json").read_text())  # their as_dict() at cff7fea
    back = vm.read_result(BEFORE / f"{name}{suffix}")
    assert type(back) is (vm.GonioResult if name == "gonio" else vm.Result)
    assert back.as_dict() == written


def test_a_zarr_sweep_of_cff7fea_reads():
    back = vm.read_result(BEFORE / "sweep.zarr")
    assert isinstance(back, vm.Result) and back.dims == ("wavelength", "theta_i") and back.shape == (2, 2)
    assert np.all(back.rays == 300) and back.settings.seed == 2


@pytest.mark.parametrize("suffix", [".json", ".nc"])
def test_sphere_files_of_cff7fea_read_with_their_counts_and_readout(suffix):
    written = json.loads((BEFORE / "sphere.json").read_text())  # the former layout: "kind": "sphere_result"
    assert written["kind"] == "sphere_result"
    back = vm.read_result(BEFORE / f"sphere{suffix}")
    assert isinstance(back, vm.SphereResult) and back.dims == ("wavelength", "configuration") and back.theta_i == 8.0
    np.testing.assert_array_equal(back.wavelengths, written["wavelengths"])
    for configuration, counts in written["counts"].items():
        for name, values in counts.items():
            np.testing.assert_array_equal(back.counts[configuration][name], values, err_msg=name)
        np.testing.assert_array_equal(back.counts[configuration]["rays"], written["rays"])  # one N, now per reading
    np.testing.assert_array_equal(back.reading, written["reading"])
    np.testing.assert_array_equal(back.reading_interval, np.array(written["reading_interval"]).T)
    np.testing.assert_array_equal(back.hemispherical, written["hemispherical"])
    np.testing.assert_array_equal(back.fraction_mu, written["fraction_mu"])
    np.testing.assert_allclose(back.corrected(), vm.SphereResult.from_dict(back.as_dict()).corrected())
    assert back.options == written["options"] and back.sphere_parameters == written["sphere_parameters"]
    again = vm.SphereResult.from_dict(json.loads(json.dumps(back.as_dict())))
    assert again.as_dict() == back.as_dict()  # read, then kept in format 1


def test_every_file_of_cff7fea_reads():
    for path in sorted(BEFORE.iterdir()):
        if path.suffix in SUFFIXES:
            assert vm.read_result(path).summary(), path.name


LAST = Path(__file__).resolve().parents[1] / "data" / "results_d42bf42"
"""Files of every instrument's kind written by d42bf42, the main before the instruments' folders (issue 29)."""


@pytest.mark.parametrize("file", sorted(json.loads((LAST / "manifest.json").read_text())["files"]))
def test_every_file_of_the_last_release_reads_as_the_same_kind_with_the_same_content(file):

    manifest = json.loads((LAST / "manifest.json").read_text())
    back = vm.read_result(LAST / file)
    assert type(back).__name__ == manifest["files"][file]["class"]
    assert type(back).FORMAT == manifest["files"][file]["format"]
    written = manifest[file.rsplit(".", 1)[0]]
    assert json.dumps(back.as_dict(), sort_keys=True, default=lambda v: np.asarray(v).tolist()) == written, file


APPLICATIONS_04D2580 = Path(__file__).resolve().parents[1] / "data" / "results_04d2580"
"""Files of every application's kind written by 04d2580, before they joined the result family (issue 38)."""
_MANIFEST = json.loads((APPLICATIONS_04D2580 / "manifest.json").read_text())


def _canonical(data) -> dict:
    return json.loads(json.dumps(data, sort_keys=True, default=lambda v: np.asarray(v).tolist()))


@pytest.mark.parametrize("file", sorted(name for name in _MANIFEST["files"] if not name.endswith("_avg.npy")))
def test_every_application_file_of_04d2580_reads_to_what_it_held(file):
    entry = _MANIFEST["files"][file]
    held = json.loads(_MANIFEST["held"][entry["class"]])
    if file == "albedo.h":  # a header: the values alone (held to the table below)
        with pytest.raises(ValueError, match="a C header holds an albedo table's values, not its counts"):
            vm.read_result(APPLICATIONS_04D2580 / file)
        return
    if file in ("albedo.json", "albedo.npy"):  # the .npy's sidecar held the description, not the counts
        with pytest.raises(ValueError, match="description without its counts .* read the table's .nc"):
            vm.read_result(APPLICATIONS_04D2580 / file)
        assert json.loads((APPLICATIONS_04D2580 / "albedo.json").read_text()) == held["description"]
        return
    back = vm.read_result(APPLICATIONS_04D2580 / file)
    assert type(back).__name__ == entry["class"]
    if entry["class"] == "AlbedoTable":
        assert back.description() == held["description"]
        for name, values in held["counts"].items():
            np.testing.assert_array_equal(back.counts[name], values, err_msg=name)
        for name, values in held["average_counts"].items():
            np.testing.assert_array_equal(back.average_counts[name], values, err_msg=name)
        np.testing.assert_array_equal(back.E, held["E"])
    elif entry["class"] == "KlemsMeasurement":
        for name in ("counts", "rays", "reflected", "transmitted", "wavelengths"):
            np.testing.assert_array_equal(getattr(back, name), held[name], err_msg=name)
        assert (back.epsilon, back.delta, list(back.sides), back.basis.key) == \
            (held["epsilon"], held["delta"], held["sides"], held["basis"])
    else:  # the kinds that had as_dict(): the same, but for the tag a sweep's and a comparison's now carry
        ours = _canonical(back.as_dict())
        for data in (ours, held):
            data.pop("format", None)
        for each in ours.get("results", [ours]):  # a target's certificate, recorded since (issue 39): the old
            assert each.pop("bound", "hoeffding") == "hoeffding"  # release's files are Hoeffding's, in one batch
            assert each.pop("batches", []) == []
        assert ours == held
    assert back.summary() if hasattr(back, "summary") else back.statement()


def test_the_exports_of_04d2580_hold_the_values_of_its_table():
    table = vm.read_result(APPLICATIONS_04D2580 / "albedo.nc")
    for file in ("albedo.npy", "albedo.h"):  # a published table: the certified table's own values, none outside
        assert table.compare(APPLICATIONS_04D2580 / file).outside == []
    np.testing.assert_array_equal(np.load(APPLICATIONS_04D2580 / "albedo_avg.npy"), table.E_avg.astype(np.float32))
    comparison = table.compare(table.layout() + np.array([[0.0, 0.5], [0.0, 0.0]]))  # as the manifest's
    assert comparison.summary() == _MANIFEST["table_comparison"]["summary"]


def _application_results():
    """One result of every application kind, read from the files of 04d2580, and a comparison of a table."""

    read = {name: vm.read_result(APPLICATIONS_04D2580 / name) for name in
            ("derived.json", "derived_sweep.json", "fit.nc", "albedo.nc", "klems.nc")}
    table = read["albedo.nc"]
    reading = vm.read_result(LAST / "reading.nc")
    spectrum = (np.array([400.0, 500.0, 700.0]), np.array([0.05, 0.06, 0.07]), 0.02)
    return [*read.values(), table.compare(table.layout() + 0.3), vm.compare(reading, spectrum)]


@pytest.fixture(scope="module")
def application_results(mi):
    return _application_results()


@pytest.mark.parametrize("suffix", [".nc", ".json"])
def test_every_application_kind_round_trips_in_every_format_through_read_result(application_results, tmp_path, suffix):
    for result in application_results:
        path = result.write(tmp_path / f"{type(result).__name__}{suffix}")
        back = vm.read_result(path)
        assert type(back) is type(result) and back.as_dict() == result.as_dict(), (type(result).__name__, suffix)
        assert type(result).read(path).as_dict() == result.as_dict()
        dataset = result.to_dataset()
        assert dataset.attrs["format"] == result.FORMAT
        assert all("units" in dataset[name].attrs for name in (*dataset.data_vars, *dataset.coords))


def test_an_edited_application_file_is_refused(application_results, tmp_path):
    import xarray as xr

    derived, sweep, fit, table, klems, published, comparison = application_results
    data = json.loads(derived.sealed_json())
    data["readings"]["reflected"][0] = data["readings"]["rays"][0] + 1  # more reflected rays than rays
    data.pop("checksum")
    (tmp_path / "derived.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match="'reflected' holds a count above 'rays'"):
        vm.read_result(tmp_path / "derived.json")
    data = json.loads(klems.sealed_json())
    data["rays"][0][0][0] = 0  # an incidence without rays
    data.pop("checksum")
    (tmp_path / "klems.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match="'rays' must be at least 1"):
        vm.read_result(tmp_path / "klems.json")
    data = json.loads(fit.sealed_json())
    data["traced_rays"] = data["rays"] + 1
    (tmp_path / "fit.json").write_text(json.dumps(data))  # its checksum no longer matches: refused
    with pytest.raises(ValueError, match="does not match its checksum|'traced_rays' holds a count above 'rays'"):
        vm.read_result(tmp_path / "fit.json")
    data = json.loads(comparison.sealed_json())
    data["points_within"] -= 1
    data.pop("checksum")
    (tmp_path / "comparison.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match="'points_within' disagrees with the result and the measured spectrum"):
        vm.read_result(tmp_path / "comparison.json")
    data = json.loads(published.sealed_json())
    data["outside"] = data["outside"][1:]
    data.pop("checksum")
    (tmp_path / "published.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match="'outside' disagrees with the table and the published values"):
        vm.read_result(tmp_path / "published.json")
    fit.write(tmp_path / "fit.nc")
    with xr.open_dataset(tmp_path / "fit.nc") as opened:
        dataset = opened.load()
    dataset["estimate"].values[0] += 0.1
    dataset.to_netcdf(tmp_path / "edited.nc")
    with pytest.raises(ValueError, match="variable 'estimate' holds .* where the result the file holds gives"):
        vm.read_result(tmp_path / "edited.nc")


def test_the_other_readers_are_read_result_of_their_kind(application_results, tmp_path):
    from virtspec_mi.applications.klems.matrices import read_klems_sidecar

    derived, sweep, fit, table, klems, published, comparison = application_results
    fit_file, table_file, klems_file = (fit.write(tmp_path / "fit.json"), table.write(tmp_path / "table.nc"),
                                        klems.write(tmp_path / "klems.xml"))
    assert vm.read_fit(fit_file).as_dict() == fit.as_dict()
    assert vm.read_albedo_table(table_file).as_dict() == table.as_dict()
    assert read_klems_sidecar(klems_file).as_dict() == vm.read_result(klems_file.with_suffix(".nc")).as_dict()
    with pytest.raises(ValueError, match=r"holds a albedo table .* not a fit"):
        vm.read_fit(table.write(tmp_path / "table.json"))
    with pytest.raises(ValueError, match="a fit is written as .nc, .json"):
        fit.write(tmp_path / "fit.csv")


@pytest.mark.parametrize("file, edit, words", [
    ("albedo.nc", lambda d: d["reflected"].values.__setitem__((0, 0), d["rays"].values[0, 0] + 5),
     "'reflected' holds a count above 'rays'"),
    ("klems.nc", lambda d: d["rays"].values.__setitem__((0, 0, 0), 0), "'rays' must be at least 1"),
    ("fit.nc", lambda d: d.attrs.__setitem__("traced_rays", d.attrs["rays"] + 1), "'traced_rays' holds a count above"),
])
def test_an_edited_file_of_04d2580_is_refused(tmp_path, file, edit, words):
    import xarray as xr

    with xr.open_dataset(APPLICATIONS_04D2580 / file) as opened:
        dataset = opened.load()
    edit(dataset)
    dataset.to_netcdf(tmp_path / file)
    with pytest.raises(ValueError, match=f"result file {tmp_path / file}: .*{words}"):
        vm.read_result(tmp_path / file)
