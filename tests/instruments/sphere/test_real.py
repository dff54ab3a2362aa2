"""
Tests of virtspec_mi.instruments.sphere.real: the walk of real ports (a port wall of given
depth and reflectance, elliptical and rectangular openings) against today's walk in its
limits (bit for bit) and against the sphere theory where it has a closed form.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.instruments.sphere import SphereOptions
from virtspec_mi.instruments.sphere import theory as st
from virtspec_mi.instruments.sphere.geometry import Port, Sphere
from virtspec_mi.instruments.sphere.model import theory_inputs
from virtspec_mi.instruments.sphere.real import RealSphereLayout
from virtspec_mi.instruments.sphere.walk import SphereLayout
from virtspec_mi.runtime.scene import find_bench
from virtspec_mi.settings import Settings

LAMBERTIAN = {"type": "diffuse", "reflectance": 0.5}


def walk(sphere, rays, *, bsdf=LAMBERTIAN, radius=12.7, settings=None, layout=None):
    """One reading at 551 nm of ``sphere`` (sample, entrance, detector ports; the sample port's rays lost, the
    entrance's lost, the detector's detected): per fate code its count, and the walk's sums."""

    from virtspec_mi.engine.plan import kernel_options
    from virtspec_mi.instruments.sphere.walk import SPECIMEN, Holder, holder_frame
    from virtspec_mi.kernel.tracer import ReadingPlan, tally_readings

    vm.mitsuba()
    bench = find_bench(vm.instrument_scene(bsdf, specimen_radius=radius))
    settings = settings or Settings(theta_i=0, beam="collimated")
    holder = Holder(0, SPECIMEN, radius, holder_frame(sphere.ports[0].axis, False))
    layout = layout or sphere.layout([holder], [6, 7, 0], 100_000, [551.0])
    tally = tally_readings(bench, [ReadingPlan(551.0, settings.theta_i, settings.phi_i, rays)], hook=layout,
                           **kernel_options(settings))
    return tally.bins[0].reshape(4, layout.codes).sum(axis=0), {k: int(v[0]) for k, v in tally.sums.items()}, layout


def sphere(sample=None, detector=None, **extra):
    return Sphere(150, 0.98, (sample or Port("sample", "sample", 180, 0, 12.7), Port("entrance", "entrance", 0, 0, 6.0),
                              detector or Port("detector", "detector", 90, 90, 6.35)), **extra)


def test_knife_edges_take_the_plain_walk():
    """depth 0, a circle and no beam profile: the plain layout (today's kernel), not the real one."""

    plain = sphere(Port("sample", "sample", 180, 0, 12.7, depth=0.0), beam_profile="shape=point divergence=0")
    assert plain == sphere() and plain.beam_profile is None
    counts, sums, layout = walk(plain, 4000)
    assert type(layout) is SphereLayout
    reference, reference_sums, _ = walk(sphere(), 4000)
    assert np.array_equal(counts, reference) and sums == reference_sums


@pytest.mark.parametrize("case", ["shallow_sample_port", "shallow_detector", "round_ellipse", "hemisphere_view",
                                  "no_mirror"])
def test_real_walk_reproduces_todays_counts_in_its_limits(case):
    """The real walk itself (cylinders, non-circular caps, a field of view, the mirror share) in the limits where it
    must be today's walk: a port wall 1 nm deep (the ray enters its cylinder at the rim plane and leaves it at once),
    an ellipse of equal axes, a field of view a hair under the hemisphere (every ray reaching the cap moves outwards
    across its rim plane), a mirror share of 1e-12 (below the smallest uniform number but 0); the same random numbers,
    so the very same counts, fate by fate."""

    real = {"shallow_sample_port": sphere(Port("sample", "sample", 180, 0, 12.7, depth=1e-6, edge_reflectance=0.0)),
            "shallow_detector": sphere(detector=Port("detector", "detector", 90, 90, 6.35, depth=1e-6,
                                                     edge_reflectance=0.0)),
            "round_ellipse": sphere(detector=Port("detector", "detector", 90, 90, shape="ellipse", width=12.7,
                                                  height=12.7)),
            "hemisphere_view": sphere(detector=Port("detector", "detector", 90, 90, 6.35, field_of_view=89.999999)),
            "no_mirror": sphere(wall_specular=1e-12)}[case]
    counts, sums, layout = walk(real, 20000)
    assert type(layout) is RealSphereLayout
    reference, reference_sums, _ = walk(sphere(), 20000)
    assert np.array_equal(counts, reference) and sums == reference_sums


def _theory_detected(sphere_, rho_s=0.5):
    kw = theory_inputs(sphere_, SphereOptions(), [551.0])
    fractions = {k: kw[k] for k in ("sample_fraction", "detector_fraction", "open_fraction")}
    return rho_s * st.detected_fraction(0.98, rho_s, port_surface="flat", **fractions)


@pytest.mark.parametrize("detector", [
    Port("detector", "detector", 90, 90, 12.0, depth=8.0, edge_reflectance=0.0),
    Port("detector", "detector", 90, 90, shape="ellipse", width=30.0, height=14.0),
    Port("detector", "detector", 90, 90, shape="rectangle", width=24.0, height=10.0)], ids=["deep", "ellipse", "rect"])
def test_real_detector_port_matches_the_theory(detector):
    """
    The detector fraction against the sphere theory's flat model with the port's exact
    share: a black-walled port of depth d passes F(d, r), the view factor between its rim
    disk and its outer end (``disk_view_factor``); a non-circular port counts its exact
    area share (``shaped_fraction``). A conical beam lights the specimen uniformly, as
    the theory assumes (see test_sphere_walk). The theory's value must lie in the
    detector count's exact Clopper–Pearson interval at δ = 1e-3.
    """

    real = sphere(detector=detector)
    rays = 105_967
    counts, _, _ = walk(real, rays, settings=Settings(theta_i=0, beam="conical"))
    low, high = clopper_pearson(counts[0], rays, 1e-3)
    assert low <= _theory_detected(real) <= high
    if detector.depth:  # and the port wall matters: the knife edge's theory lies far outside that interval
        knife = sphere(detector=Port("detector", "detector", 90, 90, 12.0))
        assert _theory_detected(knife) > high + 3 * (high - low)


def test_port_wall_reflectance_and_a_recessed_specimen():
    """A reflecting port wall returns light the black one absorbs; a recessed specimen's light meets its port wall
    (fewer detections with a black wall); every ray keeps exactly one fate; the theory refuses what it does not model."""

    rays = 20000
    black, _, _ = walk(sphere(detector=Port("detector", "detector", 90, 90, 6.35, depth=6.0, edge_reflectance=0.0)),
                       rays)
    white, sums, _ = walk(sphere(detector=Port("detector", "detector", 90, 90, 6.35, depth=6.0,
                                               edge_reflectance=0.99)), rays)
    knife, _, _ = walk(sphere(), rays)
    assert black[0] < white[0] and black[0] < knife[0] and black.sum() == white.sum() == rays
    recessed, _, _ = walk(sphere(Port("sample", "sample", 180, 0, 12.7, depth=5.0, edge_reflectance=0.0)), rays)
    assert recessed[0] < 0.8 * knife[0] and recessed.sum() == rays
    with pytest.raises(ValueError, match="does not model port 'detector'"):
        theory_inputs(sphere(detector=Port("detector", "detector", 90, 90, 6.35, depth=6.0)), SphereOptions(), [551.0])
    with pytest.raises(ValueError, match="recessed"):
        theory_inputs(sphere(Port("sample", "sample", 180, 0, 12.7, depth=5.0, edge_reflectance=0.0)),
                      SphereOptions(), [551.0])


def test_holder_mask():
    """
    A clip in front of the specimen: with the mask's reflectance equal to a Lambertian
    specimen's (0.5) the port holds one 0.5 Lambertian disk as before, so the detector
    fractions' exact intervals (δ = 1e-3) meet; a black mask detects less, beyond them; an
    aperture is validated; the theory refuses it.
    """

    rays = 60_000
    plain, _, _ = walk(sphere(), rays)
    grey, _, _ = walk(sphere(Port("sample", "sample", 180, 0, 12.7, aperture=6.0, mask_reflectance=0.5)), rays)
    black, _, _ = walk(sphere(Port("sample", "sample", 180, 0, 12.7, aperture=6.0, mask_reflectance=0.0)), rays)
    white, _, _ = walk(sphere(Port("sample", "sample", 180, 0, 12.7, aperture=6.0, mask_reflectance=1.0)), rays)
    (a_plain, a_grey, a_black, a_white), (b_plain, b_grey, b_black, b_white) = clopper_pearson(
        np.array([plain[0], grey[0], black[0], white[0]]), rays, 1e-3)
    assert max(a_plain, a_grey) <= min(b_plain, b_grey)
    assert b_black < a_white
    assert grey.sum() == black.sum() == rays
    with pytest.raises(ValueError, match="aperture must satisfy 0 < aperture < radius = 12.7 mm"):
        Port("sample", "sample", 180, 0, 12.7, aperture=12.7)
    with pytest.raises(ValueError, match="mask_reflectance must satisfy 0 <= mask_reflectance <= 1"):
        Port("sample", "sample", 180, 0, 12.7, aperture=6, mask_reflectance=2)
    with pytest.raises(ValueError, match="holder mask"):
        theory_inputs(sphere(Port("sample", "sample", 180, 0, 12.7, aperture=6.0)), SphereOptions(), [551.0])


@pytest.mark.parametrize("gamma", [30.0, 60.0])
def test_detector_field_of_view_matches_the_theory(gamma):
    """A detector counting only rays within γ of its axis: Lambertian light from a uniformly bright wall arrives
    within γ with probability sin²γ, so the theory's detector share is cap · sin²γ (the rest lost); its value lies in
    the count's exact interval at δ = 1e-3. γ = 90 is today's detector (the plain walk, bit for bit)."""

    real = sphere(detector=Port("detector", "detector", 90, 90, 12.0, field_of_view=gamma))
    rays = 105_967
    counts, _, _ = walk(real, rays, settings=Settings(theta_i=0, beam="conical"))
    low, high = clopper_pearson(counts[0], rays, 1e-3)
    assert low <= _theory_detected(real) <= high
    whole = sphere(detector=Port("detector", "detector", 90, 90, 6.35, field_of_view=90))
    assert whole == sphere() and type(walk(whole, 10, layout=None)[2]) is SphereLayout
    with pytest.raises(ValueError, match="field_of_view must satisfy 0 < field_of_view <= 90"):
        Port("detector", "detector", 90, 90, 6.35, field_of_view=0)
    with pytest.raises(ValueError, match="field_of_view is for a port with role detector"):
        Port("open", "open", 90, 90, 6.35, field_of_view=10)


@pytest.mark.parametrize("share", [0.7, 1.0])
def test_a_partly_specular_wall(share):
    """
    The wall as a Lambertian + mirror mix. A closed sphere (a white specimen filling the
    only port behind a mask, wall and mask of reflectance 0.9): every wall or mask event
    survives with probability 0.9 whatever the direction law, so each ray's number of
    surviving wall reflections is exactly geometric, mean ρ/(1 − ρ) = 9, variance
    ρ/(1 − ρ)² = 90, with or without mirrors, and every ray ends absorbed by the wall.
    The mean of N rays lies within Chebyshev's bound √(90/(N δ)) at δ = 1e-3. 0 is the
    Lambertian wall (the plain walk, bit for bit); the theory refuses a mirror share.
    """

    with pytest.raises(ValueError, match="wall_specular must satisfy 0 <= wall_specular <= 1"):
        sphere(wall_specular=1.5)
    assert sphere(wall_specular=0.0) == sphere()
    rays = 200_000
    closed = Sphere(150, 0.9, (Port("sample", "sample", 180, 0, 12.7, aperture=12.0, mask_reflectance=0.9),),
                    wall_specular=share)
    counts, sums, layout = walk(closed, rays, bsdf={"type": "diffuse", "reflectance": 1.0}, radius=12.7 * 1.001)
    assert layout.wall_specular == share and counts[1] == rays
    assert abs(sums["wall_reflections"] / rays - 9.0) < math.sqrt(90.0 / (rays * 1e-3))
    with pytest.raises(ValueError, match="non-Lambertian wall"):
        theory_inputs(sphere(wall_specular=0.5), SphereOptions(), [551.0])


def test_a_specimen_standing_proud_of_its_port():
    """
    A specimen on a post standing s into the sphere: s = 1 nm is today's reading count for
    count (the real walk's plane test and post side in their limit); a black post absorbs
    light the white one returns (beyond both exact intervals at δ = 1e-3); a smaller specimen
    standing proud lets light pass round it and out through the port; validated; the theory
    refuses it.
    """

    rays = 60_000
    plain, sums, _ = walk(sphere(), 20000)
    shallow, shallow_sums, layout = walk(sphere(Port("sample", "sample", 180, 0, 12.7, proud=1e-6)), 20000)
    assert type(layout) is RealSphereLayout and np.array_equal(plain, shallow) and sums == shallow_sums
    black, _, _ = walk(sphere(Port("sample", "sample", 180, 0, 12.7, proud=10.0, edge_reflectance=0.0)), rays)
    white, _, _ = walk(sphere(Port("sample", "sample", 180, 0, 12.7, proud=10.0, edge_reflectance=1.0)), rays)
    (a_black, a_white), (b_black, b_white) = clopper_pearson(np.array([black[0], white[0]]), rays, 1e-3)
    assert b_black < a_white and black[1] > white[1]
    small, _, _ = walk(sphere(Port("sample", "sample", 180, 0, 12.7, proud=5.0)), 20000, radius=8.0)
    assert small[6] > 0 and small.sum() == 20000
    with pytest.raises(ValueError, match="proud must satisfy proud >= 0"):
        Port("sample", "sample", 180, 0, 12.7, proud=-1)
    with pytest.raises(ValueError, match="proud must satisfy 0 <= proud < "):
        sphere(Port("sample", "sample", 180, 0, 12.7, proud=80))
    with pytest.raises(ValueError, match="excludes depth and aperture"):
        Port("sample", "sample", 180, 0, 12.7, proud=2, depth=1)
    with pytest.raises(ValueError, match="standing proud"):
        theory_inputs(sphere(Port("sample", "sample", 180, 0, 12.7, proud=2.0)), SphereOptions(), [551.0])


@pytest.mark.parametrize("case", ["transmittance", "comparison"])
def test_real_holders_in_every_configuration(case):
    """
    The real walk with two holders and with a specimen lit from outside: a port wall 1 nm
    deep on every port that holds something (the transmittance specimen at the entrance,
    the standard in the sample port; the comparison's standard in the reference port) reads
    today's counts, count for count, through the whole instrument; real holders (2 mm
    recess, a mask) keep every ray's one fate.
    """

    scene, options = (("scenes/sphere_leaf_60mm.xml", {"measurement": "transmittance"}) if case == "transmittance"
                      else ("scenes/sphere_150mm_8d.xml", {"method": "comparison"}))
    settings = {"rays": 3000, "wavelengths": "550, 800", **options}
    plain = vm.mitsuba().load_file(scene).integrator().sphere_options.sphere  # the scene's sphere
    holders = ("entrance", "sample") if case == "transmittance" else ("sample", "reference")

    def real(**change):
        from dataclasses import replace

        return replace(plain, ports=tuple(replace(p, **change) if p.role in holders else p for p in plain.ports))

    reference = vm.sphere_measure(scene, sphere=plain, **settings)
    shallow = vm.sphere_measure(scene, sphere=real(depth=1e-6), **settings)
    for configuration in ("sample", "standard"):
        for name, values in reference.counts[configuration].items():
            assert np.array_equal(shallow.counts[configuration][name], values), (configuration, name)
    for change in ({"depth": 2.0, "edge_reflectance": 0.5}, {"aperture": 6.0, "mask_reflectance": 0.3}):
        result = vm.sphere_measure(scene, sphere=real(**change), **settings)
        for configuration in ("sample", "standard"):
            counts = result.counts[configuration]
            ends = sum(v for k, v in counts.items() if k in ("detected", "absorbed_wall", "absorbed_specimen",
                                                                "absorbed_other", "capped", "invalid_directions")
                       or k.startswith("lost_"))
            assert np.all(ends == counts["rays"])
        assert np.all(np.isfinite(result.reading))


def test_the_wall_as_any_bsdf():
    """
    The wall as a Mitsuba BSDF sampled at each wall event: a ``diffuse`` BSDF of reflectance
    0.98 is the Lambertian wall by another route (independent random-number use), so the
    detector fractions' exact intervals at δ = 1e-3 meet; a closed sphere whose wall BSDF
    has albedo exactly 0.9 (``diffuse``) keeps the geometric law of wall reflections (mean
    9, Chebyshev's bound at δ = 1e-3); a PTFE-like wall (a rough specular lobe blended with
    a Lambertian base) reads, every ray with one fate and no weight above 1, while
    ``roughplastic``'s weights exceed 1 and are counted (the reading then is not
    certified); validated; the theory refuses it.
    """

    rays = 60_000
    plain, _, _ = walk(sphere(), rays)
    bsdf, _, layout = walk(sphere(wall_bsdf={"type": "diffuse", "reflectance": 0.98}), rays)
    assert layout.wall_bsdf == {"type": "diffuse", "reflectance": 0.98}
    a, b = clopper_pearson(np.array([plain[0], bsdf[0]]), rays, 1e-3)
    assert max(a) <= min(b) and not np.array_equal(plain, bsdf)
    closed = Sphere(150, 0.5, (Port("sample", "sample", 180, 0, 12.7, aperture=12.0, mask_reflectance=0.9),),
                    wall_bsdf='{"type": "diffuse", "reflectance": 0.9}')
    counts, sums, _ = walk(closed, 200_000, bsdf={"type": "diffuse", "reflectance": 1.0}, radius=12.7 * 1.001)
    assert counts[1] == 200_000
    assert abs(sums["wall_reflections"] / 200_000 - 9.0) < math.sqrt(90.0 / (200_000 * 1e-3))
    rough = {"type": "blendbsdf", "weight": 0.2, "lambert": {"type": "diffuse", "reflectance": 0.97},
             "lobe": {"type": "roughconductor", "alpha": 0.3, "material": "none", "specular_reflectance": 0.97}}
    counts, sums, _ = walk(sphere(wall_bsdf=rough), 20000)
    assert counts.sum() == 20000 and counts[0] > 0 and sums["weight_violations"] == 0
    plastic, plastic_sums, _ = walk(sphere(wall_bsdf={"type": "roughplastic", "alpha": 0.3,
                                                          "diffuse_reflectance": 0.97}), 4000)
    assert plastic_sums["weight_violations"] > 0  # weights above 1: counted, such a reading is not certified
    with pytest.raises(ValueError, match="wall_bsdf must be a Mitsuba BSDF plugin dict with a 'type'"):
        sphere(wall_bsdf={"reflectance": 0.5})
    with pytest.raises(ValueError, match="give wall_specular = 0 with it"):
        sphere(wall_bsdf=rough, wall_specular=0.2)
    with pytest.raises(ValueError, match="non-Lambertian wall"):
        theory_inputs(sphere(wall_bsdf=rough), SphereOptions(), [551.0])
    from virtspec_mi.instruments.sphere.geometry import sphere_from_parameters

    assert sphere_from_parameters(sphere(wall_bsdf=rough).parameters()) == sphere(wall_bsdf=rough)
