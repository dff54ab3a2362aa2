"""Tests of virtspec_mi.plot: Fig. 5 style curves with the certified band, Figs. 5–6 of densities."""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.plot import plot_densities, plot_sweep


@pytest.fixture(scope="module")
def angular(mi):
    return vm.sweep(vm.instrument_scene({"type": "simple_dielectric"}), theta_i="0:90:5", beam="collimated",
                    rays=2000)


def test_angular_sweep_png_with_the_certified_band(angular, tmp_path):
    figure = plot_sweep(angular, tmp_path / "fig5.png")
    assert (tmp_path / "fig5.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    axes = figure.axes[0]
    assert axes.get_xlabel().startswith("θi")
    line = axes.lines[0]
    np.testing.assert_array_equal(line.get_xdata(), angular.theta_i)
    np.testing.assert_array_equal(line.get_ydata(), angular.reflectance[0])
    # the band is +-mu certified by 2000 rays (hoeffding_mu(2000, 0.01) = 0.0364), not the settings' 0.005
    band = axes.collections[0].get_paths()[0].vertices[:, 1]
    assert band.max() == pytest.approx(angular.reflectance.max() + vm.hoeffding_mu(2000, 0.01))


def test_spectrum_svg_and_bad_suffix(diamond, tmp_path):
    spectrum = vm.sweep(diamond, theta_i=[30], wavelengths="400:700:100", rays=500)
    figure = plot_sweep(spectrum, tmp_path / "spectrum.svg", quantity="transmittance")
    assert figure.axes[0].get_xlabel() == "wavelength (nm)"
    assert (tmp_path / "spectrum.svg").read_text().lstrip().startswith("<?xml")
    with pytest.raises(ValueError, match=r"plot must end in one of \.png, \.svg"):
        plot_sweep(spectrum, tmp_path / "spectrum.pdf")


def test_densities_figure_has_curves_delta_and_seconds(angular, diamond, tmp_path):
    other = vm.sweep(diamond, theta_i="0:90:5", beam="collimated", rays=200)
    figure = plot_densities([other, angular], [2.3, 3.3], [float("nan"), vm.fluctuation(other, angular)],
                            tmp_path / "fig6.png")
    assert len(figure.axes) == 3 and (tmp_path / "fig6.png").stat().st_size > 0
    assert figure.axes[1].lines[0].get_ydata()[0] == pytest.approx(vm.fluctuation(other, angular))
