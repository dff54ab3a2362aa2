"""The shared optical pieces of random walks (virtspec_mi.kernel.walk_optics) against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from virtspec_mi.references.quadrature import fresnel_reflectance_cos
from virtspec_mi.kernel.walk_optics import cross_interface, free_path, sample_hg

N = 200_000
K = 5.0  # 5 sigma per comparison: false-failure probability 5.7e-7 each


@pytest.fixture(scope="module")
def uniforms():
    return np.random.default_rng(7).random((3, N)).astype(np.float32)


def test_free_path_is_exponential_and_infinite_without_extinction(mi, uniforms):
    import drjit as dr

    paths = np.array(free_path(mi.Float(uniforms[0]), mi.Float(2.0)))
    assert abs(paths.mean() - 0.5) < K * 0.5 / math.sqrt(N)  # mean 1/mu_t, sd 1/mu_t
    clear = free_path(mi.Float([0.0, 0.3]), mi.Float(0.0))
    dr.eval(clear)
    assert np.all(np.isinf(np.array(clear)))


@pytest.mark.parametrize("g", [0.0, 0.75, -0.5, 0.99, 1.0])
def test_hg_mean_cosine_is_g(mi, uniforms, g):
    direction = mi.Vector3f(0.0, 0.6, -0.8)
    out = np.array(sample_hg(direction, mi.Float(g), mi.Float(uniforms[0]), mi.Float(uniforms[1])))
    cos = out.T @ np.array([0.0, 0.6, -0.8])
    assert np.allclose(np.linalg.norm(out, axis=0), 1.0, atol=1e-5)
    # HG: E[cos] = g, Var[cos] = (1 + 2g^2)/3 - g^2 (E[cos^2] = (1 + 2g^2)/3).
    sd = math.sqrt(max((1 + 2 * g * g) / 3 - g * g, 0.0))
    assert abs(cos.mean() - g) <= K * sd / math.sqrt(N) + 1e-6


@pytest.mark.parametrize("eta, cos_i", [(1.5, 0.9), (1.5, 0.2), (1 / 1.5, 0.9), (1 / 1.5, 0.6), (1.0, 0.01)])
def test_interface_reflects_with_the_fresnel_probability(mi, uniforms, eta, cos_i):
    sin_i = math.sqrt(1 - cos_i**2)
    direction = mi.Vector3f(sin_i, 0.0, -cos_i)  # going down onto z = const, medium below has eta
    new, reflected = cross_interface(direction, mi.Float(eta), mi.Float(uniforms[2]))
    new, reflected = np.array(new), np.array(reflected)
    f = float(fresnel_reflectance_cos(cos_i, eta))
    assert abs(reflected.mean() - f) <= K * math.sqrt(max(f * (1 - f), 1 / N) / N)
    # Reflected rays mirror z; refracted ones obey Snell's law n1 sin1 = n2 sin2.
    assert np.allclose(new[2, reflected], cos_i, atol=1e-6)
    if (~reflected).any():
        assert np.allclose(new[0, ~reflected] * eta, sin_i, atol=1e-5)
        assert np.all(new[2, ~reflected] < 0)


# --- an interface near eta = 1 (issue 22): the cancellation-free Fresnel form, bit-identical elsewhere ---------


def _even_uniforms(n: int) -> np.ndarray:
    """u_j = (j + 1/2)/n: the share of them below F is F within 1/(2n), with no randomness."""

    return ((np.arange(n) + 0.5) / n).astype(np.float32)


@pytest.mark.parametrize("eta_minus_one", [2.0**-20, -(2.0**-20), 1e-3, -0.05])
def test_an_interface_near_one_reflects_with_the_float64_fresnel_probability(mi, eta_minus_one):
    eta = 1.0 + eta_minus_one
    u = _even_uniforms(100_000)
    # grazing angles, where float32 mi.fresnel is off most; away from a critical angle (infinite slope there)
    for cos_i in np.cos(np.radians([60.0, 89.0, 89.9, 89.919, 89.95])).astype(np.float32):
        sin_i = math.sqrt(1.0 - float(cos_i) ** 2)
        if eta < 1 and abs(math.degrees(math.acos(float(cos_i))) - math.degrees(math.asin(eta))) < 1e-3:
            continue
        direction = mi.Vector3f(sin_i, 0.0, -float(cos_i))
        _, reflected = cross_interface(direction, mi.Float(eta), mi.Float(u), mi.Float(eta_minus_one))
        expected = float(fresnel_reflectance_cos(float(cos_i), eta))
        assert abs(np.array(reflected).mean() - expected) < 1e-4 + 1 / len(u), (eta_minus_one, cos_i)


def test_mi_fresnel_is_what_fails_near_one(mi):
    """Without eta - 1 the float32 form is off by 0.05 at 89.919 deg for eta = 1 - 2**-20 (why the form exists)."""

    cos_i = np.float32(math.cos(math.radians(89.919)))
    direction = mi.Vector3f(math.sqrt(1.0 - float(cos_i) ** 2), 0.0, -float(cos_i))
    u = mi.Float(_even_uniforms(100_000))
    _, plain = cross_interface(direction, mi.Float(1 - 2.0**-20), u)
    assert abs(np.array(plain).mean() - float(fresnel_reflectance_cos(float(cos_i), 1 - 2.0**-20))) > 0.04


@pytest.mark.parametrize("eta", [1.5, 1 / 1.5, 1.0, 1.2, 0.9])
def test_lanes_away_from_one_are_bit_identical_with_eta_minus_one_given(mi, uniforms, eta):
    cos = np.linspace(-1.0, 1.0, 4001).astype(np.float32)
    sin = np.sqrt(1.0 - cos.astype(np.float64) ** 2).astype(np.float32)
    direction = mi.Vector3f(mi.Float(sin), 0.0, mi.Float(cos))
    u = mi.Float(uniforms[2][:len(cos)])
    plain = cross_interface(direction, mi.Float(eta), u)
    given = cross_interface(direction, mi.Float(eta), u, mi.Float(eta - 1.0))
    for a, b in zip(plain, given):
        assert np.array_equal(np.array(a), np.array(b))


@pytest.mark.parametrize("spectral", [False, True])
def test_a_turbid_slab_near_one_reads_the_fresnel_reflectance_at_grazing_incidence(mi, spectral):
    """The slab's top face at eta = 1 - 2**-20, 89.919 deg: float32 Fresnel read 0.37, float64 gives 0.4198."""

    import warnings

    import virtspec_mi as vm
    from virtspec_mi.budgets.bounds import hoeffding_mu

    eta = 1 - 2.0**-20
    index = eta if not spectral else {"type": "regular", "wavelength_min": 400, "wavelength_max": 700,
                                      "values": f"{eta!r}, {eta!r}"}
    scene = vm.instrument_scene({"type": "turbid_slab", "eta": index, "mu_a": 1e3, "thickness": "inf"})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        reading = vm.measure(scene, beam="collimated", theta_i=89.919, rays=20_000, wavelengths=551)
    cos_i = float(np.float32(math.cos(math.radians(89.919))))  # the beam's float32 direction
    expected = float(fresnel_reflectance_cos(cos_i, eta))
    assert abs(reading.reflectance.item() - expected) < hoeffding_mu(20_000, 1e-6)  # 0.019; float32 was 0.05 off
