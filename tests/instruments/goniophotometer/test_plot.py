"""
Tests of :mod:`virtspec_mi.instruments.goniophotometer.plot`: the goniophotometer's figures.

The plane of incidence is drawn through the φo bins holding φi + 180° and φi (folded: 180° and
0°), the perpendicular plane through φi ± 90°; the polar plots step over each bin at the
reading's BRDF values with the certified band, the series draws the CDF of θo and its DKW
band, the hemisphere map the BRDF of its bins; the titles state the beam, λ, N, K and the
band's level; the figures are written in the format of their suffix.

References
----------
Nicodemus et al. (1977), NBS Monograph 160.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.instruments.goniophotometer.bins import make_bins
from virtspec_mi.instruments.goniophotometer.plot import plane_bins, plot_hemisphere, plot_polar, plot_series


@pytest.fixture(scope="module")
def reading(mi):
    scene = vm.instrument_scene({"type": "roughconductor", "alpha": 0.3})
    return vm.gonio(scene, theta_i=[20, 50], phi_i=30.0, wavelengths=[550], theta_o_bins=6, phi_o_bins=12,
                    rays=4000, seed=1)


@pytest.mark.parametrize("phi_i, across, expected", [(0.0, False, (6, 0)), (30.0, False, (7, 1)),
                                                     (30.0, True, (4, 10)), (350.0, False, (5, 11))])
def test_the_planes_bins(phi_i, across, expected):
    bins = make_bins(theta_o_bins=3, phi_o_bins=12)  # 30-degree bins
    assert plane_bins(SimpleNamespace(bins=bins, phi_i=phi_i), across) == expected


def test_folded_planes():
    bins = make_bins(theta_o_bins=3, phi_o_bins=6, fold_phi=True)  # 30-degree bins over [0, 180]
    assert plane_bins(SimpleNamespace(bins=bins, phi_i=77.0)) == (5, 0)
    assert plane_bins(SimpleNamespace(bins=bins, phi_i=77.0), across=True) == (3, 3)


def test_polar_plots_step_over_the_bins_with_the_band(reading, tmp_path):
    figure = plot_polar(reading, tmp_path / "polar.svg", name="rough.nc")
    assert (tmp_path / "polar.svg").read_text().lstrip().startswith("<?xml")
    axes = figure.axes[0]
    front, _ = plane_bins(reading)
    first = axes.lines[0]  # theta_i = 20, the mirror side, the reflection hemisphere
    np.testing.assert_allclose(first.get_ydata(), np.repeat(reading.brdf[0, 0, :6, front], 2))  # 6 bins per hemisphere
    assert first.get_label() == "θi = 20°"
    title = figure._suptitle.get_text()
    assert title.startswith("rough.nc: goniophotometer") and "conical beam, λ = 550 nm" in title
    assert "N = 4,000 rays, K = 144 bins (band: all bins at 0.99)" in title


def test_the_series_draws_the_cdf_and_its_dkw_band(reading, tmp_path):
    figure = plot_series(reading, tmp_path / "series.png")
    assert (tmp_path / "series.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    cdf_axes = [axes for axes in figure.axes if axes.get_ylabel() == "F(θo)"][0]
    step = cdf_axes.lines[0]
    np.testing.assert_allclose(step.get_ydata(), reading.cdf_theta_o[0, 0])
    assert any(f"DKW band ± {float(reading.cdf_mu[0, 0]):.3g}" == text.get_text()
               for text in cdf_axes.get_legend().get_texts())


def test_the_hemisphere_map(reading):
    figure = plot_hemisphere(reading, theta_i=50)
    mesh = figure.axes[0].collections[0]
    np.testing.assert_allclose(np.asarray(mesh.get_array()).ravel(), reading.brdf[0, 1, :6].ravel())
    with pytest.raises(ValueError, match="plot must end in one of"):
        plot_polar(reading, "figure.pdf.txt")
