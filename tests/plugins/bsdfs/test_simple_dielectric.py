"""Tests of the simple_dielectric BSDF plugin (plugins/bsdfs/simple_dielectric.py)."""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.references.quadrature import fresnel_reflectance


def sample(mi, bsdf, theta_deg, n=200_000):
    import drjit as dr

    si = dr.zeros(mi.SurfaceInteraction3f, n)
    t = np.radians(theta_deg)
    si.wi = mi.Vector3f(float(np.sin(t)), 0.0, float(np.cos(t)))
    si.wavelengths = mi.Spectrum(551.0)
    u = mi.Float(np.random.default_rng(7).random(n).astype(np.float32))
    bs, weight = bsdf.sample(mi.BSDFContext(), si, u, mi.Point2f(0.5, 0.5), True)
    return np.array(bs.wo), np.array(weight)[0]


def test_loads_with_default_diamond_and_registered_name(mi):
    bsdf = mi.load_dict({"type": "simple_dielectric"})
    assert "eta=2.419" in str(bsdf)
    assert bsdf.wavelength_independent is True


@pytest.mark.parametrize("theta", [0.0, 40.0, 75.0])
def test_reflects_with_fresnel_probability_unit_weight(mi, theta):
    bsdf = mi.load_dict({"type": "simple_dielectric", "eta": 1.5})
    wo, weight = sample(mi, bsdf, theta)
    assert np.all(weight == 1.0)
    reflected = wo[2] > 0
    assert reflected.mean() == pytest.approx(fresnel_reflectance(theta, 1.5), abs=4e-3)
    # reflection is specular: wo = (-wi.x, -wi.y, wi.z)
    t = np.radians(theta)
    np.testing.assert_allclose(wo[0][reflected], -np.sin(t), atol=1e-6)


def test_refraction_obeys_snell(mi):
    bsdf = mi.load_dict({"type": "simple_dielectric", "eta": 2.419})
    wo, _ = sample(mi, bsdf, 60.0)
    refracted = wo[2] < 0
    sin_t = np.hypot(wo[0][refracted], wo[1][refracted])
    np.testing.assert_allclose(sin_t, np.sin(np.radians(60.0)) / 2.419, rtol=1e-5)


@pytest.mark.parametrize("eta", [0.0, -1.0, "glass"])
def test_bad_eta_is_refused(mi, eta):
    with pytest.raises(Exception, match="'eta' must be a number > 0"):
        mi.load_dict({"type": "simple_dielectric", "eta": eta})


# --- issue 12: parameters float32 cannot hold, and booleans, are refused ----------------


@pytest.mark.parametrize("eta", [float("inf"), float("nan"), 1e-40, 1e39, 9e-7, 1.1e6, True])
def test_eta_outside_its_range_or_not_a_number_is_refused(mi, eta):
    # inf read R = 0, T = 1; 1e-40 (a float32 denormal) disagreed between measure and trace_rays.
    with pytest.raises(Exception, match=r"'eta' must be a number > 0 with 1e-06 <= eta <= 1e\+06"):
        mi.load_dict({"type": "simple_dielectric", "eta": eta})


@pytest.mark.parametrize("eta", [1e-6, 1e6])
def test_eta_at_the_ends_of_its_range_gives_fresnel_readings(mi, eta):
    scene = vm.instrument_scene({"type": "simple_dielectric", "eta": eta})
    for theta in (0.0, 30.0, 89.0, 90.0):
        reading = vm.measure(scene, rays=2000, theta_i=theta, beam="collimated")
        assert reading.certified.all() and int(reading.invalid_directions[0]) == 0
        assert abs(float(reading.reflectance[0]) - fresnel_reflectance(theta, eta)) <= float(reading.certified_mu[0])


def _fresnel64(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """Float64 unpolarised Fresnel reflectance, cos_i < 0 seen from inside (index 1/eta)."""

    c = np.abs(cos_i)
    n = np.where(cos_i >= 0, eta, 1 / eta)
    sin2_t = (1 - c * c) / (n * n)
    out = np.ones_like(c)
    ok = sin2_t < 1
    ct, ci, nn = np.sqrt(1 - sin2_t[ok]), c[ok], n[ok]
    out[ok] = 0.5 * (((ci - nn * ct) / (ci + nn * ct)) ** 2 + ((nn * ci - ct) / (nn * ci + ct)) ** 2)
    return out


def test_fresnel_near_one_against_float64_over_eta_and_theta(mi):
    """The bound of the module docstring: < 1e-4 off float64 away from critical angles, |eta-1| down to 1e-12."""

    from virtspec_mi.kernel.walk_optics import NEAR_ONE, fresnel_near_one

    theta = np.linspace(0.0, 90.0, 1_000_001)
    cos = np.cos(np.radians(theta)).astype(np.float32).astype(np.float64)
    for d in (0.099, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-10, 1e-12):
        for eta_minus_one in (d, -d / (1 + d)):
            eta = 1.0 + eta_minus_one
            assert 0 < abs(eta_minus_one) < NEAR_ONE
            for side in (1.0, -1.0):
                fresnel = np.array(fresnel_near_one(mi.Float(side * cos), eta_minus_one)[0], dtype=np.float64)
                n = eta if side > 0 else 1 / eta
                away = np.ones_like(theta, bool) if n >= 1 else np.abs(theta - np.degrees(np.arcsin(n))) > 1e-4
                error = np.abs(fresnel - _fresnel64(side * cos, eta))[away]
                assert error.max() < 1e-4, (eta_minus_one, side, error.max())
    # mi.fresnel's float32 form loses eta - 1 there: the reason for the separate form
    plain = np.array(mi.fresnel(mi.Float(cos), mi.Float(1 - 1e-6))[0], dtype=np.float64)
    assert np.abs(plain - _fresnel64(cos, 1 - 1e-6)).max() > 0.5


@pytest.mark.parametrize("eta", [1 + 1e-6, 1 - 1e-6, 1.05])
def test_a_reading_near_eta_one_is_fresnel_at_grazing_incidence(mi, eta):
    """The wrong number of the adversarial pass: eta within 1e-6 of 1 at grazing incidence, certified."""

    scene = vm.instrument_scene({"type": "simple_dielectric", "eta": eta})
    for theta in (0.0, 85.0, 89.9):
        reading = vm.measure(scene, rays=20_000, theta_i=theta, beam="collimated", seed=4)
        expected = _fresnel64(np.array([np.cos(np.radians(theta))]), eta)[0]
        assert abs(float(reading.reflectance[0]) - expected) <= float(reading.certified_mu[0]), (theta, expected)
