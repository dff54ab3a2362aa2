"""
Tests of virtspec_mi.results.integrity: every rule a result file is read by, with its
message — counts that are not whole numbers or lie beyond their whole, parts that do not
add up, shapes that do not match the dims, labels that are not finite or repeat, a tag or
version this version does not read, a file edited after it was written (its checksum; a
NetCDF variable, a CSV row, a Zarr table's count that disagrees with the result it holds)
— for every kind and format, ``virtspec measure --json`` output included. Each bad file
gives one line naming the file and the field.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

import virtspec_mi as vm
from result_kinds import hemispherical_grid, sphere_grid
from result_kinds import gonio_from_counts
from virtspec_mi.results.integrity import MissingFile, checksum, whole_counts

KINDS = {"sweep": hemispherical_grid, "gonio": gonio_from_counts, "sphere": sphere_grid}


def _written(result, path: Path, edit=None, sealed: bool = False) -> Path:
    """``result`` as a JSON file, edited by ``edit(data)``; without its checksum unless ``sealed`` (a hand-made file)."""

    data = json.loads(result.sealed_json()) if sealed else result.as_dict()
    if edit is not None:
        edit(data)
    path.write_text(json.dumps(data))
    return path


def _refused(path: Path, pattern: str) -> str:
    with pytest.raises(ValueError) as caught:
        vm.read_result(path)
    message = str(caught.value)
    assert message.startswith(f"result file {path}: "), message
    assert "\n" not in message
    assert re.search(pattern, message), message
    return message


def _set(*keys_and_value):
    *keys, value = keys_and_value

    def edit(data):
        for key in keys[:-1]:
            data = data[key]
        data[keys[-1]] = value

    return edit


# -- 1. whole counts ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("value, message", [
    (18.5, r"'reflected' holds 18\.5 at index \[1, 2, 0\], not a whole number"),
    ("12", r"'reflected' holds '12' at index \[1, 2, 0\], not a count"),
    (None, r"'reflected' holds None at index \[1, 2, 0\], not a count"),
    (True, r"'reflected' holds True at index \[1, 2, 0\], not a count"),
    (-3, r"'reflected' holds -3 at index \[1, 2, 0\], a negative count"),
    (float("nan"), r"'reflected' holds nan at index \[1, 2, 0\], not a whole number"),
    (float("inf"), r"'reflected' holds inf at index \[1, 2, 0\], not a whole number"),
    (10**400, r"'reflected' holds a number of 401 digits at index \[1, 2, 0\], beyond the counts a file holds"),
])
def test_a_count_that_is_not_a_whole_number_is_refused_by_name(tmp_path, value, message):
    path = _written(hemispherical_grid(), tmp_path / "sweep.json", _set("reflected", 1, 2, 0, value))
    _refused(path, message)


def test_whole_counts_takes_integral_floats_and_refuses_the_rest():
    np.testing.assert_array_equal(whole_counts([3.0, 4.0], "n"), [3, 4])
    assert whole_counts(np.array([1, 2], dtype=np.uint8), "n").dtype == np.int64
    for bad in ([[1, 2], [3]], [1.5], np.array(["1"]), [True], [2.0**60]):
        with pytest.raises(ValueError, match="'n'"):
            whole_counts(bad, "n")


# -- 2. labels, 3. shapes -------------------------------------------------------------------------------------------


@pytest.mark.parametrize("edit, message", [
    (_set("wavelengths", 1, None), r"'wavelengths' holds nan at index \[1\], not a finite number"),
    (_set("wavelengths", 1, "550"), r"'wavelengths' holds '550' at index \[1\], not a number"),
    (_set("theta_i", 1, 0.0), r"coordinate 'theta_i' must hold distinct labels \(got \[0\.0, 0\.0, 60\.0\]\)"),
    (_set("theta_i", 1, 95.0), r"coordinate 'theta_i' must satisfy 0 <= theta_i <= 90 degrees \(95\.0 at index \[1\]\)"),
    (_set("wavelengths", [400.0, 550.0]), r"'rays' has shape \(3, 3, 2\); its dims wavelength \(2\)"),
    (_set("reflected", [[1, 2], [3, 4]]), r"'reflected' has shape \(2, 2\); its dims wavelength \(3\) x theta_i \(3\) x "
                                          r"specimen\.thickness \(2\) give \(3, 3, 2\)"),
    (_set("dims", ["wavelength", "wavelength", "theta_i"]), r"'dims' must be distinct names"),
    (_set("parameters", "names", True), r"'parameters' must be null or an object with distinct 'names'"),
    (_set("source", "defines", "seed", 3), r"'source' must be null or an object of a 'scene' name and its 'defines'"),
    (_set("source", "scene", None), r"'source' must be null or an object of a 'scene' name"),
])
def test_labels_and_shapes_are_checked(tmp_path, edit, message):
    _refused(_written(hemispherical_grid(), tmp_path / "sweep.json", edit), message)


def test_the_points_of_a_parameter_list_are_numbered(tmp_path):
    path = _written(sphere_grid(), tmp_path / "sphere.json", _set("parameter_coords", "point", [1, 0]))
    _refused(path, r"coordinate 'point' must number the points 0 \.\.\. 1")


def test_labels_in_the_order_asked_for_are_kept(tmp_path):
    reading = hemispherical_grid().isel(wavelength=[2, 0], theta_i=1, **{"specimen.thickness": 0})
    assert list(vm.read_result(reading.write(tmp_path / "r.json")).wavelengths) == [700.0, 400.0]


# -- 4. counts add up, as each kind says ------------------------------------------------------------------------------


@pytest.mark.parametrize("kind, edit, message", [
    ("sweep", _set("reflected", 1, 2, 0, 10_001),
     r"'reflected' holds a count above 'rays' \(reading wavelength=550, theta_i=60, specimen\.thickness=0\.0001\)"),
    ("sweep", _set("specular_reflected", 0, 0, 0, 9000), r"'specular_reflected' holds a count above 'reflected'"),
    ("sweep", _set("transmitted", 0, 0, 0, 9000),
     r"'reflected' \+ 'transmitted' \+ 'capped' \+ 'invalid_directions' add up to more than 'rays' \(reading "
     r"wavelength=400, theta_i=0, specimen\.thickness=0\.0001\)"),
    ("sweep", _set("rays", 0, 0, 0, 0), r"'rays' must be at least 1"),
    ("sweep", _set("absorbed", 0, 0, 0, 1),
     r"'reflected' \+ 'transmitted' \+ 'absorbed' \+ 'capped' \+ 'invalid_directions' must add up to 'rays' \(reading "
     r"wavelength=400, theta_i=0, specimen\.thickness=0\.0001\)"),
    ("gonio", _set("bin_counts", 0, 1, 0, 2, 10**4),
     r"'bin_counts \(theta_o < 90\)' holds a count above 'reflected' \(reading wavelength=400, theta_i=50\)"),
    ("gonio", _set("bin_counts", 0, 0, 1, 0, 10**4), r"'bin_counts \(theta_o > 90\)' holds a count above 'transmitted'"),
    ("gonio", _set("bin_counts", 0, 0, 1, 0, -1), r"'bin_counts' holds -1 at index \[0, 0, 1, 0\], a negative count"),
    ("sphere", _set("counts", "standard", "absorbed_wall", 2, 1, 0, 0),
     r"counts\['standard'\] 'detected' \+ 'absorbed_wall' \+ 'absorbed_specimen' \+ 'absorbed_other' \+ 'capped' \+ "
     r"'invalid_directions' \+ 'lost_entrance' must add up to 'rays' \(reading wavelength=700, theta_i=10, point=0\)"),
    ("sphere", _set("counts", "sample", "hemispherical_specular", 0, 0, 0, 19_999),
     r"counts\['sample'\] 'hemispherical_specular' holds a count above 'hemispherical_reflected'"),
    ("sphere", _set("counts", "sample", "lost_entrance", 0, 0, 0, 100.5),
     r"counts\['sample'\] 'lost_entrance' holds 100\.5 at index \[0, 0, 0\], not a whole number"),
    ("sphere", _set("wall_reflectance", 0, 0, 0, 1.5), r"'wall_reflectance' must satisfy 0 <= wall_reflectance <= 1"),
    ("sphere", _set("counts", "other", {}), r"'counts' must hold the counts of the configurations sample, standard"),
])
def test_counts_that_do_not_add_up_are_refused_with_the_reading(tmp_path, kind, edit, message):
    _refused(_written(KINDS[kind](), tmp_path / f"{kind}.json", edit), message)


def test_the_rules_hold_for_every_original_kind():
    from virtspec_mi.results.integrity import check_result

    for make in KINDS.values():
        check_result(make())


# -- 5. tags and versions ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("tag, message", [
    ("virtspec-mi result 2", r"written in format 'virtspec-mi result 2' by a newer virtspec-mi.*upgrade"),
    ("virtspec-mi result 0", r"format 'virtspec-mi result 0' is not read by this version"),
    ("virtspec-mi weird 1", r"not a virtspec-mi result kind: format 'virtspec-mi weird 1'"),
    (7, r"not a virtspec-mi result \(format '7'\)"),
])
def test_a_tag_or_version_this_version_does_not_read_is_refused(tmp_path, tag, message):
    _refused(_written(hemispherical_grid(), tmp_path / "sweep.json", _set("format", tag)), message)


# -- 6. what a file shows agrees with what it rebuilds, 7. checksums ---------------------------------------------------


@pytest.mark.parametrize("kind", list(KINDS))
def test_a_sealed_file_changed_after_writing_is_refused(tmp_path, kind):
    result = KINDS[kind]()
    path = result.write(tmp_path / f"{kind}.json")
    data = json.loads(path.read_text())
    assert data["checksum"] == checksum(data) == json.loads(result.sealed_json())["checksum"]
    data.get("result", data)["seconds"] = 99.0  # a field no rule checks: only the checksum sees the change
    path.write_text(json.dumps(data))
    _refused(path, r"its content does not match its checksum \('sha256:[0-9a-f]+\.\.\.\): the file was changed after "
                   r"virtspec-mi wrote it")
    del data["checksum"]  # a hand-made file: read by the rules alone
    path.write_text(json.dumps(data))
    assert vm.read_result(path).seconds == 99.0


@pytest.mark.parametrize("kind, variable, index, value", [
    ("sweep", "reflected", (0, 0, 0), 20_000), ("gonio", "bin_counts", (0, 0, 0, 0), 7),
    ("sphere", "detected", (0, 0, 0, 1), 3)])
@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_an_edited_dataset_variable_is_refused_not_ignored(tmp_path, kind, variable, index, value, suffix):
    import xarray as xr

    path = KINDS[kind]().write(tmp_path / f"{kind}{suffix}")
    with (xr.open_zarr(path, consolidated=False, chunks=None) if suffix == ".zarr" else xr.open_dataset(path)) as ds:
        dataset = ds.load()
    dataset[variable][index] = value  # edited with xarray, every attribute kept
    edited = tmp_path / f"edited{suffix}"
    dataset.to_zarr(edited, consolidated=False) if suffix == ".zarr" else dataset.to_netcdf(edited)
    if kind == "sweep" and suffix == ".zarr":  # a sweep's table: its counts are its variables, so a rule speaks
        _refused(edited, r"'reflected' holds a count above 'rays' \(reading wavelength=400, theta_i=0, "
                         r"specimen\.thickness=0\.0001\)")
    else:
        _refused(edited, rf"variable '{variable}' holds {value} at index \[{', '.join(map(str, index))}\] where the "
                         "result the file holds gives")


@pytest.mark.parametrize("kind", list(KINDS))
def test_an_edited_or_truncated_csv_file_is_refused(tmp_path, kind):
    path = KINDS[kind]().write(tmp_path / f"{kind}.csv")
    head, *rows = path.read_text().splitlines()
    columns = rows[0].split(",")
    cells = rows[1].split(",")
    at = columns.index("rays")
    cells[at] = str(int(cells[at]) + 1)
    path.write_text("\n".join([head, rows[0], ",".join(cells), *rows[2:]]) + "\n")
    _refused(path, r"column 'rays' holds \d+ at index \[0\] where the result the file holds gives")
    path.write_text("\n".join([head, *rows[:-1]]) + "\n")
    _refused(path, r"holds \d+ rows; the result in its header gives \d+ \(a truncated or edited file\)")


def test_a_zarr_table_changed_after_writing_is_refused(tmp_path):
    import zarr

    path = hemispherical_grid().write(tmp_path / "sweep.zarr")
    group = zarr.open_group(str(path), mode="r+")
    values = group["specular_reflected"][...]
    values[0, 0, 0] -= 1  # still within its rules: only the checksum sees it
    group["specular_reflected"][...] = values
    _refused(path, r"its content does not match its checksum")


# -- files that are missing, or not results --------------------------------------------------------------------------


def test_a_missing_file_is_both_a_file_not_found_and_a_value_error(tmp_path):
    for suffix in (".nc", ".csv", ".json", ".zarr"):
        with pytest.raises(FileNotFoundError, match=f"result file {tmp_path}/none{suffix}: not found") as caught:
            vm.read_result(tmp_path / f"none{suffix}")
        assert isinstance(caught.value, (ValueError, MissingFile))


@pytest.mark.parametrize("suffix, content, message", [
    (".json", "[1, 2]", r"is not a virtspec-mi result \(a JSON list, not an object\)"),
    (".json", "{\"format\": " * 100_000, r"is not valid JSON"),
    (".json", "\udcff", r"is not (UTF-8 text|valid JSON)"),
    (".csv", "# virtspec-mi result [1]\na\n1\n", r"has a bad header line \(not a JSON object\)"),
    (".nc", "CDF\x01 not really", r"could not be read as NetCDF"),
])
def test_a_file_that_is_no_result_is_refused_in_one_line(tmp_path, suffix, content, message):
    path = tmp_path / f"x{suffix}"
    path.write_bytes(content.encode("utf-8", "surrogateescape"))
    _refused(path, message)


# -- `virtspec measure --json` output --------------------------------------------------------------------------------


def test_measure_json_output_is_sealed_and_checked(mi, tmp_path, capsys):
    from virtspec_mi.cli import main

    assert main(["measure", "scenes/diamond_conical.xml", "--rays", "300", "--wavelengths", "450,550", "--json"]) == 0
    path = tmp_path / "measure.json"
    path.write_text(capsys.readouterr().out)
    reading = vm.read_result(path)
    assert reading.rays.tolist() == [300, 300]
    data = json.loads(path.read_text())
    data["reflected"][1] = 301
    path.write_text(json.dumps(data))
    _refused(path, r"'reflected' holds a count above 'rays' \(reading wavelength=550, theta_i=")
    del data["checksum"]
    data["reflected"][1] = 12.5
    path.write_text(json.dumps(data))
    _refused(path, r"'reflected' holds 12\.5 at index \[1\], not a whole number")


# -- what a file states beside its counts ----------------------------------------------------------------------------


def _at_first(key, value):
    def edit(data):
        entry = data[key]
        while isinstance(entry[0], list):
            entry = entry[0]
        entry[0] = value

    return edit


@pytest.mark.parametrize("edit, message", [
    (_at_first("rays_spent", 1), r"'rays_spent' states 1 at index \[0, 0, 0\] where the file's counts give 10000"),
    (_at_first("certified_mu", 1e-6), r"'certified_mu' states 1e-06 at index \[0, 0, 0\] where the file's counts give"),
    (_set("settings", "bound", "two-stage"), r"the settings say two-stage .* but the file holds no pilot counts"),
])
def test_a_certificate_edited_against_its_counts_is_refused(tmp_path, edit, message):
    _refused(_written(hemispherical_grid(), tmp_path / "edited.json", edit), message)
    vm.read_result(_written(hemispherical_grid(), tmp_path / "plain.json"))  # the file as written reads


@pytest.mark.parametrize("value, message", [(0, r"options.standard must satisfy 0 < options.standard <= 1 \(got 0\)"),
                                            (2.0, r"options.standard must satisfy 0 < options.standard <= 1"),
                                            ("x", r"options.standard must be a number")])
def test_a_sphere_file_with_an_impossible_standard_is_refused(tmp_path, value, message):
    _refused(_written(sphere_grid(), tmp_path / "sphere.json", _set("options", "standard", value)), message)
