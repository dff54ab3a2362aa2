"""Tests of virtspec_mi.settings: the one place that validates input."""

from __future__ import annotations

import pytest

import virtspec_mi as vm
from virtspec_mi.checks import parse_wavelengths
from virtspec_mi.settings import Settings


def test_defaults_are_the_papers():
    s = Settings()
    assert (s.mu, s.delta, s.bound, s.beam, s.sampling) == (0.005, 0.01, "hoeffding", "conical", "jittered")
    assert s.rays_per_reading == 105_967
    assert Settings(rays=1000).rays_per_reading == 1000
    assert Settings(bound="chebyshev").rays_per_reading == 1_000_000


def test_wavelength_parsing():
    assert parse_wavelengths("400:700:100") == (400.0, 500.0, 600.0, 700.0)
    assert parse_wavelengths("465, 551 608") == (465.0, 551.0, 608.0)
    assert parse_wavelengths(551) == (551.0,)
    assert parse_wavelengths([2500, 400]) == (2500.0, 400.0)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"mu": 0}, r"mu must satisfy 0 < mu < 0.5 \(got 0\)"),
        ({"mu": -0.1}, "mu must satisfy 0 < mu < 0.5"),
        ({"mu": 0.5}, "mu must satisfy 0 < mu < 0.5"),
        ({"mu": float("nan")}, "mu must be a number"),
        ({"delta": 0}, "delta must satisfy 0 < delta < 1"),
        ({"delta": 1}, "delta must satisfy 0 < delta < 1"),
        ({"theta_i": -1}, r"theta_i must satisfy 0 <= theta_i <= 90 degrees \(got -1\)"),
        ({"theta_i": 90.5}, "theta_i must satisfy 0 <= theta_i <= 90"),
        ({"phi_i": float("inf")}, "phi_i must be a finite number"),
        ({"wavelengths": []}, "wavelengths must hold at least one wavelength"),
        ({"wavelengths": ""}, "wavelengths must hold at least one wavelength"),
        ({"wavelengths": [500, 0]}, "wavelengths must be finite and > 0 nm"),
        ({"wavelengths": [-400]}, "wavelengths must be finite and > 0 nm"),
        ({"wavelengths": "400:300:10"}, "needs step > 0 and stop >= start"),
        ({"wavelengths": "abc"}, "wavelengths must be a number"),
        ({"rays": 0}, "rays must satisfy 1 <= rays"),
        ({"rays": 2.5}, "rays must be a whole number"),
        ({"rays": 2**32}, "rays must satisfy 1 <= rays <= 4294967295"),
        ({"beam": "laser"}, "beam must be one of conical, collimated"),
        ({"sampling": "sobol"}, "sampling must be one of jittered, random, concentric"),
        ({"bound": "magic"}, "bound must be one of hoeffding, chebyshev, exact, two-stage"),
        ({"pilot_rays": 0}, "rays must satisfy 1 <= rays"),
        ({"pilot_delta": 0.01}, r"pilot_delta must satisfy 0 < pilot_delta < delta = 0.01 \(got 0.01\)"),
        ({"pilot_delta": 0}, "pilot_delta must satisfy 0 < pilot_delta < delta"),
        ({"joint": "yes"}, "joint must be true or false"),
        ({"seed": -1}, "seed must be a whole number"),
        ({"chunk_size": 10}, "chunk_size must be a whole number"),
    ],
)
def test_bad_input_names_parameter_and_range(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Settings(**kwargs)


def test_updated_ignores_none_and_revalidates():
    s = Settings(theta_i=30)
    assert s.updated(theta_i=None, mu=0.01).theta_i == 30
    with pytest.raises(ValueError, match="theta_i"):
        s.updated(theta_i=100)


def test_check_wavelength_range():
    from virtspec_mi.checks import check_wavelength_range

    check_wavelength_range([400.0, 2500.0], (400, 2500), "abm_b")  # both ends included
    check_wavelength_range([1.0, 1e6], None, "any")  # no declared range: anything goes
    with pytest.raises(ValueError, match=r"400 <= wavelength <= 2500 nm for the specimen abm_u \(got 399, 2501\)"):
        check_wavelength_range([399.0, 551.0, 2501.0], (400, 2500), "abm_u")


def test_budget_settings():
    assert Settings(bound="exact").rays_per_reading == 66_501
    # joint: each of R and T at delta/2 (Hoeffding 119,830, anchors.md section 3)
    assert Settings(joint=True).rays_per_reading == 119_830
    assert Settings(joint=True).quantity_delta == 0.005 and Settings().quantity_delta == 0.01
    two = Settings(bound="two-stage")
    assert two.adaptive and not Settings(bound="two-stage", rays=100).adaptive
    assert (two.pilot_rays_per_reading, two.pilot_delta_value) == (2000, 0.001)
    assert Settings(bound="two-stage", mu=0.05, pilot_rays=300).pilot_rays_per_reading == 300
    with pytest.raises(ValueError, match="two-stage"):
        two.rays_per_reading
    assert two.as_dict()["rays"] is None and two.as_dict()["pilot_rays"] == 2000


# --- one definition: API keywords, integrator parameters and CLI flags derive from it ----


def test_every_setting_is_an_api_keyword_an_xml_parameter_and_a_cli_flag(mi):
    import inspect
    import re
    import subprocess
    import sys

    from virtspec_mi.plugins.integrators import spectrophotometer
    from virtspec_mi.settings import SETTING_NAMES

    for function in (vm.measure, vm.sweep):
        parameters = inspect.signature(function).parameters
        assert set(SETTING_NAMES) <= set(parameters), function.__name__
    documented = re.findall(r"^(\w+) : ", spectrophotometer.__doc__, flags=re.M)
    assert documented == list(SETTING_NAMES)
    for command in ("measure", "sweep"):
        text = subprocess.run([sys.executable, "-m", "virtspec_mi.cli", command, "--help"],
                              capture_output=True, text=True).stdout
        for name in SETTING_NAMES:
            assert "--" + name.replace("_", "-") in text, (command, name)


def test_unknown_settings_and_booleans_are_refused(diamond):
    with pytest.raises(TypeError, match="unexpected keyword argument.*theta; the settings are theta_i"):
        vm.measure(diamond, theta=10)
    for name, value in (("theta_i", True), ("seed", True), ("wavelengths", [True]), ("mu", False)):
        with pytest.raises(ValueError, match=name):
            Settings(**{name: value})


def test_strings_from_xml_and_the_command_line_are_validated_once():
    settings = Settings(theta_i="45", seed="7", rays="1000", joint="true", wavelengths="400 500")
    assert (settings.theta_i, settings.seed, settings.rays, settings.joint) == (45.0, 7, 1000, True)
    assert settings.wavelengths == (400.0, 500.0)
    with pytest.raises(ValueError, match=r"theta_i must satisfy 0 <= theta_i <= 90 degrees \(got 95\)"):
        Settings(theta_i="95")
    assert "theta_i = 0: polar incidence angle" in Settings.describe()
