"""
Tests of :mod:`virtspec_mi.plugins.bsdfs.microfacet_model`: the ``microfacet`` plugin's choices
by name, their statement in words and the check of a combination (no Mitsuba needed).

References
----------
Walter et al. (2007), eqs. (23), (25), (27); Heitz (2014), eq. (99).
"""

from __future__ import annotations

import itertools
import math

import pytest

from virtspec_mi.plugins.bsdfs.microfacet_model import (
    ALPHA_RANGE,
    DISTRIBUTIONS,
    FRESNELS,
    G1S,
    SHADOWINGS,
    WALTER_SCALE,
    check_model,
    model_statement,
)


def allowed(distribution, shadowing, g1, fresnel) -> bool:
    return not (g1 == "walter" and distribution != "beckmann") and not (shadowing == "unreal" and distribution != "ggx")


def test_every_allowed_combination_passes_and_is_stated():
    combinations = list(itertools.product(DISTRIBUTIONS, SHADOWINGS, G1S, FRESNELS))
    passed = 0
    for combination in combinations:
        if allowed(*combination):
            check_model(*combination)
            text = model_statement(*combination)
            assert text.startswith(f"{combination[0]} microfacet reflector, {SHADOWINGS[combination[1]]}")
            assert FRESNELS[combination[3]] in text
            passed += 1
        else:
            with pytest.raises(ValueError, match="microfacet: "):
                check_model(*combination)
    assert passed == 3 * 1 * 4 + 2 * 2 * 4  # ggx: 3 shadowings x exact g1; beckmann: 2 shadowings x 2 g1s; x 4 fresnels


def test_a_ggx_statement_names_the_exact_g1():
    assert "exact Smith G1" in model_statement("ggx", "separable", "walter", "one")
    assert "rational fit" in model_statement("beckmann", "separable", "walter", "one")


@pytest.mark.parametrize("arguments, message", [
    (("phong", "separable", "exact", "one"), r"'distribution' must be one of ggx, beckmann \(got 'phong'\)"),
    (("ggx", "smith", "exact", "one"),
     r"'shadowing' must be one of separable, height_correlated, unreal \(got 'smith'\)"),
    (("ggx", "separable", "approx", "one"), r"'g1' must be one of exact, walter \(got 'approx'\)"),
    (("ggx", "separable", "exact", "schlick"), r"'fresnel' must be one of one, fc, one_minus_fc, split"),
    (("ggx", "separable", "walter", "one"), r"g1='walter' is the Beckmann fit"),
    (("beckmann", "unreal", "exact", "one"), r"shadowing='unreal' is Unreal Engine 4's GGX approximation"),
])
def test_refusals_name_the_parameter(arguments, message):
    with pytest.raises(ValueError, match=message):
        check_model(*arguments)


def walter_g1(a: float) -> float:
    """Walter et al. (2007), eq. (27)."""

    return 1.0 if a >= 1.6 else (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)


def exact_beckmann_g1(a: float) -> float:
    """Walter et al. (2007), eq. (25): 2/(1 + erf(a) + exp(−a²)/(a√π))."""

    return 2.0 / (1.0 + math.erf(a) + math.exp(-a * a) / (a * math.sqrt(math.pi)))


def test_walter_scale_bounds_the_fit_over_the_exact_g1():
    ratios = [walter_g1(a) / exact_beckmann_g1(a) for a in (k * 1e-3 for k in range(1, 6001))]
    assert max(ratios) <= WALTER_SCALE
    assert max(ratios) > WALTER_SCALE - 1e-3  # and is tight
    assert ALPHA_RANGE == (0.0, 10.0)
