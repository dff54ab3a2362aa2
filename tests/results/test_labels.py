"""
Tests of virtspec_mi.results.labels: the labels every result kind shares — ``isel`` /
``sel`` (nearest, lists, slices; the same kind back; a scalar label drops its dim),
``squeeze``, ``as_grid`` — with the clear error of what a kind keeps whole.
"""

from __future__ import annotations

import numpy as np
import pytest

from result_kinds import THICKNESS


def kinds(hemispherical, gonio, sphere):
    return {"hemispherical": hemispherical, "gonio": gonio, "sphere": sphere}


# --- isel / sel on every kind -------------------------------------------------------------


def counts_of(result):
    """Every stored array of a result of any kind, by name (what selection slices)."""

    return {name: values for name, (_, values) in result._labelled().items()}


@pytest.mark.parametrize("kind", ["hemispherical", "gonio", "sphere"])
def test_a_scalar_label_drops_its_dim_and_keeps_the_kind(hemispherical, gonio, sphere, kind):
    result = kinds(hemispherical, gonio, sphere)[kind]
    one = result.sel(wavelength=550)
    assert type(one) is type(result) and "wavelength" not in one.dims
    assert float(one.coords["wavelength"]) == 550.0 and np.ndim(one.coords["wavelength"]) == 0
    whole, part = counts_of(result), counts_of(one)
    axis = result.dims.index("wavelength")
    for name, values in whole.items():
        np.testing.assert_array_equal(part[name], np.take(values, 1, axis=axis), err_msg=name)
    assert one.dims == tuple(d for d in result.dims if d != "wavelength")
    assert float(result.isel(wavelength=1).coords["wavelength"]) == 550.0
    assert result.isel(wavelength=-2).as_dict() == one.as_dict()


@pytest.mark.parametrize("kind", ["hemispherical", "gonio", "sphere"])
def test_nearest_lists_and_slices_on_every_kind(hemispherical, gonio, sphere, kind):
    result = kinds(hemispherical, gonio, sphere)[kind]
    with pytest.raises(ValueError, match=r"wavelength must be one of the result's labels \[400.0, 550.0, 700.0\] "
                                         r"\(got 530; method='nearest' takes the nearest\)"):
        result.sel(wavelength=530)
    near = result.sel(wavelength=530, method="nearest")
    assert near.as_dict() == result.sel(wavelength=550).as_dict()
    picked = result.sel(wavelength=[710, 390], method="nearest")  # a list keeps the dim, in the order asked
    assert type(picked) is type(result) and picked.sizes["wavelength"] == 2
    np.testing.assert_array_equal(picked.coords["wavelength"], [700, 400])
    axis = result.dims.index("wavelength")
    for name, values in counts_of(result).items():
        np.testing.assert_array_equal(counts_of(picked)[name], np.take(values, [2, 0], axis=axis), err_msg=name)
    sliced = result.sel(wavelength=slice(450, 700))  # both ends included, as xarray
    np.testing.assert_array_equal(sliced.coords["wavelength"], [550, 700])
    assert sliced.as_dict() == result.isel(wavelength=slice(1, None)).as_dict() == result.isel(
        wavelength=[1, 2]).as_dict()
    open_end = result.sel(wavelength=slice(None, 550))
    np.testing.assert_array_equal(open_end.coords["wavelength"], [400, 550])
    with pytest.raises(ValueError, match="holds none of the result's labels"):
        result.sel(wavelength=slice(750, 800))
    with pytest.raises(ValueError, match="does not apply to a slice"):
        result.sel(wavelength=slice(400, 550), method="nearest")
    with pytest.raises(ValueError, match=r"method must be None or 'nearest' \(got 'pad'\)"):
        result.sel(wavelength=550, method="pad")


def test_parameter_dims_and_points_select_like_any_dim(hemispherical, sphere):
    thin = hemispherical.sel(**{"specimen.thickness": 1.1e-4}, method="nearest")
    assert thin.dims == ("wavelength", "theta_i") and float(thin.coords["specimen.thickness"]) == THICKNESS[0]
    np.testing.assert_array_equal(thin.reflected, hemispherical.reflected[..., 0])
    assert "specimen parameters: specimen.thickness = 0.0001" in thin.summary()
    point = sphere.sel(point=1)  # a point: its parameters become scalar labels
    assert point.dims == ("wavelength", "theta_i", "configuration")
    assert float(point.coords["specimen.reflectance"]) == 0.6
    np.testing.assert_array_equal(point.counts["standard"]["rays"], sphere.counts["standard"]["rays"][..., 1])
    np.testing.assert_array_equal(point.reading, sphere.reading[..., 1])
    both = sphere.sel(point=1, theta_i=9.2, method="nearest")
    assert both.dims == ("wavelength", "configuration") and float(both.coords["theta_i"]) == 10.0
    np.testing.assert_array_equal(both.reading_interval, sphere.reading_interval[:, 1, 1])


def test_a_scalar_label_may_be_given_its_own_value(hemispherical):
    reading = hemispherical.sel(theta_i=30)
    assert reading.sel(theta_i=30).as_dict() == reading.as_dict()  # the θi of a single reading: no change
    assert reading.sel(theta_i=31, method="nearest").as_dict() == reading.as_dict()
    with pytest.raises(ValueError, match=r"theta_i must be the result's label 30 \(got 31"):
        reading.sel(theta_i=31)


@pytest.mark.parametrize("kind", ["hemispherical", "gonio", "sphere"])
def test_bad_selections_name_the_dim_and_what_is_allowed(hemispherical, gonio, sphere, kind):
    result = kinds(hemispherical, gonio, sphere)[kind]
    with pytest.raises(ValueError, match=r"'colour' is not a dim of this result \(dims: wavelength, theta_i"):
        result.sel(colour=1)
    with pytest.raises(ValueError, match=r"the index of 'wavelength' must be an integer in \[-3, 3\) \(got 3\)"):
        result.isel(wavelength=3)
    with pytest.raises(ValueError, match=r"the index of 'wavelength' must be an integer .*got 1.5"):
        result.isel(wavelength=1.5)
    with pytest.raises(ValueError, match="holds no label"):
        result.isel(wavelength=[])
    with pytest.raises(ValueError, match="a label of wavelength must be a number"):
        result.sel(wavelength="green")


def test_the_bins_of_a_goniophotometer_stay_whole_with_the_reason(gonio):
    assert gonio.dims == ("wavelength", "theta_i", "theta_o", "phi_o")
    for call in (lambda: gonio.sel(theta_o=45), lambda: gonio.isel(phi_o=0)):
        with pytest.raises(ValueError, match=r"a goniophotometer reading keeps whole: its certificate is a union over "
                                             r"all K bins; select bins in to_dataset\(\)"):
            call()
    one = gonio.sel(theta_i=50, wavelength=[400, 700])
    assert one.dims == ("wavelength", "theta_o", "phi_o") and one.bin_counts.shape == (2, 6, 2)
    np.testing.assert_array_equal(one.bin_counts, gonio.bin_counts[[0, 2], 1])
    np.testing.assert_array_equal(one.bins_mu, gonio.bins_mu[[0, 2], 1])  # the certificate: still K = 12 bins
    np.testing.assert_array_equal(one.brdf_upper, gonio.brdf_upper[[0, 2], 1])
    assert "K = 12 bins" in one.summary() and repr(one).startswith("GonioResult(2 wavelength x 6 theta_o x 2 phi_o")


def test_a_sphere_keeps_both_configurations_with_the_reason(sphere):
    assert sphere.dims[-1] == "configuration" and sphere.sizes["configuration"] == 2
    assert list(sphere.coords["configuration"]) == ["sample", "standard"]
    assert sphere.reading_dims == ("wavelength", "theta_i", "point") and sphere.rays.shape == (3, 2, 2, 2)
    with pytest.raises(ValueError, match=r"'configuration' is a dim a integrating-sphere reading keeps whole: a "
                                         r"reading is the ratio of both configurations"):
        sphere.sel(configuration=0)
    np.testing.assert_array_equal(sphere.rays[..., 1], sphere.counts["standard"]["rays"])  # N per configuration


@pytest.mark.parametrize("kind", ["hemispherical", "gonio", "sphere"])
def test_as_grid_and_squeeze_undo_a_scalar_selection(hemispherical, gonio, sphere, kind):
    result = kinds(hemispherical, gonio, sphere)[kind]
    if kind != "gonio":
        result = result.isel({result.reading_dims[-1]: 0})  # no parameter dim: as_grid refuses those (see below)
    single = result.sel(theta_i=result.coords["theta_i"][0], wavelength=700)
    grid = single.as_grid()
    assert grid.dims[:2] == ("wavelength", "theta_i") and grid.shape[:2] == (1, 1)
    assert grid.as_dict() == result.isel(theta_i=[0], wavelength=[2]).as_dict()
    assert grid.squeeze("wavelength", "theta_i").as_dict() == single.as_dict()


def test_as_grid_refuses_parameter_dims_with_an_example(hemispherical, sphere):
    with pytest.raises(ValueError, match=r"dims specimen.thickness \(a parameter sweep\).*"
                                         r"sel\(\*\*\{'specimen.thickness'"):
        hemispherical.as_grid()
    with pytest.raises(ValueError, match=r"isel\(point=0\)"):
        sphere.spectrum()


def test_selections_leave_the_result_untouched(hemispherical, sphere):
    before = hemispherical.as_dict(), sphere.as_dict()
    hemispherical.sel(wavelength=[400, 700]).summary()
    sphere.sel(point=0).summary()
    assert (hemispherical.as_dict(), sphere.as_dict()) == before
    with pytest.raises(AttributeError):  # frozen: nothing is assigned after construction
        sphere.seconds = 1.0
