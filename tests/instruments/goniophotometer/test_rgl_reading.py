"""
Goniophotometer readings on the RGL grid (instruments/goniophotometer/rgl_reading.py, binning="rgl"): the cells
of a reading add up to its reflected rays exactly, a cell mean is its count over N Ω_k, the file formats read
back the same reading, and the binning's rules refuse what it cannot certify, naming the option.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.instruments.goniophotometer.rgl_reading import RGLReading

WHITE = {"type": "diffuse", "reflectance": 0.7}


@pytest.fixture(scope="module")
def reading(mi):
    return vm.gonio(vm.instrument_scene(WHITE), theta_i=[0, 45], wavelengths=[550], rays=20_000, binning="rgl",
                    rgl_resolution=6, beam="collimated", seed=5)


def test_the_cells_hold_every_reflected_ray_and_the_means_are_counts_over_solid_angles(reading):
    assert isinstance(reading, RGLReading) and reading.dims == ("wavelength", "theta_i", "cell")
    assert reading.size == 26 and reading.cell_counts.shape == (1, 2, 26)
    np.testing.assert_array_equal(reading.cell_counts.sum(axis=-1), reading.result.reflected)
    omega = reading.solid_angles[0, 1]
    some = omega > 0
    assert 0 < some.sum() < 26  # some cells' half vectors reflect every direction below the horizon
    np.testing.assert_allclose(reading.cell_mean[0, 1][some], reading.cell_counts[0, 1][some] / 20_000 / omega[some])
    assert np.all(reading.cell_counts[0, 1][~some] == 0) and np.all(np.isnan(reading.cell_mean[0, 1][~some]))
    assert np.all(reading.cell_counts[0, 0, 1:][np.isnan(reading.solid_angles[0, 0, 1:])] == 0)  # unused at 0 deg
    lower, upper = reading.cell_mean_lower[0, 1][some], reading.cell_mean_upper[0, 1][some]
    assert np.all((lower <= reading.cell_mean[0, 1][some]) & (reading.cell_mean[0, 1][some] <= upper))
    assert "K = 26 cells (6 x 6 nodes)" in reading.summary()


@pytest.mark.parametrize("suffix", [".json", ".nc"])
def test_files_read_back_the_same_reading(reading, tmp_path, suffix):
    path = reading.write(tmp_path / f"white{suffix}")
    back = vm.read_result(path)
    assert isinstance(back, RGLReading) and back.resolution == 6
    np.testing.assert_array_equal(back.cell_counts, reading.cell_counts)
    np.testing.assert_array_equal(back.cell_mean_upper, reading.cell_mean_upper)


def test_what_the_binning_cannot_certify_is_refused(mi):
    scene = vm.instrument_scene(WHITE)
    keywords = {"theta_i": [30], "wavelengths": [550], "rays": 1000, "binning": "rgl"}
    with pytest.raises(ValueError, match="fold_phi: no meaning with binning 'rgl'"):
        vm.gonio(scene, fold_phi=True, beam="collimated", **keywords)
    with pytest.raises(ValueError, match="beam must be collimated with binning 'rgl'"):
        vm.gonio(scene, beam="conical", **keywords)
    with pytest.raises(ValueError, match="rgl_resolution must be a whole number of nodes per axis"):
        vm.gonio(scene, beam="collimated", rgl_resolution=2, **keywords)
    keywords.pop("rays")
    with pytest.raises(ValueError, match="guarantee 'relative' is not available with binning 'rgl'"):
        vm.gonio(scene, beam="collimated", guarantee="relative", relative_tolerance=0.1, brdf_floor=0.1, **keywords)


def test_the_default_binning_is_unchanged(mi):
    default = vm.gonio(vm.instrument_scene(WHITE), theta_i=[30], wavelengths=[550], rays=2000, theta_o_bins=3,
                       phi_o_bins=4, seed=1)
    assert type(default).__name__ == "GonioResult" and default.bins.binning == "uniform"
