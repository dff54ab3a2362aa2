"""
The example instrument (virtspec_mi.instruments.gloss): a gloss meter, one module and one
registry row, against an independent value.

For ``simple_dielectric`` in a collimated beam every reflected ray leaves exactly in the
mirror direction, so a receptor cone holding the mirror direction catches every reflected
ray: the gloss fraction estimates the Fresnel reflectance, computed here from the Fresnel
equations (Born & Wolf, *Principles of Optics*, Sect. 1.5.2), and must lie within the
reading's own certificate (fixed seeds: a miss has probability at most δ).
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.instruments import INSTRUMENTS
from virtspec_mi.settings import Settings


def fresnel(theta: float, eta: float) -> float:
    """Unpolarised Fresnel reflectance of a smooth dielectric of index ``eta`` from air (Born & Wolf 1.5.2)."""

    cos_i = np.cos(np.radians(theta))
    cos_t = np.sqrt(1.0 - (np.sin(np.radians(theta)) / eta) ** 2)
    r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return float((r_s**2 + r_p**2) / 2)


@pytest.fixture(scope="module")
def glass(mi):
    return vm.find_bench(vm.instrument_scene({"type": "simple_dielectric", "eta": 1.5}))


def test_the_gloss_meter_is_one_registry_row_with_its_options():
    meter = INSTRUMENTS["gloss"]
    assert meter.name == "gloss" and meter.options.names() == ("cone",)
    assert meter.options(cone="2.5").cone == 2.5  # a numeric string, as every option
    for bad in (0, 95, True, "wide"):
        with pytest.raises(ValueError, match="cone"):
            meter.options(cone=bad)


@pytest.mark.parametrize("theta, seed", [(20.0, 1), (60.0, 2), (85.0, 3)])
def test_a_smooth_dielectric_reads_its_fresnel_reflectance_within_the_certificate(glass, theta, seed):
    meter = INSTRUMENTS["gloss"]
    reading = meter().run(glass, Settings(theta_i=theta, beam="collimated", seed=seed), meter.options(cone=1))
    assert isinstance(reading, meter.result)
    assert np.array_equal(reading.glossy, reading.reflected)  # every reflected ray is in the cone
    expected = fresnel(theta, 1.5)
    mu = reading.certified_mu[0, 0]
    assert mu <= 0.005 and abs(reading.gloss[0, 0] - expected) < mu
    low, high = reading.gloss_interval[0, 0]
    assert low <= expected <= high
    assert "NOT CERTIFIED" not in reading.summary()


def test_spread_directions_reach_the_receptor_only_in_part(mi, glass):
    meter = INSTRUMENTS["gloss"]
    conical = meter().run(glass, Settings(theta_i=60, rays=20_000), meter.options(cone=2))
    assert 0 < conical.glossy[0, 0] < conical.reflected[0, 0]  # a conical beam spreads the mirror directions
    rough = vm.find_bench(vm.instrument_scene({"type": "roughdielectric", "alpha": 0.2, "int_ior": 1.5}))
    wide = meter().run(rough, Settings(theta_i=60, beam="collimated", rays=20_000, seed=5), meter.options(cone=5))
    assert 0 < wide.glossy[0, 0] < wide.reflected[0, 0]


def test_two_stage_sizes_the_gloss_fraction_from_its_pilot(glass):
    meter = INSTRUMENTS["gloss"]
    reading = meter().run(glass, Settings(theta_i=60, beam="collimated", bound="two-stage", mu=0.01, seed=4),
                   meter.options(cone=1))
    assert reading.pilot is not None and reading.pilot.rays[0, 0] == 1000  # ceil(10/mu)
    assert reading.certified_mu[0, 0] == pytest.approx(0.01)
    assert abs(reading.gloss[0, 0] - fresnel(60.0, 1.5)) < 0.01


def test_a_gloss_meter_reads_at_one_angle(glass):
    meter = INSTRUMENTS["gloss"]
    with pytest.raises(ValueError, match="one theta_i"):
        meter().run(glass, Settings(rays=100), theta_i=[20, 60])
