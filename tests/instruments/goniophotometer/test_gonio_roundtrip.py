"""
The goniophotometer round trip (issue 15): measure a soybean leaf (``abm_b``) with the
goniophotometer, turn the reading into a ``tabulated`` BSDF (``GonioResult.to_dataset``
→ ``vm.tabulated_bsdf``), and measure that BSDF again — with the spectrophotometer (R
and T) and with the goniophotometer (every bin) — each against the certificates of the
readings involved.

Why the tolerances hold. The table is fixed once the leaf has been read: at a tabulated
(λ, θi) row the ``tabulated`` BSDF sends a ray into bin k with probability exactly
m_k/N of the leaf's reading (the plugin's Bernoulli contract). So, conditionally on the
table, the readings of the table are certified estimates of the leaf's *reading*:

- R and T of the table: |R_tab − R̂_leaf| < μ_tab (the table reading's certificate);
- its goniophotometer reading: |m'_k/N' − m_k/N| < ``bins_mu`` of the table reading for
  every bin at once, f_k of the leaf inside the table reading's simultaneous
  Clopper–Pearson band, sup |F̂' − F̂| < ``cdf_mu`` (DKW) for the CDF of θo.

Against the leaf itself (its true R, unknown), the leaf reading's own certificate adds:
|R_tab − R_leaf| < μ_leaf + μ_tab; checked through an independent spectrophotometer
reading of the leaf (seed apart), |R_tab − R_ind| < μ_leaf + μ_tab + μ_ind.

Probability of a false failure. Every reading is taken at δ = 10⁻³ with R and T
certified together (``joint``); the fast test makes 6 (λ, θi) readings of each kind and
asserts 6 statements of R/T on the table reading, 6 on the leaf's goniophotometer
reading, 6 on the independent reading, and 3 × 6 on the table's goniophotometer
reading (union bins, Clopper–Pearson band, DKW): 36 statements, each failing with
probability ≤ δ, so a seed picked at random fails the test with probability ≤ 3.6 %
(union bound). The seeds are fixed, so the outcome is reproducible.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.plugins.bsdfs.bsdf_table import read_table

DELTA = 1e-3
READING = dict(beam="collimated", delta=DELTA, joint=True)


def _round_trip(wavelengths, theta_i, bins, mu, tmp_path=None):
    """The leaf's goniophotometer reading, its table, and the table's two readings."""

    leaf = vm.instrument_scene({"type": "abm_b"})
    original = vm.gonio(leaf, theta_i=theta_i, wavelengths=wavelengths, mu=mu, seed=1, **bins, **READING)
    dataset = original.to_dataset()
    if tmp_path is not None:  # through a NetCDF file and the plugin's `filename`
        path = original.write(tmp_path / "leaf_brdf.nc")
        table_bsdf = {"type": "tabulated", "filename": str(path)}
    else:
        table_bsdf = vm.tabulated_bsdf(dataset)
    table = vm.instrument_scene(table_bsdf)
    rays = int(original.rays.max())
    spectro = vm.sweep(table, theta_i=theta_i, wavelengths=wavelengths, rays=rays, seed=2, **READING)
    again = vm.gonio(table, theta_i=theta_i, wavelengths=wavelengths, mu=mu, seed=3, **bins, **READING)
    independent = vm.sweep(leaf, theta_i=theta_i, wavelengths=wavelengths, rays=rays, seed=4, **READING)
    return original, read_table(dataset), spectro, again, independent


def _check(original, table, spectro, again, independent):
    leaf = original.result
    # the table is the leaf's reading: R and T are its sums over the bins (nothing outside)
    assert not np.any(original.outside)
    assert np.allclose(table.reflectance, leaf.reflectance, rtol=0, atol=1e-12)
    assert np.allclose(table.transmittance, leaf.transmittance, rtol=0, atol=1e-12)
    assert np.all(np.isfinite(spectro.certified_mu)) and np.all(np.isfinite(leaf.certified_mu))

    # the spectrophotometer reads the table's R and T: within mu_tab of the leaf's reading ...
    mu_tab = spectro.certified_mu
    assert np.all(np.abs(spectro.reflectance - leaf.reflectance) < mu_tab)
    assert np.all(np.abs(spectro.transmittance - leaf.transmittance) < mu_tab)
    # ... and within mu_leaf + mu_tab of the leaf itself (seen through an independent reading)
    tolerance = leaf.certified_mu + mu_tab + independent.certified_mu
    assert np.all(np.abs(spectro.reflectance - independent.reflectance) < tolerance)
    assert np.all(np.abs(spectro.transmittance - independent.transmittance) < tolerance)

    # the table's own goniophotometer reading reproduces the table within its certificate
    assert np.all(np.isfinite(again.bins_mu)) and np.all(np.isfinite(again.cdf_mu))
    assert np.all(np.abs(again.fraction - original.fraction).max(axis=(-2, -1)) < again.bins_mu)
    assert np.all((again.brdf_lower <= original.brdf) & (original.brdf <= again.brdf_upper))
    assert np.all(np.abs(again.cdf_theta_o - original.cdf_theta_o).max(axis=-1) < again.cdf_mu)
    # the check has power: the leaf's lobes are far from flat, the band is narrower than them
    reflected = ~original.bins.transmitted
    assert np.all(again.brdf_upper[..., reflected, :].min(axis=(-2, -1))
                  < original.brdf[..., reflected, :].max(axis=(-2, -1)))


@pytest.fixture(scope="module")
def fast(tmp_path_factory):
    """Two wavelengths, three θi, 2 × 6 θo × 6 folded φo bins (K = 72), μ = 0.03; the table via a NetCDF file."""

    bins = dict(theta_o_bins=6, phi_o_bins=6, fold_phi=True)
    return _round_trip([551.0, 800.0], [0.0, 30.0, 60.0], bins, mu=0.03, tmp_path=tmp_path_factory.mktemp("table"))


def test_leaf_round_trip_through_the_tabulated_bsdf(fast):
    _check(*fast)


def test_round_trip_fails_for_a_wrong_table(fast):
    """Power: the same readings held against the other wavelength's table (551 and 800 nm swapped) fail."""

    original, _, spectro, again, _ = fast
    swapped = original.result.reflectance[::-1]
    assert np.any(np.abs(spectro.reflectance - swapped) >= spectro.certified_mu)
    wrong = original.brdf[::-1]
    assert not np.all((again.brdf_lower <= wrong) & (wrong <= again.brdf_upper))
    assert np.any(np.abs(again.cdf_theta_o - original.cdf_theta_o[::-1]).max(axis=-1) >= again.cdf_mu)


@pytest.mark.slow
def test_leaf_round_trip_large():
    """Slow: four wavelengths, five θi, unfolded projected bins 2 × 9 × 24 (K = 432), μ = 0.01."""

    bins = dict(theta_o_bins=9, phi_o_bins=24, binning="projected")
    _check(*_round_trip([450.0, 551.0, 650.0, 800.0], [0.0, 20.0, 40.0, 60.0, 80.0], bins, mu=0.01))


def test_the_manual_round_trip_block_prints_what_the_manual_says():
    """The goniophotometer page's round-trip block runs, and prints the numbers written below it."""

    import contextlib
    import io
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[3] / "docs" / "guide" / "goniophotometer.md").read_text()
    section = text[text.index("**Round trip**"):]
    code, printed = re.findall(r"^```(?:python)?\n(.*?)^```", section, re.M | re.S)[:2]
    output = io.StringIO()
    with contextlib.redirect_stdout(output):
        exec(compile(code, "goniophotometer.md round-trip block", "exec"), {"__name__": "__docs__"})
    assert output.getvalue().strip() == printed.strip()
