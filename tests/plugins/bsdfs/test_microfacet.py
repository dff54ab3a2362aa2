"""
The ``microfacet`` plugin (virtspec_mi.plugins.bsdfs.microfacet): its sample weight is its
own eval()/pdf() divided by c, never above 1, and what it counts is ∫ f cos (the tables'
tests hold the counts to an independent quadrature: tests/exchange/test_engine_models.py).
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from microfacet_quadrature import albedo

MODELS = [("ggx", "separable", "exact", "one"), ("ggx", "height_correlated", "exact", "fc"),
          ("ggx", "unreal", "exact", "one_minus_fc"), ("beckmann", "separable", "exact", "one"),
          ("beckmann", "height_correlated", "walter", "one"), ("beckmann", "separable", "walter", "fc")]


def _draw(mi, bsdf, mu: float, n: int, seed: int):
    import drjit as dr

    rng = np.random.default_rng(seed)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(float(np.sqrt(1 - mu * mu)), 0.0, float(mu))
    ctx = mi.BSDFContext()
    bs, weight = bsdf.sample(ctx, si, mi.Float(rng.random(n)), mi.Point2f(rng.random(n), rng.random(n)))
    value, pdf = bsdf.eval_pdf(ctx, si, bs.wo)
    return (np.array(mi.Spectrum(weight)[0]), np.array(mi.Spectrum(value)[0]), np.array(pdf),
            np.array(bs.pdf), np.array(bs.wo.z))


@pytest.mark.parametrize("model", MODELS, ids=lambda m: "-".join(m))
def test_weights_are_eval_over_pdf_and_never_above_one(mi, model):
    distribution, shadowing, g1, fresnel = model
    for alpha in (0.01, 0.3, 1.0) + (() if shadowing == "unreal" else (2.5,)):
        bsdf = mi.load_dict({"type": "microfacet", "distribution": distribution, "shadowing": shadowing, "g1": g1,
                             "fresnel": fresnel, "alpha": alpha})
        for mu in (1.0, 0.7, 0.2, 0.02):
            weight, value, pdf, sampled_pdf, cos_o = _draw(mi, bsdf, mu, 20000, seed=int(alpha * 100 + mu * 10))
            assert np.all(weight >= 0.0) and np.all(weight <= 1.0 + 1e-6), (alpha, mu, weight.max())
            live = pdf > 0
            assert np.all(cos_o[weight > 0] > 0)  # a kept ray leaves upward
            assert np.allclose(weight[live] * bsdf.count_scale, value[live] / pdf[live], rtol=2e-5, atol=1e-5)
            assert np.allclose(sampled_pdf[live], pdf[live], rtol=1e-5)


@pytest.mark.parametrize("model", MODELS[:2] + MODELS[4:5], ids=lambda m: "-".join(m))
def test_the_mean_weight_times_c_is_the_albedo(mi, model):
    """400,000 samples: the mean within 5 standard errors of the test's quadrature."""

    bsdf = mi.load_dict({"type": "microfacet", "distribution": model[0], "shadowing": model[1], "g1": model[2],
                         "fresnel": model[3], "alpha": 0.6})
    weight = _draw(mi, bsdf, 0.3, 400000, seed=7)[0] * bsdf.count_scale
    assert abs(weight.mean() - albedo(0.3, 0.6, *model)) < 5 * weight.std() / np.sqrt(weight.size)


def test_split_keeps_each_half_with_its_probability_and_weight_one(mi):
    """fresnel='split': up with probability w Fc, below with w (1 - Fc); eval/pdf = c on every kept ray."""

    bsdf = mi.load_dict({"type": "microfacet", "shadowing": "height_correlated", "fresnel": "split", "alpha": 0.6})
    weight, value, pdf, sampled_pdf, cos_o = _draw(mi, bsdf, 0.3, 400000, seed=11)
    assert set(np.unique(weight)) <= {0.0, 1.0}
    kept, up = weight > 0, cos_o > 0
    assert np.allclose(value[kept] / pdf[kept], 1.0, rtol=1e-4) and np.allclose(sampled_pdf[kept], pdf[kept])
    n = weight.size
    for share, fresnel in ((np.mean(kept & up), "fc"), (np.mean(kept & ~up), "one_minus_fc")):
        expected = albedo(0.3, 0.6, "ggx", "height_correlated", "exact", fresnel)
        assert abs(share - expected) < 5 * np.sqrt(expected * (1 - expected) / n), (fresnel, share, expected)


def test_alpha_through_traverse_and_errors(mi):
    bsdf = mi.load_dict({"type": "microfacet", "alpha": 0.2})
    params = mi.traverse(bsdf)
    params["alpha"] = 0.9
    params.update()
    assert bsdf.alpha == pytest.approx(0.9)
    assert "alpha=0.9" in str(bsdf)
    for props, message in (({"alpha": 0.0}, "'alpha' must be a number with 0 < alpha <= 10"),
                           ({"distribution": "phong"}, "'distribution' must be one of ggx, beckmann"),
                           ({"g1": "walter"}, "g1='walter' is the Beckmann fit"),
                           ({"shadowing": "unreal", "distribution": "beckmann"}, "shadowing='unreal'"),
                           ({"shadowing": "unreal", "alpha": 1.5}, "0 < alpha <= 1")):
        with pytest.raises(Exception, match=message):
            mi.load_dict({"type": "microfacet", **props})


def test_the_instrument_measures_it(mi):
    """The plugin on the instrument's specimen: a reading counts reflected rays, nothing transmitted."""

    scene = vm.instrument_scene({"type": "microfacet", "shadowing": "height_correlated", "alpha": 1.0})
    result = vm.measure(scene, theta_i=0.0, wavelengths=[550], rays=200000, seed=1, progress=False)
    expected = albedo(1.0, 1.0, "ggx", "height_correlated")  # 1 - ln 2
    assert float(np.asarray(result.transmittance).max()) == 0.0
    assert abs(float(np.asarray(result.reflectance).ravel()[0]) - expected) < 0.005
