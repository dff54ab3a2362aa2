"""The independent microfacet quadrature (virtspec_mi.references.microfacet) against known limits."""

from __future__ import annotations

import numpy as np
import pytest

from virtspec_mi.references.microfacet import average_albedo, directional_albedo, smith_g1, smith_lambda
from virtspec_mi.references.quadrature import fresnel_reflectance_cos


def test_quadrature_converges_when_the_nodes_double():
    for args in ((1.0, 1.0, "ggx", None), (0.3, 0.5, "beckmann", None), (0.7, 0.5, "ggx", 1.5)):
        coarse, fine = directional_albedo(*args, nodes=192), directional_albedo(*args, nodes=384)
        assert abs(coarse.total - fine.total) < 2e-5


def test_smooth_limit_is_fresnel():
    """α → 0: a conductor with F = 1 keeps everything, a dielectric splits by Fresnel."""

    assert directional_albedo(0.8, 1e-3, "ggx", nodes=256).total == pytest.approx(1.0, abs=1e-5)
    for eta in (1.5, 1 / 1.5):
        smooth = directional_albedo(0.8, 1e-3, "ggx", eta=eta, nodes=256)
        fresnel = float(fresnel_reflectance_cos(0.8, eta))
        assert smooth.reflected == pytest.approx(fresnel, abs=1e-4)
        assert smooth.transmitted == pytest.approx(1 - fresnel, abs=1e-4)


def test_masking_functions():
    assert smith_lambda(np.inf, "ggx") == 0 and smith_lambda(np.inf, "beckmann") == 0
    # G1 at normal incidence is 1, and 0 for a facet seen from behind
    assert smith_g1(1.0, 1.0, 0.5, "ggx") == 1.0 and smith_g1(0.5, -0.1, 0.5, "ggx") == 0.0
    # Walter et al.'s rational fit stays within 0.35 % of the exact Beckmann G1
    cos = np.linspace(0.01, 0.999, 200)
    exact = smith_g1(cos, np.ones_like(cos), 0.7, "beckmann", "exact")
    rational = smith_g1(cos, np.ones_like(cos), 0.7, "beckmann", "rational")
    assert np.max(np.abs(rational / exact - 1)) < 0.0036


def test_energy_is_lost_by_rough_single_scattering():
    """GGX at α = 1 keeps about 31 % at normal incidence (separable masking), less than 1 everywhere."""

    e = directional_albedo(1.0, 1.0, "ggx", nodes=256).total
    assert 0.30 < e < 0.32
    assert average_albedo(0.5, "ggx", nodes=64, mu_nodes=8).total < 1.0


def test_bad_input_names_the_parameter():
    with pytest.raises(ValueError, match="mu"):
        directional_albedo(0.0, 0.5)
    with pytest.raises(ValueError, match="alpha"):
        directional_albedo(0.5, -1.0)
    with pytest.raises(ValueError, match="distribution"):
        directional_albedo(0.5, 0.5, "phong")
    with pytest.raises(ValueError, match="eta"):
        directional_albedo(0.5, 0.5, eta=0.0)
