"""
Tests of virtspec_mi.instruments.sphere.walk: reproducibility, chunk independence, conservation,
the hemispherical fates of the same rays, exact limits and the ideal sphere against
virtspec_mi.instruments.sphere.theory.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.budgets.bounds import hoeffding_mu
from virtspec_mi.runtime.scene import find_bench
from virtspec_mi.settings import Settings
from virtspec_mi.instruments.sphere import theory as st
from virtspec_mi.instruments.sphere.geometry import Baffle, Port, Sphere
from virtspec_mi.instruments.sphere import SphereOptions
from virtspec_mi.instruments.sphere.model import theory_inputs

R = 75.0


def walk_counts(sphere, bsdf, radius, rho_w, rays, *, actions, settings=None, max_bounces=100_000, safe_point=None):
    """One reading at 551 nm through :class:`SphereLayout` on the kernel's one tally path: its ``cross``
    histogram (hemisphere, sphere fate) and wall reflections."""

    from dataclasses import replace

    from virtspec_mi.engine.plan import kernel_options
    from virtspec_mi.instruments.sphere.walk import SPECIMEN, Holder, holder_frame
    from virtspec_mi.kernel.tracer import ReadingPlan, tally_readings

    vm.mitsuba()
    instrument = find_bench(vm.instrument_scene(bsdf, specimen_radius=radius))
    settings = settings or Settings(theta_i=0, beam="collimated")
    holder = Holder(0, SPECIMEN, radius, holder_frame(sphere.ports[0].axis, False))
    layout = replace(sphere, wall_reflectance=rho_w).layout([holder], actions, max_bounces, [551.0])
    tally = tally_readings(instrument, [ReadingPlan(551.0, settings.theta_i, settings.phi_i, rays)], hook=layout,
                           safe_point=safe_point, **kernel_options(settings))
    return {"cross": tally.bins[0].reshape(4, layout.codes), **{k: int(v[0]) for k, v in tally.sums.items()}}


def ideal(detector_fraction_target=0.01, sample_radius=12.7):
    alpha = math.acos(1 - 2 * detector_fraction_target)
    return Sphere(150, 0.98, (Port("sample", "sample", 180, 0, sample_radius),
                              Port("entrance", "entrance", 0, 0, 6.0),
                              Port("detector", "detector", 90, 90, R * math.sin(alpha))))


def test_counts_are_reproducible_and_independent_of_chunking():
    sphere = ideal()
    base = Settings(theta_i=0, beam="collimated")
    a = walk_counts(sphere, {"type": "diffuse", "reflectance": 0.6}, 12.7, 0.95, 5000, actions=[6, 7, 0],
                    settings=base)
    b = walk_counts(sphere, {"type": "diffuse", "reflectance": 0.6}, 12.7, 0.95, 5000, actions=[6, 7, 0],
                    settings=base.updated(chunk_size=1024))
    c = walk_counts(sphere, {"type": "diffuse", "reflectance": 0.6}, 12.7, 0.95, 5000, actions=[6, 7, 0],
                    settings=base)
    assert np.array_equal(a["cross"], b["cross"]) and a["wall_reflections"] == b["wall_reflections"]
    assert np.array_equal(a["cross"], c["cross"])
    assert a["cross"].sum() == 5000  # conservation: every ray has exactly one fate
    other = walk_counts(sphere, {"type": "diffuse", "reflectance": 0.6}, 12.7, 0.95, 5000, actions=[6, 7, 0],
                        settings=base.updated(seed=1))
    assert not np.array_equal(a["cross"], other["cross"])


def test_zero_port_limit_is_exact():
    """Only the sample port, filled by a white Lambertian: every ray ends in the wall; with ρw = 1, capped."""

    sphere = Sphere(150, 0.9, (Port("sample", "sample", 180, 0, 12.7),))
    white = {"type": "diffuse", "reflectance": 1.0}
    counts = walk_counts(sphere, white, 12.7 * 1.001, 0.9, 4000, actions=[6])
    assert counts["cross"][:, 1].sum() == 4000  # absorbed by the wall, all of them
    capped = walk_counts(sphere, white, 12.7 * 1.001, 1.0, 2000, actions=[6], max_bounces=40)
    assert capped["cross"][:, 4].sum() == 2000
    assert capped["wall_reflections"] > 2000 * 30


def test_baffle_shades_the_detector_from_the_sample():
    """Black wall and baffle: only the sample's first flight can reach the detector; the baffle stops it."""

    ports = (Port("sample", "sample", 180, 0, 12.7), Port("entrance", "entrance", 0, 0, 6.0),
             Port("detector", "detector", 90, 90, 6.35))
    open_sphere = Sphere(150, 0.0, ports)
    lambertian = {"type": "diffuse", "reflectance": 1.0}
    seen = walk_counts(open_sphere, lambertian, 12.7, 0.0, 20000, actions=[6, 7, 0])
    assert seen["cross"][:, 0].sum() > 0
    baffled = Sphere(150, 0.0, ports, Baffle((0, 37.45, -36.96), (0, 0.7118, 0.7025), 14))
    shaded = walk_counts(baffled, lambertian, 12.7, 0.0, 20000, actions=[6, 7, 0])
    assert shaded["cross"][:, 0].sum() == 0
    assert shaded["cross"][:, 1].sum() > seen["cross"][:, 1].sum()  # the baffle absorbs what it stops


def three_port_sphere(fraction, rho_w):
    """A 150 mm sphere with sample (bottom), entrance (top) and detector (equator) ports of cap fraction f each."""

    radius = st.port_radius_for_fraction(fraction, R)
    return Sphere(150, rho_w, (Port("sample", "sample", 180, 0, radius), Port("entrance", "entrance", 0, 0, radius),
                               Port("detector", "detector", 90, 90, radius)))


def theory(sphere, rho_s, rho_w, port_surface="flat", convention="cap"):
    """
    ρs · T_sample of :mod:`virtspec_mi.instruments.sphere.theory` with the fractions of
    :func:`virtspec_mi.instruments.sphere.model.theory_inputs` (exact caps h/2R, or the same ports'
    r²/4R² with ``convention="projected"``).
    """

    kw = theory_inputs(sphere, SphereOptions(), [551.0])
    fractions = {k: kw[k] for k in ("sample_fraction", "detector_fraction", "open_fraction")}
    if convention == "projected":  # r²/4R² = a (1 − a) for each port (the ports here fill their caps)
        fractions = {k: v * (1 - v) for k, v in fractions.items()}
    return rho_s * st.detected_fraction(rho_w, rho_s, port_surface=port_surface, **fractions)


# the grid: rho_w in {0.90, 0.95, 0.98, 0.99} x port fraction in {1 %, 5 %, 10 %} (exact caps h/2R,
# three ports of that fraction each), a 0.5 grey Lambertian sample; the first two cases run by default
GRID = [(rho_w, f) for rho_w in (0.98, 0.90, 0.95, 0.99) for f in (0.10, 0.01, 0.05)]


@pytest.mark.parametrize("rho_w, f", [*GRID[:2], *(pytest.param(*case, marks=pytest.mark.slow) for case in GRID[2:])])
def test_ideal_sphere_detector_fraction_matches_the_theory(rho_w, f):
    """
    The walk against :func:`virtspec_mi.instruments.sphere.theory.detected_fraction` in its flat model
    (the simulation's geometry: the specimen a flat disk filling its port), exact cap
    fractions. The beam is conical, so it lights the disk uniformly and a Lambertian
    sample's first emission is uniform over the disk, as the theory assumes (a collimated
    beam lights the disk's centre only: its first landing is not uniform,
    ``spot_landing_density``, a few per cent of the 1/G share of the signal detected
    before any wall bounce). The cap model (Goebel; iadpython's ``Sphere`` with cap
    fractions, which ``test_sphere_theory`` shows equal) and the IAD program's r²/4R²
    convention are other models: at 10 % ports both are farther from the walk than the
    flat model (README, the convention table).
    """

    sphere = three_port_sphere(f, rho_w)
    rays, delta = 105_967, 1e-3
    counts = walk_counts(sphere, {"type": "diffuse", "reflectance": 0.5}, sphere.ports[0].radius, rho_w, rays,
                         actions=[6, 7, 0], settings=Settings(theta_i=0, beam="conical"))
    detected = counts["cross"][:, 0].sum() / rays
    flat = theory(sphere, 0.5, rho_w)
    assert abs(detected - flat) < hoeffding_mu(rays, delta)
    if f == 0.10:
        import iadpython as iad

        d = 2 * sphere.ports[0].radius
        cap = iad.Sphere(150.0, d, d_entrance=d, d_detector=d, r_detector=0.0, r_wall=rho_w)
        cap_model = cap.a_detector * cap.multiplier(0.5, 0.5)
        assert cap_model == pytest.approx(theory(sphere, 0.5, rho_w, "cap"), rel=1e-9)
        projected = theory(sphere, 0.5, rho_w, "cap", "projected")
        assert abs(detected - cap_model) > abs(detected - flat) and abs(detected - projected) > abs(detected - flat)


def test_a_long_walk_reaches_a_safe_point_between_launches_and_keeps_its_counts(monkeypatch):
    """
    A white sphere with small ports and a huge max_bounces: the walk is launched LAUNCH_STEPS steps at a time, an
    interrupt is honoured between two launches (it once ran on for minutes after Ctrl-C), and the counts do not
    depend on the launches.
    """

    import virtspec_mi.base.interrupts as interrupts
    import virtspec_mi.instruments.sphere.walk as walk

    sphere = Sphere(150, 0.9, (Port("sample", "sample", 180, 0, 12.7), Port("detector", "detector", 90, 90, 2.0)))
    white = {"type": "diffuse", "reflectance": 1.0}
    whole = walk_counts(sphere, white, 12.7 * 1.001, 0.999, 300, actions=[6, 0], max_bounces=10**7)
    monkeypatch.setattr(walk, "LAUNCH_STEPS", 7)
    safe_points = []
    launched = walk_counts(sphere, white, 12.7 * 1.001, 0.999, 300, actions=[6, 0], max_bounces=10**7,
                           safe_point=lambda: safe_points.append(1))
    assert np.array_equal(whole["cross"], launched["cross"])
    assert whole["wall_reflections"] == launched["wall_reflections"]
    assert len(safe_points) > 10  # walks of hundreds of steps: many launches, a safe point after each

    def interrupted():
        raise interrupts.Interrupted()

    with pytest.raises(interrupts.Interrupted):
        walk_counts(sphere, white, 12.7 * 1.001, 0.999, 300, actions=[6, 0], max_bounces=10**7,
                    safe_point=interrupted)
