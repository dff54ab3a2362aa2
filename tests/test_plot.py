"""Tests of virtspec_mi.results.plot: Fig. 5 style curves with the certified band, Figs. 5–6 of densities."""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.results.plot import SPARSE, curve_style, plot_comparison, plot_densities, plot_sweep, select


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


# --- figures as users meet them: titles, legends, markers, distinct curves, comparisons ------


def grid_result(values, wavelengths, thetas, rays=10**4, scene="sha256:0123456789abcdef0123"):
    """A result of given reflectance over (wavelength, theta_i), exact counts, no tracing."""

    from dataclasses import replace

    from virtspec_mi.kernel.counts import Counts

    values = np.asarray(values, dtype=np.float64).reshape(len(wavelengths), len(thetas))
    counts = replace(Counts.zeros(values.shape), rays=np.full(values.shape, rays, dtype=np.int64),
                     reflected=np.round(values * rays).astype(np.int64))
    return vm.Result(("wavelength", "theta_i"), {"wavelength": np.asarray(wavelengths, float),
                                                 "theta_i": np.asarray(thetas, float)},
                     counts, None, vm.Settings(wavelengths=wavelengths, beam="collimated"),
                     vm.InstrumentGeometry(8, 12.5, 100), 0.0, scene=scene)


def legend_texts(axes) -> list[str]:
    return [text.get_text() for text in axes.get_legend().get_texts()]


def test_the_title_names_the_scene_beam_angles_and_rays(angular):
    title = plot_sweep(angular, name="diamond.nc").axes[0].get_title()
    assert title.startswith("diamond.nc — scene dict, specimen SimpleDielectric\n")
    assert "reflectance, collimated beam, θi = 0–90°" in title and "N = 2,000 rays per reading" in title
    assert "sha256" not in title  # the specimen by name, never by its fingerprint
    spectrum = plot_sweep(grid_result([0.5, 0.4], [500, 600], [8]), quantity="absorptance").axes[0].get_title()
    assert spectrum.startswith("virtspec-mi result\n") and "absorptance, collimated beam, θi = 8°" in spectrum


def test_the_title_names_a_scene_file_its_defines_and_the_parameter_point(mi, scenes_dir):
    table = vm.sweep(str(scenes_dir / "diamond_conical.xml"), defines={"seed": 3}, wavelengths=[551], rays=500,
                     parameters={"specimen.eta": [2.0, 2.4]}, progress=False)
    title = plot_sweep(table.sel({"specimen.eta": 2.4})).axes[0].get_title()
    assert title.startswith("diamond_conical -D seed=3, specimen.eta = 2.4\n")


def test_the_certified_band_has_a_legend_entry(angular):
    texts = legend_texts(plot_sweep(angular).axes[0])
    assert texts[0] == "λ = 551 nm" and texts[-1] == "certified ±μ' (δ = 0.01 per reading)"


def test_markers_on_sparse_grids_only(angular):
    sparse = plot_sweep(angular).axes[0].lines[0]  # 19 angles
    assert len(angular.theta_i) <= SPARSE and sparse.get_marker() not in (None, "None", "")
    dense = plot_sweep(grid_result(np.linspace(0.1, 0.5, 31), np.arange(400, 701, 10), [8])).axes[0].lines[0]
    assert dense.get_marker() in (None, "None", "")


def test_every_curve_is_told_apart_by_colour_and_line_style():
    wavelengths = np.arange(400, 800, 10)  # 40 curves against theta_i
    figure = plot_sweep(grid_result(np.full((40, 3), 0.3), wavelengths, [0, 30, 60]))
    axes = figure.axes[0]
    styles = {(line.get_color(), line.get_linestyle()) for line in axes.lines}
    assert len(axes.lines) == 40 and len(styles) == 40
    assert [curve_style(k, 3)["color"] for k in (0, 10)] == ["C0", "C0"]
    assert curve_style(0, 3)["linestyle"] != curve_style(10, 3)["linestyle"]
    texts = legend_texts(axes)  # too many curves to list: how many, and the band
    assert texts == ["40 curves, λ = 400…790 nm (colours and line styles cycle)",
                     "certified ±μ' (δ = 0.01 per reading)"]


def test_readings_are_selected_by_wavelength_and_angle(angular):
    figure = plot_sweep(angular, theta_i=[0, 45, 90], wavelengths=[551])
    np.testing.assert_array_equal(figure.axes[0].lines[0].get_xdata(), [0, 45, 90])
    chosen = select(angular, theta_i=[90, 0])
    np.testing.assert_array_equal(chosen.theta_i, [90, 0])
    np.testing.assert_array_equal(chosen.reflected[0], angular.reflected[0, [-1, 0]])
    with pytest.raises(ValueError, match=r"theta_i must be among the result's theta_i \(0, 5, 10.*got 7\)"):
        select(angular, theta_i=[7])
    with pytest.raises(ValueError, match=r"wavelengths must be among the result's wavelengths \(551; got 600\)"):
        plot_sweep(angular, wavelengths=[600])


def test_the_comparison_figure_overlays_and_shows_the_residuals(tmp_path):
    from virtspec_mi.comparison import compare

    result = grid_result([0.1, 0.2, 0.3, 0.4, 0.5], [380, 400, 500, 600, 700], [8])
    comparison = compare(result, ([400, 500, 600], [0.21, 0.3, 0.41], [0.01, 0.02, 0.01]))
    figure = plot_comparison(comparison, tmp_path / "compare.svg", name="grey wedge")
    top, bottom = figure.axes
    assert top.get_title().startswith("grey wedge\n") and "θi = 8°" in top.get_title()
    texts = legend_texts(top)
    assert "certified ±μ' (δ = 0.01 per point)" in texts and "measured: measured (± its uncertainty)" in texts
    assert "not compared (outside the measured range)" in texts
    residuals = bottom.lines[-1]
    np.testing.assert_array_equal(residuals.get_xdata(), [400, 500, 600])
    np.testing.assert_allclose(residuals.get_ydata(), [-0.01, 0.0, -0.01], atol=1e-12)
    assert "simulated − measured: 3 of 3 within" in legend_texts(bottom)
    assert "combined tolerance ±(μ' + u)" in legend_texts(bottom)
    assert (tmp_path / "compare.svg").stat().st_size > 0


def test_cli_plots_a_sweep_file_and_a_measure_json(angular, scenes_dir, tmp_path):
    import json
    import subprocess
    import sys

    def virtspec(*args):
        return subprocess.run([sys.executable, "-m", "virtspec_mi.cli", *args], capture_output=True, text=True,
                              cwd=tmp_path)

    angular.write(tmp_path / "fig5.nc")
    printed = virtspec("plot", "fig5.nc", "--theta-i", "0:90:10", "--quantity", "transmittance", "--out", "t.svg")
    assert printed.returncode == 0, printed.stderr
    assert printed.stdout.strip() == "plot: t.svg" and (tmp_path / "t.svg").stat().st_size > 0
    reading = virtspec("measure", str(scenes_dir / "diamond_collimated.xml"), "--wavelengths", "400:700:100",
                       "--rays", "1000", "--json")
    assert reading.returncode == 0, reading.stderr
    (tmp_path / "reading.json").write_text(reading.stdout)
    assert json.loads(reading.stdout)["dims"] == ["wavelength"]
    printed = virtspec("plot", "reading.json", "--wavelengths", "400", "500")
    assert printed.returncode == 0, printed.stderr
    assert (tmp_path / "reading.png").read_bytes()[:4] == b"\x89PNG"
    printed = virtspec("plot", "fig5.nc", "--wavelengths", "600")
    assert printed.returncode == 1 and "wavelengths must be among the result's wavelengths" in printed.stderr
