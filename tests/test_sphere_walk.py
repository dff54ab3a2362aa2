"""
Tests of virtspec_mi.kernel.sphere_walk: reproducibility, chunk independence, conservation,
the hemispherical fates of the same rays, exact limits and the ideal-sphere closed form.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.bounds import hoeffding_mu
from virtspec_mi.scene import find_instrument
from virtspec_mi.settings import Settings
from virtspec_mi.sphere import Baffle, Port, Sphere

R = 75.0


def walk_counts(sphere, bsdf, radius, rho_w, rays, *, actions, settings=None, max_bounces=100_000):
    from virtspec_mi.kernel.sphere_walk import Holder, SphereWalk, holder_frame, tally_sphere

    mi = vm.mitsuba()
    instrument = find_instrument(vm.instrument_scene(bsdf, specimen_radius=radius))
    settings = settings or Settings(theta_i=0, beam="collimated")
    holder = Holder(0, instrument.bsdf, radius, holder_frame(sphere.ports[0].axis, False))
    walk = SphereWalk(sphere, [holder], actions, max_bounces)
    del mi
    return tally_sphere(walk, instrument, [551.0], [rho_w], rays, settings)[0]


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


def _view_fraction(sphere, port, depth, nodes=200):
    """Cosine-weighted share of a cap seen from the point (0, 0, −depth) facing +z (Gauss–Legendre)."""

    alpha = port.half_angle(sphere.radius)
    x, w = np.polynomial.legendre.leggauss(nodes)
    beta = (x + 1) * alpha / 2
    wb = w * alpha / 2
    psi = (x + 1) * math.pi
    wp = w * math.pi
    B, P = np.meshgrid(beta, psi, indexing="ij")
    c = port.axis
    e1 = np.cross(c, [0.0, 0.0, 1.0]) if abs(c[2]) < 0.9 else np.cross(c, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(c, e1)
    wall = sphere.radius * (np.cos(B)[..., None] * c + np.sin(B)[..., None] * (
        np.cos(P)[..., None] * e1 + np.sin(P)[..., None] * e2))
    v = wall - np.array([0.0, 0.0, -depth])
    d = np.linalg.norm(v, axis=-1)
    cos0 = v[..., 2] / d
    cosw = (v * wall).sum(-1) / (d * sphere.radius)
    integrand = np.clip(cos0, 0, None) * cosw / (math.pi * d * d) * sphere.radius ** 2 * np.sin(B)
    return float(np.einsum("ij,i,j->", integrand, wb, wp))


def closed_form(sphere, rho_s, rho_w):
    """
    P(detected) for a collimated ray onto the centre of a Lambertian sample (reflectance ρs)
    filling the sample port: the first flight exactly (cosine-weighted view fractions G_k of the
    caps from the sample centre), then the exact uniform exchange from the wall with cap
    fractions f_k = h_k/2R:

        q = P(det | leaves the wall) = f_d (1 − f_s + f_s ρs) / ((1 − f_s)(1 − f_w ρw) − f_s ρs f_w ρw)
        P = ρs (G_d + G_w ρw q),  G_w = 1 − Σ_k G_k,  f_w = 1 − Σ_k f_k,

    where a ray re-emitted by the sample after a re-hit is taken to land uniformly on the rest
    of the sphere (exact for uniform radiance on the port disk; the sample port here is 0.7 %).
    """

    sample, *others = sphere.ports
    depth = sphere.radius * sample.cos_half_angle(sphere.radius)
    g = {p.role: _view_fraction(sphere, p, depth) for p in others}
    f = {p.role: sphere.cap_fraction(p) for p in sphere.ports}
    fs, fd = f["sample"], f["detector"]
    fw = 1 - sum(f.values())
    q = fd * (1 - fs + fs * rho_s) / ((1 - fs) * (1 - fw * rho_w) - fs * rho_s * fw * rho_w)
    gw = 1 - sum(g.values())
    return rho_s * (g["detector"] + gw * rho_w * q)


# the grid: rho_w in {0.90, 0.95, 0.98, 0.99} x detector port fraction in {1 %, 5 %, 10 %}
# (exact caps, h/2R), each with its own sample reflectance; the first case runs by default
GRID = [(rho_w, f_d, rho_s) for (rho_w, f_d), rho_s in zip(
    [(w, f) for w in (0.98, 0.90, 0.95, 0.99) for f in (0.01, 0.05, 0.10)],
    (0.5, 0.8, 0.3, 0.9, 0.2, 0.6, 0.95, 0.4, 0.7, 0.1, 0.5, 0.99))]


@pytest.mark.parametrize("rho_w, f_d, rho_s", [GRID[0], *(pytest.param(*case, marks=pytest.mark.slow)
                                                          for case in GRID[1:])])
def test_lambertian_sample_in_an_ideal_sphere_matches_the_closed_form(rho_w, f_d, rho_s):
    sphere = ideal(f_d)
    rays, delta = 105_967, 1e-3
    counts = walk_counts(sphere, {"type": "diffuse", "reflectance": rho_s}, 12.7, rho_w, rays, actions=[6, 7, 0])
    detected = counts["cross"][:, 0].sum() / rays
    assert abs(detected - closed_form(sphere, rho_s, rho_w)) < hoeffding_mu(rays, delta)
