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


def test_several_angles_each_have_their_own_mirror_direction(glass):
    meter = INSTRUMENTS["gloss"]
    reading = meter().run(glass, Settings(rays=20_000, beam="collimated", seed=6), meter.options(cone=1),
                          theta_i=[20, 60, 85])
    assert np.array_equal(reading.glossy, reading.reflected)  # each angle's reflected rays lie in its own cone
    expected = [fresnel(t, 1.5) for t in (20, 60, 85)]
    low, high = np.moveaxis(np.asarray(reading.gloss_interval).reshape(-1, 3, 2), -1, 0)
    assert np.all((low <= expected) & (expected <= high))


def test_without_theta_i_it_reads_at_iso_2813s_three_angles_in_gloss_units(mi):
    """
    100 GU is the black glass standard (n = 1.567) at each angle: a specimen of that glass,
    read without theta_i, gives ISO 2813's 20, 60 and 85 degrees, each 100 GU within its interval.
    """

    from virtspec_mi.instruments.gloss import ISO_2813_ANGLES, standard_reflectance
    from virtspec_mi.references.quadrature import fresnel_reflectance

    assert np.allclose(standard_reflectance(ISO_2813_ANGLES), [0.0491, 0.1001, 0.6191], atol=5e-5)
    standard = vm.instrument_scene({"type": "simple_dielectric", "eta": 1.567})
    reading = vm.gloss(standard, beam="collimated", rays=200_000, cone=1, seed=3)
    assert tuple(np.atleast_1d(reading.coords["theta_i"])) == ISO_2813_ANGLES
    low, high = np.moveaxis(np.asarray(reading.gloss_units_interval).reshape(-1, 2), -1, 0)
    assert len(low) == 3 and np.all((low <= 100.0) & (100.0 <= high)), (low, high)
    theta = np.asarray(reading.coords["theta_i"], dtype=float)
    expected = 100 * np.asarray(reading.gloss).reshape(-1) / fresnel_reflectance(theta, 1.567)
    assert np.allclose(np.asarray(reading.gloss_units).reshape(-1), expected)
    text = reading.summary()
    assert text.count("GU in [") == 3 and "not one of ISO 2813's" not in text
    assert all(f"theta_i {t:g}:" in text for t in ISO_2813_ANGLES)


def test_angles_given_are_read_as_asked_and_others_than_iso_are_named(mi):
    standard = vm.instrument_scene({"type": "simple_dielectric", "eta": 1.567})
    other = vm.gloss(standard, theta_i=[45, 60], beam="collimated", rays=100, cone=1)
    assert tuple(np.atleast_1d(other.coords["theta_i"])) == (45.0, 60.0)
    assert "(theta_i 45 deg: not one of ISO 2813's 20, 60, 85)" in other.summary()
    with pytest.raises(ValueError, match="theta_i"):
        vm.gloss(standard, theta_i=95, rays=100)


def test_a_gloss_summary_reads_the_same_from_its_file(mi, tmp_path, capsys):
    """The command's squeezed print and the file read back give one heading and one text."""

    from virtspec_mi.cli import main

    out = tmp_path / "g.nc"
    assert main(["gloss", "diamond_collimated", "--theta-i", "60", "--rays", "4000", "--out", str(out)]) == 0
    printed = "".join(capsys.readouterr())
    back = vm.read_result(out).summary()
    assert back.splitlines()[:3] == printed.splitlines()[:3]
    assert "collimated reading, theta_i = 60 deg" in back and "sweep" not in back


def test_a_three_angle_reading_reads_back_to_the_same_summary(mi, tmp_path):
    """ISO 2813's three angles in one result: every format gives back the same counts and the same summary."""

    reading = vm.gloss("diamond_collimated", wavelengths=[450, 650], rays=4000, cone=2, seed=5)
    assert tuple(np.atleast_1d(reading.coords["theta_i"])) == (20.0, 60.0, 85.0)
    for suffix in (".nc", ".json", ".csv"):
        back = vm.read_result(reading.write(tmp_path / f"iso{suffix}"))
        assert np.array_equal(back.glossy, reading.glossy), suffix
        assert back.summary() == reading.summary(), suffix
