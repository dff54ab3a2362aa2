"""
Tests of virtspec_mi.results.formats: every data variable and coordinate of every kind's
dataset carries ``units`` and ``long_name`` (in memory, in NetCDF, in a Zarr table of a
sweep), from one table; format tags are parsed strictly and found in files of every era.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import virtspec_mi as vm
from result_kinds import gonio_reading, hemispherical_grid, sphere_grid, sphere_reading
from virtspec_mi.results.formats import VARIABLES, describe_variable, format_parts, tagged


@pytest.fixture(scope="module")
def datasets(mi):
    gonio, sphere = gonio_reading(), sphere_reading()
    return {"hemispherical sweep": hemispherical_grid().to_dataset(), "hemispherical reading": vm.measure(
        vm.instrument_scene({"type": "plastic"}), wavelengths=[450, 600], rays=500).to_dataset(),
        "gonio": gonio.to_dataset(), "gonio selected": gonio.sel(theta_i=10).to_dataset(),
        "sphere": sphere.to_dataset(), "sphere grid": sphere_grid().to_dataset()}


def unlabelled(dataset):
    return [str(name) for name in (*dataset.data_vars, *dataset.coords)
            if not (dataset[name].attrs.get("units") and dataset[name].attrs.get("long_name"))]


@pytest.mark.parametrize("name", ["hemispherical sweep", "hemispherical reading", "gonio", "gonio selected", "sphere",
                                  "sphere grid"])
def test_every_variable_and_coordinate_has_units_and_a_long_name(datasets, tmp_path, name):
    dataset = datasets[name]
    assert unlabelled(dataset) == []
    assert dataset["wavelength"].attrs["units"] == "nm" and dataset["theta_i"].attrs["units"] == "degree"
    assert dataset.attrs["format"].startswith("virtspec-mi ") and "result_json" in dataset.attrs
    dataset.to_netcdf(tmp_path / "d.nc")
    with xr.open_dataset(tmp_path / "d.nc") as written:
        assert unlabelled(written) == []


def test_the_units_of_what_they_are(datasets):
    gonio, sphere = datasets["gonio"], datasets["sphere grid"]
    assert gonio["brdf"].attrs["units"] == "1/sr" and gonio["solid_angle"].attrs["units"] == "sr"
    assert gonio["theta_o_lower"].attrs["units"] == "degree" and gonio["bin_counts"].attrs["units"] == "1"
    assert sphere["detected"].dims == ("wavelength", "theta_i", "point", "configuration")
    assert list(sphere["configuration"].values) == ["sample", "standard"]
    assert sphere["lost_entrance"].attrs["long_name"] == "rays lost through port 'entrance'"
    assert sphere["specimen.reflectance"].attrs["long_name"] == ("specimen parameter specimen.reflectance "
                                                                 "(mi.traverse key specimen.reflectance.value)")
    assert datasets["hemispherical sweep"]["specimen.thickness"].attrs["units"] == "as in the specimen plugin"


def test_a_zarr_table_of_a_sweep_has_units_too(mi, tmp_path):
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": 0.4})
    two = vm.sweep(scene, theta_i=[0, 30], wavelengths=[500], bound="two-stage", mu=0.05, progress=False,
                   out=tmp_path / "t.zarr")
    with xr.open_zarr(tmp_path / "t.zarr", consolidated=False) as store:
        assert unlabelled(store) == [] and store["pilot_rays"].attrs["long_name"].startswith("two-stage pilot")
        np.testing.assert_array_equal(store["rays"].values, two.rays)


def test_one_table_and_a_clear_error_for_a_name_not_in_it():
    assert describe_variable("pilot_reflected") == ("1", "two-stage pilot (spent, not in the estimates): rays "
                                                         "reflected into the upper hemisphere")
    assert all(len(units) and len(long_name) for units, long_name in VARIABLES.values())
    with pytest.raises(KeyError, match="no units and long_name for the dataset variable 'glow'"):
        describe_variable("glow")


def test_format_tags_are_a_word_and_a_version():
    assert format_parts("virtspec-mi gonio 1") == ("gonio", 1)
    for bad in ("virtspec-mi gonio", "virtspec-mi Gonio 1", "gonio 1", None, 3):
        with pytest.raises(ValueError, match="not a virtspec-mi result"):
            format_parts(bad)
    assert tagged(("plain", {"kind": "sphere_result"}))[0] == "virtspec-mi sphere 0"
    with pytest.raises(ValueError, match="no result_json attribute"):
        tagged(("dataset", xr.Dataset(attrs={"a": 1})))
    with pytest.raises(ValueError, match="its result_json attribute is not JSON"):
        tagged(("dataset", xr.Dataset(attrs={"result_json": "{"})))
