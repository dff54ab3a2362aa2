"""
Tests of virtspec_mi.instruments.sphere.beam (and the traced beam of
virtspec_mi.instruments.sphere.real): profiles validated, the bench's beam kept bit for bit,
the traced beam against the kernel's first interaction, the spill against its exact area.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.budgets.bounds import hoeffding_mu
from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.instruments.sphere.beam import BeamProfile, parse_beam_profile
from virtspec_mi.instruments.sphere.geometry import Port, Sphere, sphere_from_parameters
from virtspec_mi.instruments.sphere.real import RealSphereLayout
from virtspec_mi.runtime.scene import find_bench
from virtspec_mi.settings import Settings

SCENE = "scenes/sphere_150mm_8d.xml"
LAMBERTIAN = {"type": "diffuse", "reflectance": 0.5}


def sphere(**extra):
    return Sphere(150, 0.98, (Port("sample", "sample", 180, 0, 12.7), Port("entrance", "entrance", 0, 0, 6.0),
                              Port("detector", "detector", 90, 90, 6.35)), **extra)


def walk(sphere_, rays, *, radius=12.7, layout=None, seed=0):
    from virtspec_mi.engine.plan import kernel_options
    from virtspec_mi.instruments.sphere.walk import SPECIMEN, Holder, holder_frame
    from virtspec_mi.kernel.tracer import ReadingPlan, tally_readings

    vm.mitsuba()
    bench = find_bench(vm.instrument_scene(LAMBERTIAN, specimen_radius=radius))
    settings = Settings(theta_i=0, beam="collimated", seed=seed)
    holder = Holder(0, SPECIMEN, radius, holder_frame(sphere_.ports[0].axis, False))
    layout = layout or sphere_.layout([holder], [6, 7, 0], 100_000, [551.0])
    tally = tally_readings(bench, [ReadingPlan(551.0, 0.0, 0.0, rays)], hook=layout, **kernel_options(settings))
    return tally.bins[0].reshape(4, layout.codes).sum(axis=0), {k: int(v[0]) for k, v in tally.sums.items()}, layout


def test_beam_profiles_are_validated_naming_the_parameter_and_its_range():
    with pytest.raises(ValueError, match="shape must be one of point, ellipse, rectangle"):
        BeamProfile("gauss")
    with pytest.raises(ValueError, match="shape ellipse needs width > 0"):
        BeamProfile("ellipse", height=2)
    with pytest.raises(ValueError, match="width must be a finite number > 0"):
        BeamProfile("rectangle", -1, 2)
    with pytest.raises(ValueError, match="divergence must satisfy 0 <= divergence < 30"):
        BeamProfile(divergence=30)
    with pytest.raises(ValueError, match="width is for shape ellipse or rectangle"):
        BeamProfile("point", width=2)
    with pytest.raises(ValueError, match="expected 'key=value' items with keys shape, width, height, divergence"):
        parse_beam_profile("size=3")
    profile = BeamProfile("rectangle", 7, 4, 0.5)
    assert parse_beam_profile(profile.text()) == profile
    assert sphere_from_parameters(sphere(beam_profile=profile).parameters()) == sphere(beam_profile=profile)
    assert sphere(beam_profile=BeamProfile("point", divergence=0.0)).beam_profile is None  # the bench's beam


def test_traced_beams_are_refused_where_they_do_not_apply():

    scene_sphere = vm.mitsuba().load_file(SCENE).integrator().sphere_options.sphere
    traced = replace(scene_sphere, beam_profile="shape=ellipse width=4 height=4")
    with pytest.raises(ValueError, match="beam_profile traces a collimated beam"):
        vm.sphere_measure(SCENE, rays=200, wavelengths="550", sphere=traced, beam="conical")
    with pytest.raises(ValueError, match="beam is too wide for the sphere"):
        vm.sphere_measure(SCENE, rays=200, wavelengths="550",
                          sphere=replace(scene_sphere, beam_profile="shape=rectangle width=200 height=4"))


def test_a_traced_point_beam_agrees_with_the_kernels_first_interaction():
    """The same physics by two routes: the specimen sampled by the kernel at its centre (the plain walk), or by the
    walk after the beam line is traced to it (independent random numbers). Each detector fraction's exact interval
    at δ = 1e-3; the intervals must meet."""

    rays = 60_000
    plain, _, layout = walk(sphere(), rays)
    traced_layout = RealSphereLayout(**{f: getattr(layout, f) for f in layout.__dataclass_fields__},
                                     beam=(0, 0.0, 0.0, 1.0))
    traced, sums, _ = walk(sphere(), rays, layout=traced_layout)
    assert sums["beam_spill"] == 0 and traced.sum() == rays
    a, b = clopper_pearson(np.array([plain[0], traced[0]]), rays, 1e-3)
    assert max(a) <= min(b)
    assert not np.array_equal(plain, traced)  # the routes do not share random numbers


def test_beam_spill_is_the_beams_area_outside_the_specimen():
    """
    A 30 × 10 mm rectangle at normal incidence on a 10 mm specimen in a 12.7 mm port:
    the spill is exactly the rectangle's area outside the specimen,
    1 − ∫ 2√(ρ² − y²) dy / 300; its count's exact interval at δ = 1e-3 holds it. The
    part of it inside the port (ρ = 10 … 12.7 mm) leaves through the port: the port's
    losses are at least that share (Hoeffding, δ = 1e-3); the rest lands on the wall round
    the port, which returns some of it into the sphere.
    """

    def inside(rho, h=5.0):  # ∫_{-h}^{h} 2√(ρ² − y²) dy: the rectangle's area within radius ρ (30 mm > 2ρ here)
        return 2 * (h * math.sqrt(rho * rho - h * h) + rho * rho * math.asin(h / rho))

    rays = 40_000
    counts, sums, _ = walk(sphere(beam_profile="shape=rectangle width=30 height=10"), rays, radius=10.0)
    low, high = clopper_pearson(sums["beam_spill"], rays, 1e-3)
    assert low <= 1.0 - inside(10.0) / 300.0 <= high
    through_port = (inside(12.7) - inside(10.0)) / 300.0
    assert counts[6] >= rays * (through_port - hoeffding_mu(rays, 1e-3))
    plain, _, _ = walk(sphere(), rays, radius=10.0)
    assert counts[0] < plain[0]  # the light lost through the port is not detected


def test_a_beam_within_the_specimen_reads_a_lambertian_as_the_point_does():
    """A Lambertian specimen's reading does not depend on where a beam lands on it nor, much, on a few degrees of
    divergence: an elliptical 6 × 4 mm beam diverging by 3° and the plain point beam agree within both intervals."""

    rays = 60_000
    plain, _, _ = walk(sphere(), rays)
    shaped, sums, _ = walk(sphere(beam_profile="shape=ellipse width=6 height=4 divergence=3"), rays)
    assert sums["beam_spill"] == 0
    a, b = clopper_pearson(np.array([plain[0], shaped[0]]), rays, 1e-3)
    assert max(a) <= min(b)


def test_a_sphere_reading_reports_its_beam_spill(tmp_path):

    scene_sphere = vm.mitsuba().load_file(SCENE).integrator().sphere_options.sphere
    traced = replace(scene_sphere, beam_profile="shape=rectangle width=30 height=6 divergence=1")
    result = vm.sphere_measure(SCENE, rays=4000, wavelengths="550", sphere=traced)
    spill = result.counts["sample"]["beam_spill"]
    assert 0 < spill[0] < 4000 and "beam shape=rectangle" in result.summary()
    assert f"beam spill (rays whose first surface was not the specimen): {spill[0] / 4000:.4f}" in result.summary()
    assert result.counts["standard"]["beam_spill"][0] == spill[0]  # the standard is the specimen's size: same beam
    result.write(tmp_path / "spill.json")
    again = type(result).read(tmp_path / "spill.json")
    assert np.array_equal(again.counts["sample"]["beam_spill"], spill)
