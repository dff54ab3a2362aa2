"""
Tests of virtspec_mi.instruments.sphere.double_result: the readings and their certificate from the counts,
files read back to the same counts, and what is refused or not certified.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.instruments.sphere.double_result import DoubleSphereResult


@pytest.fixture(scope="module")
def result():
    return vm.double_sphere("double_sphere_leaf", wavelengths=[550, 850], rays=2000, seed=5)


def test_the_readings_are_ratios_of_the_counts_and_their_intervals_the_extreme_ratios(result):
    c = result.counts
    m_r = 0.99 * (c["sample"]["detected_r"] / 2000) / (c["standard"]["detected_r"] / 2000)
    m_t = (c["sample"]["detected_t"] / 2000) / (c["open"]["detected_t"] / 2000)
    assert np.allclose(result.reflectance, m_r, rtol=1e-15) and np.allclose(result.transmittance, m_t, rtol=1e-15)
    delta = result.delta / 4
    s_low, s_high = clopper_pearson(c["sample"]["detected_t"], 2000, delta)
    o_low, o_high = clopper_pearson(c["open"]["detected_t"], 2000, delta)
    assert np.allclose(result.transmittance_interval[..., 0], s_low / o_high)
    assert np.allclose(result.transmittance_interval[..., 1], s_high / o_low)
    assert np.all(result.reflectance_interval[..., 0] <= result.reflectance)
    assert "double integrating sphere" in result.summary() and "M_T" in result.summary()


@pytest.mark.parametrize("suffix", [".json", ".nc"])
def test_files_read_back_to_the_same_counts(result, tmp_path, suffix):
    path = result.write(tmp_path / f"d{suffix}")
    back = vm.read_result(path)
    assert isinstance(back, DoubleSphereResult)
    for configuration, named in result.counts.items():
        for name, values in named.items():
            assert np.array_equal(values, back.counts[configuration][name]), (configuration, name)
    assert back.transmittance_description == result.transmittance_description


def test_an_edited_file_that_breaks_its_counts_is_refused(result):
    data = result.as_dict()
    data["counts"]["open"]["detected_t"] = [10**6, 10**6]
    with pytest.raises(ValueError, match="open"):
        DoubleSphereResult.from_dict(data)


def test_a_capped_walk_is_not_certified():
    capped = vm.double_sphere("double_sphere_leaf", wavelengths=[850], rays=500, seed=5, max_bounces=2)
    assert int(capped.counts["sample"]["capped"][0]) > 0
    assert not bool(capped.certified[0]) and np.isnan(capped.reflectance_interval[0]).all()
    assert "NOT CERTIFIED" in capped.summary()
