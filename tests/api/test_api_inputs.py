"""
Every specification checked where it enters (issue 22, items 2 and 5): the adversarial
pass's tracebacks, useless messages and nonsense accepted, each now a one-line
``ValueError`` naming the setting, the value as given and the allowed range — through
the API, the command line and the integrators' XML parameters alike — and numbers the
instrument cannot certify (wavelengths outside a specimen's data, wavelengths in
micrometres) refused before anything is traced.
"""

from __future__ import annotations

import os
import warnings

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.cli import main
from virtspec_mi.instruments.sphere.geometry import Baffle, Port, Sphere
from virtspec_mi.instruments.goniophotometer import GonioOptions

SPHERE_XML = os.path.join(os.path.dirname(__file__), "..", "..", "scenes", "sphere_150mm_8d.xml")


@pytest.fixture(scope="module")
def dielectric(mi):
    return vm.instrument_scene({"type": "simple_dielectric", "eta": 1.5})


def one_line_error(call, *words: str) -> str:
    """``call()`` raises a one-line ValueError holding every word of ``words``; its message."""

    with pytest.raises(ValueError) as error:
        call()
    message = str(error.value)
    assert "\n" not in message and all(word in message for word in words), message
    return message


# --- goniophotometer bins: RecursionError, OverflowError before -------------------------------------------


@pytest.mark.parametrize("name", ["theta_o_bins", "phi_o_bins"])
@pytest.mark.parametrize("value", [18.5, float("nan"), float("inf"), "1e400", "18.5", "nan", "", -3, 10**9, 10**400,
                                   [0, float("nan"), 90], "0:inf:1", "0:180:1e-9", "a b", {"a": 1}, "0,90,,180"])
def test_bad_bins_are_one_line_errors_naming_the_option_and_the_value(dielectric, name, value):
    message = one_line_error(lambda: vm.gonio(dielectric, rays=100, **{name: value}), name)
    assert "Recursion" not in message and "Overflow" not in message
    one_line_error(lambda: GonioOptions(**{name: value}), name)


@pytest.mark.parametrize("flags", [["--theta-o-bins", "18.5"], ["--theta-o-bins", "0:inf:1"],
                                   ["--phi-o-bins", "1e400"], ["--guarantee", "relative", "--relative-tolerance", "5",
                                                               "--brdf-floor", "1"]])
def test_bad_goniophotometer_flags_are_one_line_errors(flags, capsys):
    assert main(["gonio", "diamond_collimated", "--rays", "100", *flags]) == 1
    err = capsys.readouterr().err
    assert err.startswith("virtspec: error: ") and err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.parametrize("options, words", [
    ({"guarantee": "foo"}, ("guarantee must be one of union, union-exact, dkw, relative", "'foo'")),
    ({"guarantee": "relative", "relative_tolerance": 5, "brdf_floor": 1},
     ("relative_tolerance must satisfy 0 < relative_tolerance <= 1", "5")),
    ({"relative_tolerance": 0}, ("relative_tolerance",)),
    ({"relative_tolerance": -0.1}, ("relative_tolerance",)),
    ({"brdf_floor": float("inf")}, ("brdf_floor",)),
])
def test_guarantees_and_tolerances_are_checked_at_every_entry(mi, dielectric, options, words):
    one_line_error(lambda: vm.gonio(dielectric, mu=0.05, **options), *words)
    one_line_error(lambda: GonioOptions(**options), *words)
    integrator = {"type": "spectrophotometer", **{k: v if isinstance(v, str) else float(v) for k, v in options.items()}}
    with pytest.raises(Exception, match=words[0].replace("(", r"\(")):  # Mitsuba's loader passes the message on
        mi.load_dict({**dielectric, "integrator": integrator})


# --- specimen parameters, workers ------------------------------------------------------------------------


@pytest.mark.parametrize("values", ["1,2,,3", ",1.5", "1.5,", "", "nan", "1.4:inf:0.1", [], [1.5, float("inf")]])
def test_bad_parameter_lists_name_the_parameter(dielectric, values):
    one_line_error(lambda: vm.sweep(dielectric, parameters={"specimen.eta": values}, rays=100, progress=False),
                   "eta")


def test_an_empty_item_between_commas_is_refused_everywhere_lists_are_written():
    from virtspec_mi.base.checks import parse_theta_i, parse_values, parse_wavelengths

    for parse in (parse_wavelengths, parse_theta_i, lambda text: parse_values("eta", text)):
        with pytest.raises(ValueError, match="no empty item between commas"):
            parse("10,20,,30")
    assert parse_wavelengths("400, 500 600") == (400.0, 500.0, 600.0)


def test_workers_are_limited_to_four_per_core_of_a_local_cluster_with_the_reason(dielectric):
    from virtspec_mi.runtime.scaleout import WORKERS_PER_CORE, check_workers, local_worker_limit

    limit = WORKERS_PER_CORE * (os.cpu_count() or 1)
    assert local_worker_limit() == limit
    message = one_line_error(lambda: vm.sweep(dielectric, workers=1_000_000, rays=100),
                             f"workers must be at most {limit}", "(got 1000000)", "per core", "scheduler address")
    assert "own Mitsuba" in message
    one_line_error(lambda: vm.sweep(dielectric, workers=limit + 1, rays=100), "workers")
    assert check_workers(limit) == limit and check_workers("2") == 2  # a numeric string is the number
    assert check_workers("tcp://10.0.0.1:8786") == "tcp://10.0.0.1:8786"  # a scheduler's cluster is not limited
    one_line_error(lambda: check_workers("2x"), "workers must be", "'2x'", "tcp://host:8786")
    one_line_error(lambda: check_workers("tcp://host"), "workers", "'tcp://host'")


# --- the specimen and the sphere --------------------------------------------------------------------------


def test_a_specimen_without_a_bsdf_is_refused_not_measured_as_mitsubas_default(mi, tmp_path):
    scene = vm.instrument_scene({"type": "diffuse"})
    bare = {**scene, "specimen": {k: v for k, v in scene["specimen"].items() if k != "bsdf"}}
    one_line_error(lambda: vm.measure(bare, rays=100), "specimen", "has no BSDF", "default diffuse")
    xml = tmp_path / "bare.xml"
    xml.write_text('<scene version="3.0.0"><shape type="disk" id="emitter"><transform name="to_world">'
                   '<rotate x="1" angle="180"/><translate z="100"/></transform></shape>'
                   '<shape type="disk" id="specimen"><transform name="to_world"><scale value="12.5"/>'
                   '</transform></shape></scene>')
    one_line_error(lambda: vm.measure(str(xml), rays=100), "has no BSDF", str(xml))
    assert vm.measure(scene, rays=100).rays.sum() == 100  # given a BSDF: measured
    referenced = {**bare, "leaf": {"type": "diffuse", "id": "leaf"}}
    referenced["specimen"] = {**bare["specimen"], "bsdf": {"type": "ref", "id": "leaf"}}
    assert vm.measure(referenced, rays=100).rays.sum() == 100


def _ports():
    return (Port("sample", "sample", 180, 0, 12.5), Port("entrance", "entrance", 8, 0, 6),
            Port("detector", "detector", 90, 90, 5))


@pytest.mark.parametrize("baffle, words", [
    (5, ("baffle must be a virtspec_mi.Baffle", "(got int 5)")),
    ("junk", ("baffle: expected 'key=value' items",)),
    ("centre=0,0 normal=0,0,1 radius=3", ("baffle centre must be three numbers",)),
    (lambda: Baffle(5, (0, 0, 1), 3), ("baffle centre must be three numbers", "(got 5)")),
    (lambda: Baffle((0, 0, -72.5), (0, 1, 0), 2), ("baffle must not cross the plane of port 'sample'",)),
    (lambda: Baffle((0, 0, 0), (0, 0, 1), 80), ("baffle must lie inside the sphere",)),
])
def test_bad_baffles_are_one_line_errors(baffle, words):
    one_line_error(lambda: Sphere(150, 0.98, _ports(), baffle() if callable(baffle) else baffle), *words)


def test_a_baffle_as_text_is_read_as_the_xml_writes_it():
    sphere = Sphere(150, 0.98, _ports(), "centre=0,37.45,-36.96 normal=0,0.7118,0.7025 radius=12")
    assert isinstance(sphere.baffle, Baffle) and sphere.baffle.radius == 12.0


@pytest.mark.parametrize("ports, words", [
    ("abc", ("ports must be a sequence of virtspec_mi.Port",)),
    ([{"role": "sample"}], ("ports must be virtspec_mi.Port objects",)),
    (lambda: (Port("a b", "sample", 180, 0, 5),), ("port name must be a non-empty string",)),
    (lambda: (Port("x", "open", "ninety", 0, 5),), ("port 'x' polar must be a number", "'ninety'")),
    (lambda: (Port("a", "sample", 180, 0, 10), Port("b", "detector", 170, 0, 10)), ("ports 'a' and 'b' overlap",)),
])
def test_bad_ports_are_one_line_errors(ports, words):
    one_line_error(lambda: Sphere(150, 0.98, ports() if callable(ports) else ports), *words)


@pytest.mark.parametrize("options, word", [({"standard": "bright"}, "standard"), ({"standard": 0}, "standard"),
                                           ({"max_bounces": 18.5}, "max_bounces"), ({"sphere": "150 mm"}, "sphere"),
                                           ({"measurement": "absorptance"}, "measurement")])
def test_bad_sphere_options_name_the_option(options, word):
    one_line_error(lambda: vm.sphere_measure(SPHERE_XML, rays=100, **options), word)


def test_a_sphere_with_no_light_on_the_detector_is_not_certified_and_says_so():
    """It read NaN silently: a detector of 0.05 mm on a 150 mm sphere, 40 rays."""

    dark = Sphere(150, 0.98, (Port("sample", "sample", 180, 0, 12.7), Port("entrance", "entrance", 15.88, 0, 12.7),
                              Port("detector", "detector", 90, 90, 0.05)))
    with pytest.warns(RuntimeWarning, match="not certified: no light reached the detector"):
        result = vm.sphere_measure(SPHERE_XML, sphere=dark, rays=40, wavelengths="500, 600", progress=False)
    assert np.all(result.counts["standard"]["detected"] == 0)
    assert not result.certified.any() and result.no_light.all()
    assert np.all(np.isnan(result.reading_interval))
    assert "NOT CERTIFIED: no light reached the detector" in result.summary()
    lit = vm.sphere_measure(SPHERE_XML, rays=2000, wavelengths=500, progress=False)
    assert lit.certified.all() and not lit.no_light.any()


# --- wavelengths the instrument cannot certify ------------------------------------------------------------


@pytest.mark.parametrize("wavelengths", ["0.4:0.7:0.1", [0.55], "0.4, 2.5", 99.9])
def test_wavelengths_in_micrometres_are_refused_with_compares_hint(dielectric, wavelengths):
    one_line_error(lambda: vm.sweep(dielectric, wavelengths=wavelengths, rays=100), "wavelengths must be in nm",
                   "micrometres? multiply by 1000")
    assert vm.measure(dielectric, wavelengths=[50, 400], rays=100).rays.shape == (2,)  # one is nm: nanometres


def test_the_micrometre_rule_is_the_one_compare_uses(tmp_path):
    from virtspec_mi.base.checks import NANOMETRE_FLOOR
    from virtspec_mi.applications.comparison import read_measured

    path = tmp_path / "um.csv"
    path.write_text("0.4,0.2\n0.5,0.3\n")
    with pytest.raises(ValueError, match=f"all below {NANOMETRE_FLOOR:g} nm, micrometres\\? multiply by 1000"):
        read_measured(str(path))


def test_micrometres_on_the_command_line(capsys):
    assert main(["sweep", "diamond_collimated", "--wavelengths", "0.4:0.7:0.1", "--rays", "100"]) == 1
    assert "micrometres? multiply by 1000" in capsys.readouterr().err


@pytest.mark.parametrize("bsdf, wavelengths, words", [
    ({"type": "diffuse", "reflectance": {"type": "regular", "wavelength_min": 400, "wavelength_max": 700,
                                         "values": "0.2, 0.8"}}, [500, 800],
     ("400 <= wavelength <= 700 nm", "'reflectance' is a regular spectrum", "(got 800)")),
    ({"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.2, 0.1]}}, [1000],
     ("360 <= wavelength <= 830 nm", "'reflectance' is an RGB colour", "(got 1000)")),
    ({"type": "conductor", "material": "Au"}, [1200], ("'eta' is an irregular spectrum", "(got 1200)")),
    ({"type": "blendbsdf", "weight": 0.5, "bsdf_0": {"type": "diffuse"},
      "bsdf_1": {"type": "diffuse", "reflectance": {"type": "irregular", "wavelengths": "450, 650",
                                                    "values": "0.3, 0.6"}}}, [400],
     ("450 <= wavelength <= 650 nm", "'bsdf_1.reflectance'", "(got 400)")),
])
def test_wavelengths_outside_a_mitsuba_spectrum_are_refused_naming_it(mi, bsdf, wavelengths, words):
    scene = vm.instrument_scene(bsdf)
    one_line_error(lambda: vm.measure(scene, wavelengths=wavelengths, rays=100), "wavelengths must satisfy", *words)
    one_line_error(lambda: vm.gonio(scene, wavelengths=wavelengths, rays=100, theta_o_bins=2, phi_o_bins=2),
                   *words)


def test_an_rgb_specimen_inside_the_cie_range_is_measured(mi):
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.2, 0.1]}})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        reading = vm.measure(scene, wavelengths=[360, 600, 830], rays=2000)
    assert reading.rays.tolist() == [2000, 2000, 2000]


def test_a_turbid_slab_spectrum_and_a_measured_table_hold_their_data_range(mi):
    slab = vm.instrument_scene({"type": "turbid_slab", "mu_s": 1.0, "mu_a": {
        "type": "regular", "wavelength_min": 400, "wavelength_max": 700, "values": "1, 2"}})
    one_line_error(lambda: vm.measure(slab, wavelengths=[550, 750], rays=100), "turbid_slab", "'mu_a'", "(got 750)")
    rough = vm.instrument_scene({"type": "roughdielectric", "alpha": 0.3, "int_ior": 1.5})
    table = vm.gonio(rough, wavelengths="450, 650", rays=2000, theta_o_bins=3, phi_o_bins=4, progress=False)
    tabulated = vm.instrument_scene(vm.tabulated_bsdf(table.to_dataset()))
    assert vm.measure(tabulated, wavelengths=[450, 500, 650], rays=100).rays.sum() == 300
    one_line_error(lambda: vm.measure(tabulated, wavelengths=[700], rays=100),
                   "450 <= wavelength <= 650 nm", "(got 700)")


# --- compare's options (the measured files' contents: tests/applications/comparison/test_comparison.py) ------------------------------


@pytest.mark.parametrize("options, words", [
    ({"quantity": 5}, ("quantity must be one of",)), ({"theta_i": "abc"}, ("theta_i must be a number", "'abc'")),
    ({"theta_i": True}, ("theta_i must be a number", "True")), ({"theta_i": 45}, ("theta_i must be one of",)),
    ({"measurement_uncertainty": "x"}, ("measurement_uncertainty must be a number", "'x'")),
    ({"measurement_uncertainty": -1}, ("measurement_uncertainty must be finite and >= 0",)),
    ({"measurement_uncertainty": [0.1]}, ("measurement_uncertainty", "one value per measured point")),
    ({"illuminant": 5}, ("illuminant",)),
])
def test_compare_options_are_one_line_errors_naming_the_option(dielectric, options, words):
    from virtspec_mi.applications.comparison import compare

    reading = vm.sweep(dielectric, theta_i=8, wavelengths="400, 500, 600", rays=1000, progress=False)
    measured = ([400.0, 500.0, 600.0], [0.04, 0.04, 0.04])
    one_line_error(lambda: compare(reading, measured, **options), *words)
