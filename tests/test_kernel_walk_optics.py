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
