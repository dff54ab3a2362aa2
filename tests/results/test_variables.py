"""
Tests of virtspec_mi.results.variables: a result kind's dataset is its stored Dataset and
the tables of what it derives (``DERIVED``, ``COORDS``) — every variable of every kind's
``to_dataset()`` is stored or declared, with its units; a kind that adds a variable adds a
row, not a method.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from result_kinds import gonio_reading, hemispherical_grid, sphere_grid
from virtspec_mi.results.base import KINDS
from virtspec_mi.results.variables import READINGS, Coordinate, Variable, bounds, of_reading


@pytest.fixture(scope="module")
def results(mi):
    scene = vm.mitsuba().load_dict(vm.instrument_scene({"type": "roughdielectric", "alpha": 0.3}))
    gloss = vm.take("gloss", scene, theta_i=60, wavelengths=[450, 650], rays=2000, cone=5)
    return {"result": hemispherical_grid(), "gonio": gonio_reading(), "sphere": sphere_grid(), "gloss": gloss}


def test_every_variable_of_every_kind_is_stored_or_in_its_tables(results):
    assert set(results) <= set(KINDS)
    for word, result in results.items():
        dataset = result.to_dataset()
        stored = set(map(str, result.data.variables))
        declared = set(result.DERIVED) | set(result.COORDS)
        assert set(map(str, dataset.variables)) == stored | declared, word
        assert not stored & declared, f"{word}: a stored variable is also derived"
        for name in declared:
            units, long_name = result.described()[name]
            assert dataset[name].attrs["units"] == units and dataset[name].attrs["long_name"] == long_name
        for name, variable in result.DERIVED.items():
            assert dataset[name].dims == variable.dims_of(result)
            assert (dataset[name].dtype.kind == "i") == variable.count, name


def test_the_stored_dataset_holds_exact_counts_and_what_they_were_measured_with(results):
    gonio = results["gonio"]
    assert gonio.data["bin_counts"].dtype == np.int64 and gonio.data["rays"].dims == ("wavelength", "theta_i")
    assert gonio.data.attrs["settings"] is gonio.settings and gonio.data.attrs["bins"] is gonio.bins
    assert gonio.result.data.sizes == {"wavelength": 3, "theta_i": 2}  # the reading it extends, without the bins
    one = gonio.sel(theta_i=50)
    assert one.data.equals(gonio.data.isel(theta_i=1)) and one.settings.theta_i == 50 == one.theta_i[0]
    sphere = results["sphere"]
    assert sphere.data["detected"].dims == ("wavelength", "theta_i", "point", "configuration")
    assert np.array_equal(sphere.counts["standard"]["rays"], sphere.data["rays"].values[..., 1])


def test_a_result_is_read_only(results):
    result = results["result"]
    for name in ("data", "counts", "anything"):
        with pytest.raises(AttributeError, match="read-only"):
            setattr(result, name, None)
    with pytest.raises(AttributeError, match="read-only"):
        del result.data


def test_the_constructor_names_an_array_of_the_wrong_shape():
    good = hemispherical_grid()
    with pytest.raises(ValueError, match=r"'reflected' has shape \(3, 3\); its dims wavelength \(3\) x theta_i "
                                         r"\(3\) x specimen.thickness \(2\) give \(3, 3, 2\)"):
        vm.Result(good.dims, good.coords, type(good.counts)(**{**good.counts.__dict__, "reflected": np.ones((3, 3))}),
                  None, good.settings, good.geometry, 1.0, parameters=good.parameters)
    with pytest.raises(ValueError, match="'glossy' has shape"):
        vm.GlossResult(good, np.ones((2,), dtype=np.int64))


class Percent(vm.Result):
    """A kind that adds a variable and a figure by a row each (no FORMAT: not registered)."""

    DERIVED = {**vm.Result.DERIVED,
               "reflectance_percent": Variable("percent", "reflectance in per cent", lambda r: 100 * r.reflectance),
               "rays_total": Variable("1", "rays of all readings", lambda r: np.full(r.shape, r.rays.sum()),
                                      count=True, csv=False)}
    COORDS = {"wavenumber": Coordinate("1/cm", "wavenumber", ("wavelength",), lambda r: 1e7 / r.wavelengths)}
    FIGURES = {**vm.Result.FIGURES, "percent": vm.Result.FIGURES["spectra"]}


def test_a_new_variable_coordinate_and_figure_are_one_row_each(tmp_path):
    base = hemispherical_grid().isel(theta_i=0, **{"specimen.thickness": 0})
    result = Percent._of(base.data)
    dataset = result.to_dataset()
    assert np.allclose(dataset["reflectance_percent"], 100 * dataset["reflectance"])
    assert dataset["reflectance_percent"].attrs["units"] == "percent" and "wavenumber" in dataset.coords
    assert "rays_total" in result._count_variables() and "rays_total" not in result.csv_dataset()
    back = vm.read_result(result.write(tmp_path / "percent.nc"))  # its file reads as the kind of its format
    assert type(back) is vm.Result and np.array_equal(back.reflected, result.reflected)
    assert result.plot(figure="percent", quantity="transmittance").axes[0].get_ylabel() == "transmittance"


def test_bounds_and_the_variables_of_a_reading_a_kind_extends(results):
    table = bounds({"reflectance": "the reflectance"}, lambda r, name: r.interval(name), lambda r: r.interval_delta)
    reading = results["result"]
    assert set(table) == {"reflectance_lower", "reflectance_upper"}
    assert np.array_equal(table["reflectance_upper"].values(reading), reading.interval("reflectance")[1])
    assert table["reflectance_lower"].attrs(reading) == {"clopper_pearson_delta": reading.interval_delta}
    moved = of_reading({"reflectance": vm.Result.DERIVED["reflectance"], "mu": Variable("1", "mu", lambda r: r.mu,
                                                                                         READINGS)})
    gonio = results["gonio"]
    assert moved["reflectance"].dims_of(gonio) == ("wavelength", "theta_i")
    assert np.array_equal(moved["reflectance"].values(gonio), gonio.result.reflectance)
