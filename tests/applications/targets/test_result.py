"""
Tests of :mod:`virtspec_mi.applications.targets.result`: a target's certified result and its sweep.

A band of a Lambertian specimen whose reflectance is linear over the band (0.7 at 500 nm to
0.61 at 530 nm: the band's true value 0.655) is certified at δ = 0.05 with a fixed seed: the
true value lies in the interval, the rays are the readings' N summed, the summary states the
certificate, the files (``.json``, ``.nc``) read back to the same values, and a file whose
rays or values were edited is refused. A sweep holds one result per θi.

References
----------
Hoeffding (1963), Theorem 2.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.applications.targets.result import FORMAT, SWEEP_FORMAT, DerivedResult, DerivedSweep

VALUES = "0.1, 0.3, 0.7, 0.4, 0.2, 0.6, 0.8, 0.5"  # 300 … 1000 nm every 100 nm
TRUE_BAND = 0.7 - 0.003 * 15  # the mean of the linear reflectance over 500–530 nm


@pytest.fixture(scope="module")
def scene(mi):
    return vm.instrument_scene({"type": "diffuse", "reflectance": {"type": "regular", "wavelength_min": 300,
                                                                   "wavelength_max": 1000, "values": VALUES}})


@pytest.fixture(scope="module")
def band(scene):
    return vm.measure(scene, target=vm.band((500, 530), tolerance=0.02), delta=0.05, seed=0, bound="hoeffding")


def test_the_band_is_certified_around_its_true_value(band):
    assert isinstance(band, DerivedResult) and band.FORMAT == FORMAT
    value = band["band_500-530"]
    assert value.lower <= TRUE_BAND <= value.upper and value.upper - value.lower <= 2 * 0.02 + 1e-12
    assert band.met and band.pilot_rays == 0 and band.total_rays == band.rays == int(np.sum(band.readings.rays))
    assert band.statements == 1 and len(band.functional_tolerances) == 1 and band.delta == 0.05
    with pytest.raises(KeyError, match="'NDVI': the quantities are band_500-530"):
        band["NDVI"]


def test_the_summary_states_the_certificate(band):
    text = band.summary()
    assert text.startswith("target: reflectance in band 500-530 (500-530 nm) to +-0.02\n"
                           "certified together at delta = 0.05 (1 linear functional, Hoeffding 1963, each at delta/1)")
    assert f"rays: {band.rays:,} on 31 wavelengths 500-530 nm (N_k proportional to |w_k|" in text
    assert "they carry no joint per-wavelength certificate of their own" in text
    assert repr(band).startswith("<virtspec_mi DerivedResult band_500-530 = ")


@pytest.mark.parametrize("suffix", [".json", ".nc"])
def test_files_read_back_to_the_same_values(band, tmp_path, suffix):
    back = vm.read_result(band.write(tmp_path / f"band{suffix}"))
    assert isinstance(back, DerivedResult) and back.rays == band.rays
    assert back["band_500-530"] == band["band_500-530"]
    np.testing.assert_array_equal(back.readings.rays, band.readings.rays)


def test_the_dataset_has_each_value_with_its_bounds(band):
    dataset = band.to_dataset()
    for name in ("band_500-530", "band_500-530_lower", "band_500-530_upper", "functional_tolerance"):
        assert name in dataset, name
    assert float(dataset["band_500-530_lower"]) == band["band_500-530"].lower
    assert dataset.attrs["rays"] == band.rays


def test_edited_files_are_refused(band, tmp_path):
    data = band.as_dict()
    data.pop("checksum", None)
    data["rays"] += 1
    (tmp_path / "rays.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"'rays' holds .*; the readings' rays add up to"):
        vm.read_result(tmp_path / "rays.json")
    data = band.as_dict()
    data["values"]["band_500-530"]["value"] = 2.0
    (tmp_path / "value.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"the value of 'band_500-530' \(2\) lies outside its interval"):
        vm.read_result(tmp_path / "value.json")


def test_a_sweep_holds_one_result_per_angle(scene, tmp_path):
    sweep = vm.sweep(scene, theta_i=[0, 45], target=vm.band((500, 530), tolerance=0.03), delta=0.1, seed=2,
                     bound="hoeffding")
    assert isinstance(sweep, DerivedSweep) and sweep.FORMAT == SWEEP_FORMAT and len(sweep) == 2
    assert sweep.theta_i == (0.0, 45.0) and sweep.total_rays == sum(r.total_rays for r in sweep.results)
    for result in sweep.results:  # a Lambertian specimen: the same true value at every angle
        assert result["band_500-530"].lower <= TRUE_BAND <= result["band_500-530"].upper
    assert sweep.summary().startswith("theta_i = 0 deg\ntarget: ") and "\n\ntheta_i = 45 deg\n" in sweep.summary()
    dataset = sweep.to_dataset()
    assert dataset["band_500-530"].dims == ("theta_i",) and list(dataset["rays"].values) == [
        r.total_rays for r in sweep.results]
    back = vm.read_result(sweep.write(tmp_path / "sweep.json"))
    assert isinstance(back, DerivedSweep) and back[1]["band_500-530"] == sweep[1]["band_500-530"]
    data = sweep.as_dict()
    data["theta_i"] = [0.0]
    data.pop("checksum", None)
    (tmp_path / "short.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"'theta_i' holds 1 angles and 'results' 2 targets"):
        vm.read_result(tmp_path / "short.json")
