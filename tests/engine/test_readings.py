"""
Tests of virtspec_mi.engine.readings.take_readings: per-reading ray offsets (the key of a
reading's random numbers) and the tracing-once of wavelength-independent specimens.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.runtime.scene import find_bench
from virtspec_mi.settings import Settings
from plans import take_readings
from virtspec_mi.engine.readings import shares_wavelengths

WORD = 2**32


@pytest.fixture(scope="module")
def dielectric(mi):
    """Mitsuba's smooth dielectric: traced per wavelength (not flagged wavelength-independent)."""

    return find_bench(vm.instrument_scene({"type": "dielectric", "int_ior": 2.419, "ext_ior": 1.0}))


@pytest.fixture(scope="module")
def diamond_instrument(mi):
    return find_bench(vm.instrument_scene({"type": "simple_dielectric"}))


READINGS = [(500.0, 10.0, 0.0), (600.0, 40.0, 0.0), (700.0, 70.0, 0.0), (550.0, 85.0, 0.0)]


@pytest.mark.parametrize("sampling", ["jittered", "random"])
@pytest.mark.parametrize("beam", ["conical", "collimated"])
def test_a_reading_gets_the_same_rays_alone_or_with_others(dielectric, beam, sampling):
    settings = Settings(rays=3000, beam=beam, sampling=sampling, seed=9, chunk_size=4096)
    # gaps, unsorted, and one range straddling a 2**32 boundary of the global ray index
    offsets = np.array([7 * 3000, 2 * 3000, WORD - 1000, 5 * WORD + 11])
    together, _ = take_readings(dielectric, READINGS, settings, offsets=offsets)
    for k, reading in enumerate(READINGS):
        alone, _ = take_readings(dielectric, [reading], settings, offsets=offsets[k:k + 1])
        assert alone.reflected[0] == together.reflected[k]
        assert alone.transmitted[0] == together.transmitted[k]
    # and the counts do not depend on the chunk size either
    bigger, _ = take_readings(dielectric, READINGS, Settings(rays=3000, beam=beam, sampling=sampling, seed=9),
                           offsets=offsets)
    np.testing.assert_array_equal(bigger.reflected, together.reflected)
    # a different offset is different rays
    moved, _ = take_readings(dielectric, READINGS[:1], settings, offsets=[offsets[0] + 3000])
    assert moved.reflected[0] != together.reflected[0]


def test_default_offsets_are_consecutive_ranges(dielectric):
    settings = Settings(rays=2000, seed=3)
    default, _ = take_readings(dielectric, READINGS, settings)
    explicit, _ = take_readings(dielectric, READINGS, settings, offsets=np.arange(4) * 2000)
    np.testing.assert_array_equal(default.reflected, explicit.reflected)
    assert not shares_wavelengths(dielectric)


@pytest.mark.parametrize("offsets, message", [
    ([0, 100, 5000, 9000], "disjoint"),  # reading 0 (2000 rays) overlaps reading 1
    ([-1, 3000, 6000, 9000], ">= 0"),
    ([0, 3000], "one start per reading"),
    ([0.5, 3000, 6000, 9000], "whole numbers"),
])
def test_bad_offsets_are_refused(dielectric, offsets, message):
    with pytest.raises(ValueError, match=message):
        take_readings(dielectric, READINGS, Settings(rays=2000), offsets=offsets)


def test_wavelength_independent_specimen_is_traced_once_per_incidence(diamond_instrument):
    settings = Settings(rays=4000, seed=2)
    readings = [(w, t, 0.0) for t in (20.0, 60.0) for w in (400.0, 550.0, 700.0)]
    tallies, _ = take_readings(diamond_instrument, readings, settings, offsets=np.arange(6) * 4000)
    assert shares_wavelengths(diamond_instrument)
    assert len(set(tallies.reflected[:3])) == 1 and len(set(tallies.reflected[3:])) == 1
    # the shared counts are those of the first reading of each incidence, at its offset
    first, _ = take_readings(diamond_instrument, [readings[3]], settings, offsets=[3 * 4000])
    assert first.reflected[0] == tallies.reflected[3]
    np.testing.assert_array_equal(tallies.rays, 4000)


# --- issue 12: nothing hangs; every N is range-checked before tracing ---------------------------


@pytest.fixture
def _refused_fast(monkeypatch):
    """Refused before any ray is traced: the engine's one kernel call (``_fixed``) must not run."""

    from virtspec_mi.engine import readings as engine

    def untraced(*args, **kwargs):
        raise AssertionError("rays were traced before the budget was refused")

    monkeypatch.setattr(engine, "_fixed", untraced)

    def check(call, message: str) -> None:
        with pytest.raises(ValueError, match=message):
            call()

    return check


def test_huge_budgets_are_refused_before_any_ray_is_traced(diamond, _refused_fast):
    white = vm.instrument_scene({"type": "diffuse", "reflectance": {"type": "uniform", "value": 1.0}})
    _refused_fast(lambda: vm.measure(white, theta_i=88, mu=2.4e-5), "needs N = 4,599,233,825 rays per reading")
    _refused_fast(lambda: vm.measure(diamond, mu=1e-9), "hoeffding bound for mu = 1e-09")  # N = 2.6e18
    _refused_fast(lambda: vm.measure(diamond, mu=1e-9, bound="exact"), "exact bound for mu = 1e-09")
    _refused_fast(lambda: vm.measure(diamond, mu=1e-9, bound="two-stage"), "two-stage pilot")
    _refused_fast(lambda: vm.sweep(diamond, mu=2e-5, bound="two-stage", pilot_rays=100, theta_i=[0, 10]),
                  "two-stage bound for mu = 2e-05")
    _refused_fast(lambda: vm.sweep(diamond, theta_i="0:90:1e-7"), "holds 900,000,001 values")


def test_readings_and_rays_per_call_are_capped(diamond, _refused_fast):
    _refused_fast(lambda: vm.sweep(diamond, wavelengths="400:1399:1", theta_i="0:90:0.09", rays=1),
                  r"at most 1,000,000 readings .*got 1,001,000")
    dielectric = vm.instrument_scene({"type": "dielectric"})
    _refused_fast(lambda: vm.sweep(dielectric, wavelengths="400:2900:1", rays=2**32 - 1, theta_i=[10]),
                  r"at most 1e\+13 rays")
    # a wavelength-independent specimen traces one reading per angle: its rays are counted once
    instrument = find_bench(diamond)
    with pytest.raises(ValueError, match=r"at most 1e\+13 rays \(got 12,884,901,885,000 = 3,000 readings"):
        take_readings(instrument, [(500.0, float(t), 0.0) for t in np.linspace(0, 90, 3000)],
                      Settings(rays=2**32 - 1))


def test_the_second_stage_is_range_checked_before_it_is_traced(diamond, monkeypatch):
    from virtspec_mi.engine import readings as engine
    from virtspec_mi.budgets import twostage

    monkeypatch.setattr(twostage, "stage_two_rays", lambda *args, **kwargs: np.array([2**32], dtype=np.int64))
    traced = []
    original = engine._fixed
    monkeypatch.setattr(engine, "_fixed", lambda *args: traced.append(args[3]) or original(*args))
    with pytest.raises(ValueError, match="the two-stage second batch for mu = 0.05, delta = 0.2 needs N = "
                                         "4,294,967,296"):
        vm.measure(diamond, bound="two-stage", mu=0.05, delta=0.2)
    assert len(traced) == 1  # the pilot only


def test_a_tiny_mu_with_given_rays_is_a_reading(diamond):
    reading = vm.measure(diamond, mu=1e-300, rays=1000)
    assert reading.certified_mu[0] == pytest.approx(vm.hoeffding_mu(1000, 0.01), rel=1e-3)
