"""Tests of virtspec_mi.settings: the one place that validates input."""

from __future__ import annotations

import pytest

import virtspec_mi as vm
from virtspec_mi.base.checks import parse_wavelengths
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
        ({"pilot_rays": 0}, r"pilot_rays must satisfy 1 <= pilot_rays <= 4294967295 \(got 0\)"),
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
    from virtspec_mi.base.checks import check_wavelength_range

    check_wavelength_range([400.0, 2500.0], (400, 2500), "abm_b")  # both ends included
    check_wavelength_range([1.0, 1e6], None, "any")  # no declared range: anything goes
    with pytest.raises(ValueError, match=r"400 <= wavelength <= 2500 nm for the specimen abm_u \(got 399, 2501\)"):
        check_wavelength_range([399.0, 551.0, 2501.0], (400, 2500), "abm_u")


def test_budget_settings():
    assert Settings(bound="exact").rays_per_reading == 66_501
    # joint: each of R and T at delta/2 (Hoeffding 119,830, the project's exact computations (virtspec_mi/budgets/bounds.py) 3)
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

    from virtspec_mi.instruments import integrator as spectrophotometer
    from virtspec_mi.settings import SETTING_NAMES

    for function in (vm.measure, vm.sweep):
        parameters = inspect.signature(function).parameters
        assert set(SETTING_NAMES) <= set(parameters), function.__name__
    documented = re.findall(r"^(\w+) : ", spectrophotometer.__doc__, flags=re.M)
    assert documented == ["instrument", *SETTING_NAMES]  # the instrument, then every setting
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


# --- issue 12: every N, however obtained, passes the same range check: 1 ... 2**32 - 1 ---------


@pytest.mark.parametrize("kwargs, message", [
    # wrapped silently to N mod 2**32 before
    ({"theta_i": 88, "mu": 2.4e-5}, r"^the hoeffding bound for mu = 2.4e-05, delta = 0.01 needs N = 4,599,233,825 "
                                    r"rays per reading, more than the 4,294,967,295 \(2\*\*32 - 1\)"),
    ({"mu": 1e-9}, "the hoeffding bound for mu = 1e-09, delta = 0.01 needs N = 2,649,158,683,274,017,792"),
    ({"mu": 1e-9, "bound": "exact"}, "the exact bound for mu = 1e-09"),
    ({"mu": 1e-5, "bound": "chebyshev"}, "the chebyshev bound for mu = 1e-05, delta = 0.01 needs N = 250,000,000,000 "),
    ({"mu": 2e-5, "joint": True}, r"delta = 0.01 \(each quantity at delta/2: joint\) needs N = 7,489,330,684"),
    ({"mu": 1e-300}, r"the hoeffding bound for mu = 1e-300, delta = 0.01 needs more than 1.8e308 rays"),  # ZeroDivisionError
    ({"delta": 1e-300, "bound": "chebyshev"}, r"chebyshev bound for mu = 0.005, delta = 1e-300 needs N = 1e\+304"),
    ({"mu": 1e-200, "delta": 1e-300, "bound": "chebyshev"}, "needs more than 1.8e308 rays"),  # OverflowError
])
def test_the_bound_never_asks_for_more_than_two_to_the_32(kwargs, message):
    settings = Settings(**kwargs)
    with pytest.raises(ValueError, match=message):
        settings.rays_per_reading
    with pytest.raises(ValueError, match=message):
        settings.most_rays_per_reading
    assert Settings(**kwargs, rays=1000).rays_per_reading == 1000  # explicit rays: mu is only what was asked


def test_two_stage_sizes_are_range_checked():
    with pytest.raises(ValueError, match=r"the default two-stage pilot ceil\(10/mu\) for mu = 1e-09 needs N = "
                                         r"10,000,000,000"):
        Settings(bound="two-stage", mu=1e-9).pilot_rays_per_reading
    with pytest.raises(ValueError, match="the two-stage bound for mu = 2e-05, delta = 0.01 needs N"):
        Settings(bound="two-stage", mu=2e-5, pilot_rays=100).most_rays_per_reading
    with pytest.raises(ValueError, match="default two-stage pilot"):
        Settings(bound="two-stage", mu=3e-308).pilot_rays_per_reading  # 10/mu overflows a float


@pytest.mark.parametrize("kwargs, message", [
    ({"mu": 1e-310}, r"mu must satisfy 0 < mu < 0.5 and be at least 2.23e-308"),
    ({"delta": 5e-324}, r"delta must satisfy 0 < delta < 1 and be at least 2.23e-308"),
    ({"delta": 3e-308, "joint": True}, r"delta/2 \(joint\) must satisfy"),
    ({"delta": 1e-307, "bound": "two-stage"}, r"pilot_delta must satisfy .* at least 2.23e-308"),
    ({"delta": 1e-300, "pilot_delta": 1e-300 * (1 - 2**-52), "bound": "two-stage"}, r"\(delta - pilot_delta\)"),
])
def test_probabilities_derived_from_delta_are_normal_floats(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Settings(**kwargs)


def test_chunk_size_is_capped_by_memory():
    from virtspec_mi.base.checks import MAX_CHUNK_SIZE

    assert MAX_CHUNK_SIZE == 2**25 and Settings(chunk_size=2**25).chunk_size == 2**25
    with pytest.raises(ValueError, match=r"chunk_size must be a whole number with 1024 <= chunk_size <= 2\*\*25 "
                                         r"\(got 67108864\)"):
        Settings(chunk_size=2**26)


# --- the one-definition machinery (virtspec_mi.settings.Options) ---------------------------


def test_options_machinery_reads_validates_and_describes_one_way():
    from virtspec_mi.instruments.goniophotometer import GonioOptions
    from virtspec_mi.instruments.sphere import SphereOptions
    from virtspec_mi.settings import keywords, resolve

    # numeric strings are numbers everywhere; None means the default; booleans are not numbers
    assert Settings(seed="5").seed == 5 and SphereOptions(max_bounces="100").max_bounces == 100
    assert Settings(theta_i=None, seed=None) == Settings()
    for kind, name in ((Settings, "seed"), (SphereOptions, "max_bounces"), (GonioOptions, "relative_tolerance")):
        with pytest.raises(ValueError, match=name):
            kind(**{name: True})
    # the XML/dict reader: the options named there, converted by the checks; others ignored
    settings = Settings.from_parameters({"theta_i": "30", "joint": "true", "theta_o_bins": 3, "type": "x"})
    assert (settings.theta_i, settings.joint, settings.rays) == (30.0, True, None)
    assert GonioOptions.parameters_in({"theta_i": 1, "fold_phi": True}) == ["fold_phi"]
    assert SphereOptions.parameters_in({"mu": 0.1, "diameter": 60.0, "port_a": "x", "method": "comparison"}) == [
        "diameter", "port_a", "method"]
    # the signature builder: the function's own parameters, then each kind's options
    def f(scene, *, theta_i=None, **given):
        pass
    names = list(keywords(f, GonioOptions, Settings).parameters)
    assert names == ["scene", "theta_i", *GonioOptions.names(), *[n for n in Settings.names() if n != "theta_i"]]
    # an API call's keywords: each to the options that declare it, over the scene's values
    base = Settings(theta_i=30)
    settings, options = resolve("gonio", {"mu": 0.1, "fold_phi": "true", "theta_i": None}, base, GonioOptions())
    assert (settings.mu, settings.theta_i, options.fold_phi) == (0.1, 30.0, True)
    with pytest.raises(TypeError, match=r"gonio\(\) got unexpected keyword argument\(s\) theta_bins; the settings "
                                        r"are theta_i.*; the goniophotometer options are theta_o_bins"):
        resolve("gonio", {"theta_bins": 3}, base, GonioOptions())
    assert "max_bounces = 100000: step cap of a sphere walk" in SphereOptions.describe()


def test_every_option_is_a_flag_of_its_subcommand(capsys):
    from virtspec_mi.cli import build_parser
    from virtspec_mi.instruments.goniophotometer import GonioOptions
    from virtspec_mi.instruments.sphere import SphereOptions

    parser = build_parser()
    for command, kinds in (("measure", (Settings,)), ("sweep", (Settings,)), ("gonio", (Settings, GonioOptions)),
                           ("sphere", (Settings, SphereOptions))):
        with pytest.raises(SystemExit):
            parser.parse_args([command, "--help"])
        text = capsys.readouterr().out
        for kind in kinds:
            for name in kind.names():
                assert ("--" + name.replace("_", "-") in text) == (name != "sphere"), (command, name)
    args = parser.parse_args(["sphere", "scene.xml", "--max-bounces", "100", "--specular", "SCE"])
    assert (args.max_bounces, args.specular) == ("100", "SCE")  # validated by SphereOptions, as the API's
