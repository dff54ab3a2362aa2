"""
Tests of virtspec_mi.results.readings: one result type for a reading or a sweep, and the truth of
every certificate it prints (issue "One result, one engine, one set of settings").
"""

from __future__ import annotations

import json
import subprocess
import sys
import warnings

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.budgets.bounds import exact_mu, hoeffding_mu
from virtspec_mi.kernel.counts import WEIGHT_ROUNDING

DELTA = 0.01
ROUGH = {"type": "roughconductor", "alpha": 0.3}
COLOURED = {"type": "principled", "base_color": {"type": "rgb", "value": [0.9, 0.2, 0.1]}}
GREY = {"type": "diffuse", "reflectance": {"type": "regular", "wavelength_min": 400, "wavelength_max": 700,
                                           "values": "0.2, 0.6, 0.4"}}


def virtspec(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "virtspec_mi.cli", *args], capture_output=True, text=True)


# --- every printed certificate is the one the rays give ---------------------------------


def test_fewer_rays_state_their_own_tolerance(diamond):
    reading = vm.measure(diamond, theta_i=70, rays=1000)
    assert reading.certified_mu[0] == pytest.approx(hoeffding_mu(1000, DELTA))  # 0.0515, not 0.005
    text = reading.summary()
    assert "< 0.0515 with probability >= 0.99" in text and "< 0.005 " not in text
    assert "was asked" not in text  # the rays were given: mu (its default) sized nothing (issue 42, labels)
    assert json.loads(json.dumps(reading.as_dict()))["certified_mu"] == reading.certified_mu.tolist()
    tiny = vm.measure(diamond, theta_i=70, rays=10, mu=0.0001)
    assert tiny.certified_mu[0] == pytest.approx(hoeffding_mu(10, DELTA)) and "< 0.515 with" in tiny.summary()


def test_a_rule_sized_reading_states_at_most_mu(diamond):
    for bound in ("hoeffding", "chebyshev", "exact", "two-stage"):
        reading = vm.measure(diamond, theta_i=30, beam="collimated", bound=bound)
        assert np.all(reading.certified_mu <= 0.005), bound
        assert "< 0.005 with probability >= 0.99" in reading.summary(), bound


@pytest.mark.parametrize("bound", ["exact", "two-stage"])
def test_exact_and_two_stage_with_given_rays_state_the_exact_tolerance(diamond, bound):
    reading = vm.measure(diamond, theta_i=30, beam="collimated", bound=bound, rays=1000)
    assert reading.bound == "rays" and reading.pilot_rays is None
    assert reading.certified_mu[0] == pytest.approx(exact_mu(1000, DELTA))
    assert 0.005 < reading.certified_mu[0] < hoeffding_mu(1000, DELTA)


def test_sweeps_files_cli_and_render_state_the_spent_tolerance(diamond, scenes_dir, mi, tmp_path):
    result = vm.sweep(diamond, theta_i=[0, 45], rays=1000, beam="collimated", progress=False)
    np.testing.assert_allclose(result.certified_mu, hoeffding_mu(1000, DELTA))
    assert "< 0.0515" in result.summary()
    dataset = result.to_dataset()
    np.testing.assert_allclose(dataset["certified_mu"].values, hoeffding_mu(1000, DELTA))
    printed = virtspec("measure", str(scenes_dir / "diamond_conical.xml"), "--rays", "1000")
    assert printed.returncode == 0 and "< 0.0515" in printed.stdout and "< 0.005 " not in printed.stdout
    scene = mi.load_file(str(scenes_dir / "diamond_conical.xml"))
    mi.render(scene, spp=1000)
    assert "< 0.0515" in scene.integrator().last_reading.summary()


def test_the_plot_band_is_the_certified_tolerance(diamond):
    result = vm.sweep(diamond, theta_i=[0, 30, 60], rays=1000, beam="collimated", progress=False)
    band = result.plot().axes[0].collections[0].get_paths()[0].vertices[:, 1]
    mu = hoeffding_mu(1000, DELTA)
    assert band.max() - band.min() >= 2 * mu - 1e-9  # the band spans at least ± the spent tolerance


# --- weights: rounding tallied apart, real violations warned ----------------------------


def test_rounded_weights_of_microfacets_are_not_violations(mi):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no false alarm
        reading = vm.measure(vm.instrument_scene(ROUGH), theta_i=45, rays=20_000)
    assert reading.weight_violations[0] == 0 and reading.rounded_weights[0] > 0
    assert reading.rounding_bias[0] == reading.rounded_weights[0] * WEIGHT_ROUNDING / 20_000 < 1e-6
    assert reading.certified_mu[0] == pytest.approx(hoeffding_mu(20_000, DELTA) + reading.rounding_bias[0])
    assert "rounded" in reading.summary() and "WARNING" not in reading.summary()


def test_real_violations_warn_with_the_largest_weight(mi):
    with pytest.warns(RuntimeWarning, match=r"the largest 1\.\d+.*not certified"):
        reading = vm.measure(vm.instrument_scene(COLOURED), theta_i=20, rays=20_000, wavelengths=[650])
    assert reading.weight_violations[0] > 0 and reading.largest_weight[0] > 1 + WEIGHT_ROUNDING
    assert np.isnan(reading.certified_mu[0]) and "NOT CERTIFIED" in reading.summary()
    assert reading.as_dict()["certified_mu"] == [None]


# --- a reading is a result like any other -----------------------------------------------


@pytest.fixture(scope="module")
def grey_reading(mi):
    return vm.measure(vm.instrument_scene(GREY), theta_i=8, beam="collimated", wavelengths="400:700:20", rays=2000)


def test_a_reading_is_a_result_with_one_dimension(grey_reading):
    assert isinstance(grey_reading, vm.Result) and grey_reading.dims == ("wavelength",)
    assert grey_reading.theta_i == 8.0 and grey_reading.reflectance.shape == (16,)
    grid = grey_reading.as_grid()
    assert grid.dims == ("wavelength", "theta_i") and grid.reflectance.shape == (16, 1)
    assert grid.squeeze().as_dict() == grey_reading.as_dict()
    assert "wavelength: 16" in repr(grey_reading)


def test_a_reading_becomes_spectra_colour_plots_and_files(grey_reading, tmp_path):
    from virtspec_mi.colorimetry.cie import colorimetry
    from virtspec_mi.results.plot import plot_sweep

    sd = grey_reading.to_sd()
    np.testing.assert_allclose(sd.values, grey_reading.reflectance)
    assert grey_reading.to_msds().values.shape == (16, 3)
    np.testing.assert_allclose(colorimetry(grey_reading).XYZ, colorimetry(sd).XYZ)
    plot_sweep(grey_reading, tmp_path / "reading.png")
    assert (tmp_path / "reading.png").stat().st_size > 0
    for suffix in (".nc", ".csv", ".json"):
        back = vm.read_result(grey_reading.write(tmp_path / f"reading{suffix}"))
        assert back.dims == grey_reading.dims and back.settings == grey_reading.settings
        assert back.as_dict() == grey_reading.as_dict(), suffix


def test_colour_reads_measure_json(scenes_dir, tmp_path):
    printed = virtspec("measure", str(scenes_dir / "diamond_collimated.xml"), "--wavelengths", "400:700:50",
                       "--rays", "1000", "--json")
    assert printed.returncode == 0, printed.stderr
    path = tmp_path / "reading.json"
    path.write_text(printed.stdout)
    coloured = virtspec("colour", str(path))
    assert coloured.returncode == 0, coloured.stderr
    assert "XYZ" in coloured.stdout and "sRGB" in coloured.stdout


# --- a sweep keeps what a reading knows -------------------------------------------------


def test_a_sweep_keeps_parts_pilot_capped_and_backlit(mi, diamond, tmp_path):
    plastic = vm.instrument_scene({"type": "plastic"})
    swept = vm.sweep(plastic, theta_i=[30], wavelengths=[450, 600], rays=20_000, beam="collimated", progress=False)
    single = vm.measure(plastic, theta_i=30, wavelengths=[450, 600], rays=20_000, beam="collimated")
    np.testing.assert_array_equal(swept.specular_reflected[:, 0], single.specular_reflected)
    assert 0 < swept.specular_reflected.min() and np.all(swept.specular_reflected < swept.reflected)
    back = vm.read_result(swept.write(tmp_path / "plastic.nc"))
    np.testing.assert_array_equal(back.specular_reflectance, swept.specular_reflectance)

    grazing = vm.sweep(diamond, theta_i=[80, 85, 86, 90], rays=2000, progress=False)
    backlit = grazing.backlit_fraction
    assert backlit[0] == backlit[1] == 0 and 0 < backlit[2] < backlit[3] == pytest.approx(0.5)
    assert "below the specimen plane" in grazing.summary()
    assert grazing.as_dict()["backlit_fraction"] == backlit.tolist()

    two = vm.sweep(diamond, theta_i=[0, 60], beam="collimated", bound="two-stage", mu=0.02, delta=0.05,
                   progress=False)
    assert two.pilot_rays.shape == (1, 2) and np.all(two.pilot_rays == 500)
    np.testing.assert_array_equal(two.rays_spent, two.rays + 500)
    back = vm.read_result(two.write(tmp_path / "two.json"))
    np.testing.assert_array_equal(back.pilot.reflected, two.pilot.reflected)


def test_a_result_reads_well_in_a_terminal_and_in_jupyter(grey_reading):
    text = repr(grey_reading)
    assert text.startswith("<virtspec_mi.Result (wavelength: 16) collimated") and "certified mu <=" in text
    page = grey_reading._repr_html_()
    assert "virtspec_mi.Result" in page and "certified_mu" in page and "reflectance" in page
    assert "result_json" not in page and page.count("<div") > 5
