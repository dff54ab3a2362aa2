"""
Property-based tests (Hypothesis) of the validate-once boundary: issue 12, "Nothing wrong,
nothing lost, nothing hangs".

Every input to ``measure``, ``sweep`` and the parameters of ``simple_dielectric`` and
``turbid_slab`` — valid values, values at and beyond their ranges, huge integers,
booleans, NaN, infinities, strings, sub-normal floats — either gives a reading whose
counts add up (reflected + transmitted + absorbed + capped + invalid = rays) and whose
values are finite, or raises ``ValueError``/``TypeError`` naming a parameter. So do the
options of issue 22: the goniophotometer's bins and guarantees (bin counts within the
escaping rays), the sphere, its ports, baffle and options (every fate of both
configurations adds up to the rays; never certified without light on the detector),
specimen parameter lists and ``workers`` (a cluster size within the machine, an address,
or a one-line refusal). Each example must finish within the deadline; the whole run
within a memory budget. Derandomized with fixed example counts: the same examples on
every run (~13 s here).
"""

from __future__ import annotations

import math
import resource
import warnings
from pathlib import Path

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, event, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import virtspec_mi as vm  # noqa: E402

PROFILE = settings(derandomize=True, deadline=5000, database=None,
                   suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
MEMORY_BUDGET_KIB = 3 * 1024 * 1024  # peak resident memory of the test process

# Values no setting takes, and values at the edges of the float range.
ODD = [10**400, -(10**400), True, False, np.bool_(True), None, "", "abc", float("nan"), float("inf"),
       float("-inf"), 5e-324, 1e-300, 1e300, [], [1.0], {"a": 1}]


def odd_or(*strategies: st.SearchStrategy) -> st.SearchStrategy:
    return st.one_of(*strategies, st.sampled_from(ODD))


# Valid values of each setting (kept cheap: small rays, mu >= 0.02, delta >= 1e-3) ...
VALID = {
    "theta_i": st.one_of(st.floats(0, 90), st.sampled_from([0, 90, 89.999, "45"])),
    "phi_i": st.floats(-1e6, 1e6),
    "wavelengths": st.one_of(st.floats(380, 2600), st.lists(st.floats(1e-3, 1e6), min_size=1, max_size=3),
                             st.sampled_from(["400:700:100", "465, 551", 399.99999999, 1e-3, 1e6])),
    "mu": st.floats(0.02, 0.49),
    "delta": st.floats(1e-3, 0.99),
    "rays": st.integers(1, 3000),
    "bound": st.sampled_from(["hoeffding", "chebyshev", "exact", "two-stage"]),
    "joint": st.sampled_from([True, False, "true", "false", 0, 1]),
    "pilot_rays": st.integers(1, 500),
    "pilot_delta": st.floats(1e-6, 1e-3),
    "beam": st.sampled_from(["conical", "collimated", "diffuse"]),
    "sampling": st.sampled_from(["jittered", "random", "concentric"]),
    "seed": st.one_of(st.integers(0, 2**32 - 1), st.just("7")),
    "chunk_size": st.sampled_from([1024, 5000, 2**22, 2**25]),
}
# ... and what else each may be given: out of range, beyond the float range, not a number, edge cases.
ODD_VALUES = {
    "theta_i": odd_or(st.floats(), st.sampled_from([-1e-300, 90.0000001, 10**400])),
    "phi_i": odd_or(st.floats(), st.integers()),
    "wavelengths": odd_or(st.floats(), st.lists(st.floats(), max_size=3), st.sampled_from(
        ["400:700:1e-6", "1:1e12:1", "400:inf:1", "700:400:10", "0:1:0", 1e-300, 1e39, 0, -5, [True], "400:700:10 x",
         "1e-4", 1.0000001e6])),
    "mu": odd_or(st.floats(), st.sampled_from([1e-9, 2.4e-5, 1e-4, 0, 0.5, -0.1, 3e-308, "0.1"])),
    "delta": odd_or(st.floats(), st.sampled_from([0, 1, 1.5, 3e-308, 1e-300, 1e-30, "0.05"])),
    "rays": odd_or(st.integers(-3, 0), st.floats(), st.sampled_from([2**32, 1.5, 1000.0, "100"])),
    "bound": odd_or(st.sampled_from(["magic", 3, "Hoeffding"])),
    "joint": odd_or(st.sampled_from(["yes", 2, -1, 0.5])),
    "pilot_rays": odd_or(st.sampled_from([0, 2**32, 1.5, -1])),
    "pilot_delta": odd_or(st.floats(), st.sampled_from([0, 1, 0.999, 0.5])),
    "beam": odd_or(st.sampled_from(["laser", "Conical"])),
    "sampling": odd_or(st.sampled_from(["sobol", 0])),
    "seed": odd_or(st.integers(), st.sampled_from([2**32, -1, 1.5, "x"])),
    "chunk_size": odd_or(st.integers(-5, 2**31), st.sampled_from([10, 1023, 2**25 + 1, 2**30, 1e4, 4096.5])),
}
def mostly_valid(valid: dict, odd: dict) -> st.SearchStrategy:
    """Keywords: any of ``valid``'s names with valid values, and sometimes one of ``odd``'s given something odd."""

    return st.tuples(
        st.fixed_dictionaries({}, optional=valid),
        st.one_of(st.none(), st.sampled_from(sorted(odd)).flatmap(
            lambda name: st.tuples(st.just(name), odd[name])))).map(
        lambda pair: {**pair[0], **({pair[1][0]: pair[1][1]} if pair[1] else {})})


MEASURE_SETTINGS = mostly_valid(VALID, ODD_VALUES)
"""A measurement: mostly valid settings, and sometimes one given something odd."""


def _small_enough(kwargs: dict) -> bool:
    """Keep valid examples cheap: the ray budget of an example (when valid) is at most ~10⁶ rays."""

    from virtspec_mi.settings import Settings

    try:
        s = Settings(**{k: v for k, v in kwargs.items() if v is not None})
        per = s.rays_per_reading if not s.adaptive else s.pilot_rays_per_reading + s.most_rays_per_reading
    except (ValueError, TypeError):
        return True  # refused anyway: quick
    return per * len(s.wavelengths) <= 2_000_000 and (s.chunk_size >= 4096 or per * len(s.wavelengths) < 10**5)


def check_outcome(call, names: set[str]) -> None:
    """``call()`` gives readings whose counts add up and values are finite, or a ValueError/TypeError naming one of ``names``."""

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # not certified readings warn: fine here
            result = call()
    except (ValueError, TypeError) as error:
        message = str(error)
        assert any(name in message for name in names), f"{type(error).__name__} names none of {sorted(names)}: {message}"
        event("refused")
        return
    n = result.rays
    assert np.all(n >= 1)
    total = result.reflected + result.transmitted + result.absorbed + result.capped + result.invalid_directions
    np.testing.assert_array_equal(total, n)
    for count in (result.reflected, result.transmitted, result.absorbed, result.capped, result.invalid_directions):
        assert np.all(count >= 0)
    for values in (result.reflectance, result.transmittance, result.absorptance):
        assert np.all(np.isfinite(values)) and np.all((values >= 0) & (values <= 1))
    mu = result.certified_mu
    assert np.all(np.isnan(mu) == ~result.certified)
    assert np.all(np.isfinite(mu[result.certified])) and np.all(mu[result.certified] > 0)
    assert result.summary()
    event("reading" if result.certified.all() else "reading, not certified")


@pytest.fixture(scope="module")
def scenes(mi):
    """A wavelength-independent specimen (diamond) and a spectral one (Mitsuba's diffuse), loaded once."""

    return {"diamond": mi.load_dict(vm.instrument_scene({"type": "simple_dielectric"})),
            "spectral": mi.load_dict(vm.instrument_scene({"type": "diffuse", "reflectance": {
                "type": "regular", "wavelength_min": 400, "wavelength_max": 700, "values": "0.2, 0.8"}}))}


@settings(PROFILE, max_examples=150)
@given(kwargs=MEASURE_SETTINGS, spectral=st.booleans())
def test_measure_gives_a_consistent_reading_or_names_a_parameter(scenes, kwargs, spectral):
    if not _small_enough(kwargs):
        event("skipped: too many rays")
        return
    scene = scenes["spectral" if spectral else "diamond"]
    check_outcome(lambda: vm.measure(scene, **kwargs), set(kwargs) | {"rays"})


SWEEP_ANGLES = odd_or(st.floats(0, 90), st.lists(st.floats(-1, 91), min_size=0, max_size=4),
                      st.sampled_from(["0:90:30", "0:90:1e-7", "0:inf:1", "10:0:1", [0, 0], "0:90:45 20"]))


@settings(PROFILE, max_examples=60)
@given(kwargs=MEASURE_SETTINGS, angles=SWEEP_ANGLES)
def test_sweep_gives_consistent_readings_or_names_a_parameter(scenes, kwargs, angles):
    kwargs = {k: v for k, v in kwargs.items() if k != "theta_i"}
    if not _small_enough(kwargs):
        event("skipped: too many rays")
        return
    check_outcome(lambda: vm.sweep(scenes["spectral"], theta_i=angles, progress=False, **kwargs),
                  set(kwargs) | {"theta_i", "rays"})


@settings(PROFILE, max_examples=40)
@given(eta=st.one_of(st.floats(0.2, 5), st.floats(1e-6, 1e6), st.floats(), st.integers(), st.sampled_from(ODD)),
       theta_i=st.sampled_from([0.0, 30.0, 89.0, 90.0]))
def test_simple_dielectric_eta(mi, eta, theta_i):
    def call():
        return vm.measure(vm.instrument_scene({"type": "simple_dielectric", "eta": eta}), theta_i=theta_i,
                          beam="collimated", rays=500)

    check_outcome(call, {"eta"})


def _spectrum(values: list[float]) -> dict:
    return {"type": "regular", "wavelength_min": 400, "wavelength_max": 700, "values": ", ".join(map(repr, values))}


def _slab_value(low: float, high: float) -> st.SearchStrategy:
    return st.one_of(st.floats(low, high), st.lists(st.floats(max(low, 0.0), high), min_size=2, max_size=3).map(_spectrum))


VALID_SLAB = {"mu_a": _slab_value(0, 20), "mu_s": _slab_value(0, 50), "g": _slab_value(-1, 1),
              "eta": _slab_value(1, 2.5), "eta_above": _slab_value(1, 1.5), "eta_below": _slab_value(1, 1.5),
              "thickness": st.one_of(st.floats(1e-3, 2), st.just("inf")), "max_steps": st.sampled_from([1, 1000])}
SLAB_ODD = odd_or(st.floats(), st.integers(-2, 3), st.sampled_from([1e-40, 1e-31, 1e-30, 1e30, 1e31, 1e39, 1e7]),
                  st.lists(st.floats(0, 2e31), min_size=2, max_size=3).map(_spectrum))
SLAB = st.tuples(st.fixed_dictionaries({}, optional=VALID_SLAB),
                 st.one_of(st.none(), st.tuples(st.sampled_from(sorted(VALID_SLAB)), SLAB_ODD))).map(
    lambda pair: {**pair[0], **({pair[1][0]: pair[1][1]} if pair[1] else {})})


@settings(PROFILE, max_examples=60)
@given(params=SLAB, wavelengths=st.sampled_from([551, [450, 650], [500, 800]]))
def test_turbid_slab_parameters(mi, params, wavelengths):
    def call():
        return vm.measure(vm.instrument_scene({"type": "turbid_slab", **params}), rays=300, wavelengths=wavelengths,
                          beam="collimated")

    check_outcome(call, set(params) | {"mu_a + mu_s"})


def test_the_properties_stayed_within_the_memory_budget():
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss < MEMORY_BUDGET_KIB
    assert math.isfinite(MEMORY_BUDGET_KIB)


# --- issue 22: the new instruments' options, specimen parameters and workers ------------------------------

BIN_VALUES = st.one_of(st.integers(1, 12),
                       st.sampled_from(["6", "0:90:30", "0 30 90 120 180", "0:360:90", [0, 45, 90]]),
                       st.floats(), st.integers(-3, 2**70), st.sampled_from(
                           ["18.5", "1e400", "0:inf:1", "0:180:1e-9", "nan", "0,90,,180", "", "90:0:10",
                            [0, float("nan"), 90], [[0, 90], [90, 180]], [0, 200], 18.5]), st.sampled_from(ODD))
VALID_GONIO = {
    "theta_o_bins": st.one_of(st.integers(1, 9), st.just("0 30 90 120 180")),
    "phi_o_bins": st.one_of(st.integers(1, 12), st.just("0:360:90")),
    "binning": st.sampled_from(["uniform", "projected"]),
    "fold_phi": st.sampled_from([True, False, "true"]),
    "hemispheres": st.sampled_from(["both", "reflection", "transmission"]),
    "guarantee": st.sampled_from(["union", "union-exact", "dkw"]),
}
ODD_GONIO = {
    "theta_o_bins": BIN_VALUES, "phi_o_bins": BIN_VALUES,
    "binning": odd_or(st.sampled_from(["log", "Uniform"])), "fold_phi": odd_or(st.sampled_from(["maybe", 2])),
    "hemispheres": odd_or(st.sampled_from(["upper"])), "guarantee": odd_or(st.sampled_from(["foo", "Union"])),
    "relative_tolerance": odd_or(st.floats(), st.sampled_from([0, 5, -0.1, 1.0000001, "0.1"])),
    "brdf_floor": odd_or(st.floats(), st.sampled_from([0, -1, "1"])),
}
GONIO = mostly_valid(VALID_GONIO, ODD_GONIO)


@settings(PROFILE, max_examples=80)
@given(options=GONIO)
def test_goniophotometer_options_give_consistent_bins_or_name_an_option(scenes, options):
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            reading = vm.gonio(scenes["diamond"], theta_i=30, rays=300, mu=0.2, progress=False, **options)
    except (ValueError, TypeError) as error:
        assert "\n" not in str(error) and any(name in str(error) for name in {*options, "delta/K"}), str(error)
        event("refused")
        return
    counts = reading.bin_counts
    assert counts.dtype == np.int64 and np.all(counts >= 0)
    escaped = reading.result.reflected + reading.result.transmitted
    assert np.all(counts.sum(axis=(-2, -1)) <= escaped)
    event("reading")


SPHERE_XML = str(Path(__file__).resolve().parents[1] / "scenes" / "sphere_150mm_8d.xml")
VALID_SPHERE = {
    "sample_polar": st.floats(176, 180), "sample_radius": st.floats(12.7, 16), "entrance_polar": st.floats(14, 18),
    "detector_radius": st.floats(0.01, 10), "wall": st.floats(0, 1),
    "baffle": st.sampled_from([None, "centre=0,37.45,-36.96 normal=0,0.7118,0.7025 radius=12"]),
    "standard": st.floats(0.5, 1), "max_bounces": st.integers(1, 1000), "specular": st.sampled_from(["SCI", "sce"]),
}
ODD_SPHERE = {
    "sample_polar": odd_or(st.floats(), st.sampled_from([181, -1, "180"])),
    "sample_radius": odd_or(st.floats(), st.sampled_from([0.5, 80, -1])),
    "entrance_polar": odd_or(st.floats(), st.sampled_from([170, 179, "x"])),  # overlapping the sample port
    "detector_radius": odd_or(st.floats(), st.sampled_from([0, 1e-30, 75])),
    "wall": odd_or(st.floats(), st.sampled_from([1.5, -0.1, "400:0.9, 700:1.2", "0.9,,0.8"])),
    "baffle": odd_or(st.sampled_from(["junk", 5, "centre=0,0,-72.5 normal=0,1,0 radius=2",
                                      "centre=0,0 normal=0,0,1 radius=1",
                                      "centre=0,0,0 normal=0,0,0 radius=3", "centre=nan,0,0 normal=0,0,1 radius=3",
                                      "centre=0,0,0 normal=0,0,1 radius=80"])),
    "standard": odd_or(st.floats(), st.sampled_from([0, 1.5, "0.9"])),
    "max_bounces": odd_or(st.sampled_from([0, 10**8, 18.5, "100"])),
    "specular": odd_or(st.sampled_from(["both"])), "measurement": odd_or(st.sampled_from(["absorptance"])),
    "method": odd_or(st.sampled_from(["comparison", "twice"])),
}
SPHERE = mostly_valid(VALID_SPHERE, ODD_SPHERE)


@settings(PROFILE, max_examples=40)
@given(spec=SPHERE)
def test_a_sphere_gives_readings_whose_fates_add_up_or_names_what_is_wrong(spec):
    from virtspec_mi.instruments.sphere.geometry import Port, Sphere
    from virtspec_mi.instruments.sphere.walk import FATES

    geometry = {name: spec.pop(name) for name in list(spec) if name in ODD_SPHERE and name not in (
        "standard", "max_bounces", "specular", "measurement", "method")}
    try:
        sphere = Sphere(150, geometry.get("wall", 0.98), (
            Port("sample", "sample", geometry.get("sample_polar", 180), 0, geometry.get("sample_radius", 12.7)),
            Port("entrance", "entrance", geometry.get("entrance_polar", 15.88), 0, 12.7),
            Port("detector", "detector", 90, 90, geometry.get("detector_radius", 6.35))), geometry.get("baffle"))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # no light on the detector: said, not certified
            result = vm.sphere_measure(SPHERE_XML, sphere=sphere, rays=200, wavelengths=551, progress=False, **spec)
    except (ValueError, TypeError) as error:
        assert "\n" not in str(error) and "Traceback" not in str(error), str(error)
        event("refused")
        return
    for configuration in ("sample", "standard"):
        counts = result.counts[configuration]
        lost = sum(counts[f"lost_{port.name}"] for port in sphere.ports)
        np.testing.assert_array_equal(sum(counts[name] for name in FATES) + lost, counts["rays"])
    assert not np.any(result.certified & result.no_light)  # never certified without light on the detector
    event("reading" if result.certified.all() else "reading, not certified")


@settings(PROFILE, max_examples=40)
@given(values=odd_or(st.lists(st.floats(1.1, 2.5), min_size=1, max_size=3), st.floats(), st.sampled_from(
    ["1.2,1.5", "1.2:1.6:0.2", "1,2,,3", ",1.5", "1.5,", "1.4:inf:0.1", "1.5 x", [1.5, float("nan")], "1e400"])))
def test_specimen_parameter_lists_give_readings_or_name_the_parameter(scenes, values):
    check_outcome(lambda: vm.sweep(scenes["diamond"], parameters={"specimen.eta": values}, rays=200, progress=False),
                  {"eta"})


@settings(PROFILE, max_examples=60)
@given(workers=odd_or(st.integers(-5, 10**7), st.sampled_from(["2", " 3 ", "2x", "tcp://host", "tcp://10.0.0.1:8786",
                                                              "inproc://x", 2.5, np.int64(2)])))
def test_workers_are_a_cluster_size_within_the_machine_an_address_or_named(workers):
    import os

    from virtspec_mi.runtime.scaleout import check_workers

    try:
        checked = check_workers(workers)
    except ValueError as error:
        assert "workers" in str(error) and "\n" not in str(error)
        event("refused")
        return
    assert checked is None or isinstance(checked, str) or 1 <= checked <= 4 * (os.cpu_count() or 1)
    event("accepted")
