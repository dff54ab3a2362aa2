"""
Tests of :mod:`virtspec_mi.instruments.sphere.result`: a sphere reading and its certificate from the counts.

The reading is ρ_std·p_sample/p_standard of the detected counts; its interval the extreme
ratios of the two Clopper–Pearson intervals at δ/2 each; the hemispherical reading the same
rays' hemispherical count with its interval at δ; each fraction's tolerance Hoeffding's at
δ/2 for the rays spent; a transmittance reading's standard is the open port (1); capped walks
are counted apart and uncertify the reading; files read back to the same counts and an edited
file that breaks them is refused.

References
----------
Clopper & Pearson (1934); Hoeffding (1963); Baranoski et al. (2001), eq. (19).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.budgets.bounds import hoeffding_mu
from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.instruments.sphere.result import SphereResult

SCENE = str(Path(__file__).resolve().parents[3] / "scenes" / "sphere_150mm_8d.xml")
RAYS = 3000


@pytest.fixture(scope="module")
def result(mi):
    return vm.sphere_measure(SCENE, rays=RAYS, wavelengths="500, 600", seed=4)


def test_the_reading_is_the_ratio_of_the_detected_counts(result):
    c = result.counts
    assert isinstance(result, SphereResult) and np.all(result.rays == RAYS)
    standard = result.standard_value
    assert standard == float(result.options["standard"])
    p_s, p_r = c["sample"]["detected"] / RAYS, c["standard"]["detected"] / RAYS
    np.testing.assert_allclose(result.detector_fraction, p_s, rtol=1e-15)
    np.testing.assert_allclose(result.reading, standard * p_s / p_r, rtol=1e-15)
    np.testing.assert_allclose(result.instrument_error, result.reading - result.hemispherical)


def test_the_interval_is_the_extreme_ratio_of_the_fractions_intervals(result):
    c = result.counts
    s_low, s_high = clopper_pearson(c["sample"]["detected"], RAYS, result.delta / 2)
    r_low, r_high = clopper_pearson(c["standard"]["detected"], RAYS, result.delta / 2)
    interval = result.reading_interval
    np.testing.assert_allclose(interval[..., 0], result.standard_value * s_low / r_high)
    np.testing.assert_allclose(interval[..., 1], result.standard_value * s_high / r_low)
    assert np.all((interval[..., 0] <= result.reading) & (result.reading <= interval[..., 1]))
    assert result.fraction_delta == result.delta / 2
    np.testing.assert_allclose(result.fraction_mu, hoeffding_mu(RAYS, result.delta / 2))


def test_the_hemispherical_reading_of_the_same_rays(result):
    c = result.counts["sample"]
    np.testing.assert_allclose(result.hemispherical, c["hemispherical_reflected"] / RAYS)
    low, high = clopper_pearson(c["hemispherical_reflected"], RAYS, result.delta)
    np.testing.assert_allclose(result.hemispherical_interval[..., 0], low)
    np.testing.assert_allclose(result.hemispherical_interval[..., 1], high)
    np.testing.assert_allclose(result.wall_reflections_per_ray, c["wall_reflections"] / RAYS)
    assert result.certified.all() and not result.no_light.any()


@pytest.mark.parametrize("suffix", [".json", ".nc"])
def test_files_read_back_to_the_same_counts(result, tmp_path, suffix):
    back = vm.read_result(result.write(tmp_path / f"sphere{suffix}"))
    assert isinstance(back, SphereResult)
    for configuration, named in result.counts.items():
        for name, values in named.items():
            np.testing.assert_array_equal(back.counts[configuration][name], values, err_msg=f"{configuration}.{name}")
    np.testing.assert_allclose(back.reading_interval, result.reading_interval)


def test_an_edited_file_that_breaks_its_counts_is_refused(result):
    data = result.as_dict()
    data["counts"]["standard"]["detected"] = [10**6, 10**6]
    with pytest.raises(ValueError, match="standard"):
        SphereResult.from_dict(data)


def test_a_transmittance_readings_standard_is_the_open_port(mi):
    scene = mi.load_file(SCENE)
    reading = vm.sphere_measure(scene, measurement="transmittance", rays=2000, wavelengths="550", seed=2)
    assert reading.standard_value == 1.0
    np.testing.assert_allclose(reading.hemispherical, reading.counts["sample"]["hemispherical_transmitted"] / 2000)


def test_capped_walks_uncertify_the_reading(mi):
    capped = vm.sphere_measure(SCENE, rays=500, wavelengths="550", seed=5, max_bounces=2)
    assert int(capped.counts["sample"]["capped"][0]) > 0
    assert not capped.certified[0] and np.isnan(capped.reading_interval[0]).all() and np.isnan(capped.fraction_mu[0])
