"""
Targets through the API and the CLI (issue 30): results, outputs and clear refusals; the
certified colour of any hemispherical result; the certified colour difference.
"""

from __future__ import annotations

import json
import math

import colour
import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.colorimetry.certified import CertifiedColour, tristimulus_weights
from virtspec_mi.budgets.functionals import hoeffding_tolerance
from virtspec_mi.applications.targets.parse import parse_target
from virtspec_mi.colorimetry.cie import colorimetry

VALUES = "0.1, 0.3, 0.7, 0.4, 0.2, 0.6, 0.8, 0.5"


@pytest.fixture(scope="module")
def lambertian(mi):
    return vm.instrument_scene({"type": "diffuse", "reflectance": {"type": "regular", "wavelength_min": 300,
                                                                   "wavelength_max": 1000, "values": VALUES}})


@pytest.mark.parametrize("grid", [np.arange(400, 701, 10.0), np.array([400, 430, 470, 520, 560, 610, 650, 700.0])])
def test_the_tristimulus_weights_are_those_of_the_colorimetry(grid):
    rng = np.random.default_rng(0)
    weights = tristimulus_weights(grid)
    for _ in range(3):
        values = rng.uniform(0, 1, len(grid))
        assert weights @ values == pytest.approx(colorimetry(colour.SpectralDistribution(values, grid)).XYZ)


def test_a_result_colour_has_intervals_from_the_rays_it_spent(lambertian):
    result = vm.measure(lambertian, wavelengths="400:700:10", rays=20_000, delta=0.1, beam="collimated", seed=3)
    certified = result.colour()
    assert isinstance(certified, CertifiedColour) and certified.rays == 31 * 20_000
    weights = tristimulus_weights(np.arange(400, 701, 10.0))
    expected = [hoeffding_tolerance(w, np.full(31, 20_000), 0.1 / 3) for w in weights]
    assert (certified.XYZ_interval[:, 1] - certified.XYZ) == pytest.approx(expected)
    exact = weights @ np.interp(np.arange(400, 701, 10.0), np.linspace(300, 1000, 8), [float(v) for v in
                                                                                       VALUES.split(",")])
    assert np.all((certified.XYZ_interval[:, 0] <= exact) & (exact <= certified.XYZ_interval[:, 1]))
    assert "certified at delta = 0.1" in certified.summary() and certified.as_dict()["dE00_radius"] > 0
    difference = vm.colour_difference(result, colorimetry(colour.SpectralDistribution(
        np.interp(np.arange(400, 701, 10.0), np.linspace(300, 1000, 8), [float(v) for v in VALUES.split(",")]),
        np.arange(400, 701, 10.0))).Lab)
    low, high = difference.dE00_interval
    assert low <= difference.dE00 <= high < 2 * certified.dE00_radius
    assert difference.dEab_interval[0] == 0.0  # the exact colour lies in the box
    with pytest.raises(ValueError, match="CIE L\\*a\\*b\\* as three numbers"):
        vm.colour_difference(result, [1, 2])


def test_a_colour_target_meets_its_tolerance_and_reports_its_variables(lambertian):
    result = vm.measure(lambertian, target=vm.colour(tolerance_dE00=2.0), delta=0.1, seed=1)
    assert result.met and result.colour.dE00_radius <= 2.0 and result["dE00_radius"].value <= 2.0
    assert result.pilot_rays > 0 and result.rays == int(np.sum(result.readings.rays))
    rays = np.asarray(result.readings.rays)
    weights = tristimulus_weights(np.asarray(result.readings.coords["wavelength"])).sum(axis=0)
    assert np.corrcoef(rays, weights)[0, 1] > 0.8  # the rays follow the weights (the most X, Y or Z asks for)
    data = result.to_dataset()
    assert data["L"].attrs["units"] == "1" and "L*a*b*" in data["L"].attrs["long_name"]
    assert float(data["L_lower"]) <= float(data["L"]) <= float(data["L_upper"])
    assert "reflectance" in data and data.sizes["wavelength"] == len(rays)
    assert json.loads(result.to_json())["values"]["X"]["upper"] == pytest.approx(result["X"].upper)
    assert "no joint per-wavelength certificate" in result.summary()
    assert "certified dE00 <=" in result.plot().axes[0].get_title()


def test_a_band_target_spends_the_rays_of_one_reading(lambertian, tmp_path):
    result = vm.measure(lambertian, target=vm.band((500, 530), tolerance=0.01), delta=0.05, seed=0, bound="hoeffding")
    assert result.rays <= math.log(2 / 0.05) / (2 * 0.01 ** 2) + 31
    value = result["band_500-530"]
    figure = result.plot(tmp_path / "band.png")
    assert (tmp_path / "band.png").stat().st_size > 0 and len(figure.axes[0].lines) >= 1
    assert value.upper - value.value == pytest.approx(hoeffding_tolerance(
        result.target.functionals()[0].weights, result.readings.rays, 0.05))


def test_targets_the_instrument_cannot_certify_are_refused(mi, lambertian):
    leaf = vm.scenes.path("soybean_abmb")
    with pytest.raises(ValueError, match=r"outside the specimen's data \(400-2500 nm\)"):
        vm.measure(leaf, target=vm.band((2400, 2600)))
    narrow = vm.instrument_scene({"type": "diffuse", "reflectance": {"type": "regular", "wavelength_min": 480,
                                                                     "wavelength_max": 900, "values": "0.2, 0.4"}})
    with pytest.raises(ValueError, match="of the colour-matching weight"):
        vm.measure(narrow, target=vm.colour())
    with pytest.raises(ValueError, match="mu, wavelengths: a target picks its own wavelengths and rays"):
        vm.measure(lambertian, target=vm.fapar(), mu=0.01, wavelengths=[500])
    with pytest.raises(ValueError, match="target must be made by vm.colour"):
        vm.measure(lambertian, target="colour")
    with pytest.raises(ValueError, match="tolerance_dE00 must be a number in"):
        vm.colour(tolerance_dE00=0)
    with pytest.raises(ValueError, match="index must be one of NDVI"):
        vm.index("XYZI")


def test_target_strings():
    assert parse_target("colour,dE00=0.5").tolerance_dE00 == 0.5
    assert [b.name for b in parse_target("band:B04:650-680,tolerance=0.002").bands] == ["B04", "650-680"]
    assert parse_target("index:NDVI,tolerance=0.002").index.name == "NDVI"
    assert parse_target("fapar,tolerance=0.01,low=410").low == 410
    assert parse_target("albedo,illuminant=A,tolerance=0.01").bands[0].name == "albedo_A"
    with pytest.raises(ValueError, match="the kind must be one of colour, band, index, fapar, albedo"):
        parse_target("ndvi")
    with pytest.raises(ValueError, match="NAME one of tolerance, step"):
        parse_target("index:NDVI,dE00=1")


def test_the_cli_measures_a_target(mi, capsys, tmp_path):
    from virtspec_mi.cli import main

    assert main(["measure", "soybean_abmb", "--target", "band:B08,tolerance=0.01", "--json"]) == 0
    printed = capsys.readouterr().out
    data = json.loads(printed)
    assert data["format"] == "virtspec-mi derived 1" and data["met"]
    (tmp_path / "target.json").write_text(printed)  # what --json prints is the target's file
    back = vm.read_result(tmp_path / "target.json")
    assert isinstance(back, vm.DerivedResult) and back["band_B08"].value == data["values"]["band_B08"]["value"]
    value = data["values"]["band_B08"]
    assert value["lower"] < value["value"] < value["upper"]
    assert value["upper"] - value["value"] <= 0.01 * (1 + 1e-12)  # value + 0.01 rounded: one ulp either way
    assert back.bound == data["bound"] == "two-stage" and back.batches == tuple(data["batches"])  # read back whole
    assert main(["measure", "soybean_abmb", "--target", "band:B04", "--out", "x.nc"]) != 0
    assert "--target takes none of --out" in capsys.readouterr().err


def test_a_sweep_certifies_a_target_at_every_angle(lambertian):
    sweep = vm.sweep(lambertian, theta_i=[0, 45], target=vm.fapar(tolerance=0.02), delta=0.1, seed=2)
    assert len(sweep) == 2 and sweep.theta_i == (0.0, 45.0)
    data = sweep.to_dataset()
    assert list(data["theta_i"].values) == [0.0, 45.0] and data["fapar"].attrs["units"] == "1"
    assert np.all(data["fapar_lower"] <= data["fapar"]) and np.all(data["fapar"] <= data["fapar_upper"])
    assert sweep.total_rays == int(data["rays"].sum()) and "theta_i = 45 deg" in sweep.summary()
    with pytest.raises(ValueError, match="out: not taken with a target"):
        vm.sweep(lambertian, theta_i=[0], target=vm.fapar(), out="x.nc")


def test_a_costly_colour_gets_a_second_pilot_and_still_holds_the_exact_colour(mi):
    """A dark reflector (albedo 2-8 %): its colour moves fast with XYZ, so the plan is costly and refined."""

    from virtspec_mi.applications.targets.measure import PILOT_DELTA, PILOT_TOLERANCE
    from virtspec_mi.budgets.functionals import allocate

    values = [0.02, 0.05, 0.08, 0.04]
    dark = vm.instrument_scene({"type": "diffuse", "reflectance": {
        "type": "regular", "wavelength_min": 300, "wavelength_max": 1000, "values": ", ".join(map(str, values))}})
    result = vm.measure(dark, target=vm.colour(tolerance_dE00=2.0), delta=0.2, seed=4, bound="hoeffding")
    weights = np.stack([f.weights for f in result.target.functionals()])
    first = np.max([allocate(w, PILOT_TOLERANCE * np.abs(w).sum(), PILOT_DELTA) for w in weights], axis=0).sum()
    assert result.pilot_rays > first  # the second pilot ran
    assert result.met and result.colour.dE00_radius <= 2.0
    grid = result.target.functionals()[0].wavelengths
    exact = weights @ np.interp(grid, np.linspace(300, 1000, 4), values)
    box = result.colour.XYZ_interval
    assert np.all((box[:, 0] <= exact) & (exact <= box[:, 1]))


@pytest.mark.parametrize("make, message", [
    (lambda: vm.band({500: "a"}), r"the response at 500 nm must be a number \(got 'a'\)"),
    (lambda: vm.band({"x": 1.0}), r"a response dict's wavelength must be a number \(got 'x'\)"),
    (lambda: vm.band((500, "b")), r"band edge high must be a number \(got 'b'\)"),
    (lambda: vm.band("B04", tolerance=1e-300), r"tolerance must be at least 2.33e-10 \(got 1e-300\)"),
    (lambda: vm.band("B04", tolerance="0.01"), r"tolerance must be a number in \(0, 1\], not text"),
    (lambda: vm.fapar(low="a"), r"low must be a number, not text"),
    (lambda: vm.albedo(high="x"), r"high must be a number, not text"),
])
def test_targets_name_what_is_wrong_never_a_bare_conversion_error(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_an_index_of_a_black_specimen_says_why_it_cannot_be_certified():
    with pytest.raises(ValueError, match=r"NDVI cannot be certified to \+-0.005 for this specimen: its pilot reads the "
                                         r"bands at 0 and 0"):
        vm.index("NDVI").tolerances(np.array([0.0, 0.0]), 0.01)
