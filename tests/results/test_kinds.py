"""
Tests of virtspec_mi.results.kinds and the files of every result kind: ``vm.read_result``
reads each kind in each format back exactly (``as_dict()``-equal), by its format tag;
files written before the result family (``tests/data/results_before_21``, made by
cff7fea) still read, with the same counts and derived values; a file of another kind or
of a newer format is refused with the reason.
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
        "sphere point": sphere.sel(point=1, wavelength=550)}


def test_every_kind_measured_through_the_api_records_its_scene_and_defines(results, tmp_path):
    assert results["gonio"].source == {"scene": "mi.Scene, specimen RoughDielectric", "defines": {}}
    assert results["sphere"].source == {"scene": "sphere_150mm_8d", "defines": {}}  # a shipped scene by its path
    reading = vm.measure("diamond_conical", defines={"theta_i": 30}, rays=300)  # a shipped scene by name
    assert reading.source == {"scene": "diamond_conical", "defines": {"theta_i": "30"}}
    attrs = vm.read_result(reading.write(tmp_path / "reading.nc")).to_dataset().attrs
    assert attrs["scene_name"] == "diamond_conical" and json.loads(attrs["defines"]) == {"theta_i": "30"}


@pytest.mark.parametrize("suffix", SUFFIXES)
@pytest.mark.parametrize("name", ["hemispherical sweep", "hemispherical reading", "gonio", "sphere", "sphere grid",
                                  "sphere point"])
def test_every_kind_round_trips_exactly_in_every_format(results, tmp_path, name, suffix):
    result = results[name]
    path = result.write(tmp_path / f"result{suffix}")
    back = vm.read_result(path)
    assert type(back) is type(result) and back.dims == result.dims
    assert back.as_dict() == result.as_dict(), (name, suffix)
    assert type(result).read(path).as_dict() == result.as_dict()
    assert read_result(path).as_dict() == result.as_dict()


def test_the_format_tags_of_the_kinds():
    from virtspec_mi.instruments import INSTRUMENTS  # every instrument's kind registers when its class is defined

    assert {word: kind.FORMAT for word, kind in KINDS.items()} == {
        "result": "virtspec-mi result 1", "gonio": "virtspec-mi gonio 1", "sphere": "virtspec-mi sphere 1",
        "gloss": "virtspec-mi gloss 1"}
    assert {instrument.result for instrument in INSTRUMENTS.values()} <= set(KINDS.values())


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
