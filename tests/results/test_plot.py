"""Tests of the figures: Fig. 5 style curves with the certified band, Figs. 5–6, the goniophotometer's plots."""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.results.plot import (COLOUR_MAP, LEGEND, SPARSE, curve_style, plot_comparison, plot_densities,
                                     plot_spectra, plot_sweep, select)


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


MU = "μ': the tolerance its rays guarantee"  # what the band's half-width is
BAND = f"certified ±μ' (δ = 0.01 per reading; {MU})"  # the legend entry of the certified band


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
    assert texts[0] == "λ = 551 nm" and texts[-1] == BAND


def test_markers_on_sparse_grids_only(angular):
    sparse = plot_sweep(angular).axes[0].lines[0]  # 19 angles
    assert len(angular.theta_i) <= SPARSE and sparse.get_marker() not in (None, "None", "")
    dense = plot_sweep(grid_result(np.linspace(0.1, 0.5, 31), np.arange(400, 701, 10), [8])).axes[0].lines[0]
    assert dense.get_marker() in (None, "None", "")


def test_up_to_twelve_curves_are_told_apart_by_colour_and_line_style_each_in_the_legend():
    wavelengths = np.arange(400, 520, 10)  # 12 curves against theta_i: the legend lists them
    figure = plot_sweep(grid_result(np.full((12, 3), 0.3), wavelengths, [0, 30, 60]))
    axes = figure.axes[0]
    styles = {(line.get_color(), line.get_linestyle()) for line in axes.lines}
    assert len(figure.axes) == 1 and len(axes.lines) == 12 and len(styles) == 12  # and no colour bar
    assert [curve_style(k, 3)["color"] for k in (0, 10)] == ["C0", "C0"]
    assert curve_style(0, 3)["linestyle"] != curve_style(10, 3)["linestyle"]
    assert legend_texts(axes) == [f"λ = {w} nm" for w in wavelengths] + [BAND]
    assert {band.get_alpha() for band in axes.collections} == {0.2}


def test_a_sweep_of_31_wavelengths_is_coloured_along_a_colour_bar_of_its_wavelengths():
    from matplotlib import colormaps
    from matplotlib.colors import to_rgba

    wavelengths = np.arange(400, 701, 10)  # 31 curves against theta_i: too many to list
    figure = plot_sweep(grid_result(np.linspace(0.1, 0.5, 31 * 3), wavelengths, [0, 30, 60]))
    axes, bar = figure.axes
    assert bar.get_ylabel() == "wavelength (nm)" and bar.get_ylim() == pytest.approx((400, 700))
    colours = np.array([to_rgba(line.get_color()) for line in axes.lines])
    assert len(colours) == 31 and LEGEND < 31
    np.testing.assert_allclose(colours, colormaps[COLOUR_MAP]((wavelengths - 400) / 300))
    lightness = colours[:, :3] @ [0.299, 0.587, 0.114]
    assert np.all(np.diff(lightness) > 0)  # monotone along the bar: 400 nm darkest, 700 nm lightest
    assert {line.get_linestyle() for line in axes.lines} == {"-"}
    alphas = np.array([band.get_alpha() for band in axes.collections])  # faint: 31 bands stacked are no wall
    assert len(alphas) == 31 and np.all(alphas < 0.05) and 1 - np.prod(1 - alphas) == pytest.approx(0.5)
    assert legend_texts(axes) == [BAND]  # the colour bar names the curves


def test_several_results_of_many_curves_share_the_colour_map_each_in_its_line_style():
    wavelengths = np.arange(400, 701, 10)
    sweeps = [grid_result(np.full((31, 3), value), wavelengths, [0, 30, 60]) for value in (0.2, 0.4)]
    axes, bar = plot_sweep(sweeps, labels=["log N = 3", "log N = 4"]).axes
    assert [line.get_linestyle() for line in axes.lines] == ["-"] * 31 + ["--"] * 31
    assert axes.lines[0].get_color() == axes.lines[31].get_color()  # 400 nm in both
    assert legend_texts(axes) == ["log N = 3", "log N = 4", BAND] and bar.get_ylabel() == "wavelength (nm)"
    spectra = [grid_result([0.2, 0.3, 0.4, 0.5], [400, 500, 600, 700], [angle]) for angle in range(0, 65, 5)]
    axes, bar = plot_sweep(spectra).axes  # 13 spectra, one curve each: coloured by their theta_i
    assert bar.get_ylabel() == "θi (°)" and bar.get_ylim() == pytest.approx((0, 60))
    assert legend_texts(axes) == ["13 results (line styles cycle; colour: θi (°))", BAND]
    alike = [grid_result([0.3, 0.3], [500, 600], [8])] * 13  # 13 curves of one θi: nothing to map
    axes, = plot_sweep(alike).axes
    assert len({(line.get_color(), line.get_linestyle()) for line in axes.lines}) == 13
    assert legend_texts(axes) == ["13 curves, θi = 8° (colours and line styles cycle)", BAND]


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
    from virtspec_mi.applications.comparison import compare

    result = grid_result([0.1, 0.2, 0.3, 0.4, 0.5], [380, 400, 500, 600, 700], [8])
    comparison = compare(result, ([400, 500, 600], [0.21, 0.3, 0.41], [0.01, 0.02, 0.01]))
    figure = plot_comparison(comparison, tmp_path / "compare.svg", name="grey wedge")
    top, bottom = figure.axes
    assert top.get_title().startswith("grey wedge\n") and "θi = 8°" in top.get_title()
    texts = legend_texts(top)
    assert f"certified ±μ' (δ = 0.01 per point; {MU})" in texts
    assert "measured: measured (± its uncertainty)" in texts
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


# --- goniophotometer figures; no figure clips its titles ---------------------------------------


def test_the_polar_radial_labels_lie_on_the_horizon_clear_of_every_curve(gonio):
    from virtspec_mi.instruments.goniophotometer.plot import HORIZON, plot_polar

    for log in (False, True):
        for axes in plot_polar(gonio, log=log).axes:
            spans = [np.degrees([np.min(line.get_xdata()), np.max(line.get_xdata())]) for line in axes.lines]
            assert min(low for low, _ in spans) < -HORIZON and max(high for _, high in spans) > HORIZON  # both lobes
            where = axes.get_rlabel_position()
            assert where == HORIZON and not any(low < where < high for low, high in spans), spans
            angles = min(label.get_fontsize() for label in axes.get_xticklabels())
            assert all(8 <= label.get_fontsize() < angles for label in axes.get_yticklabels())  # smaller than those


def test_the_polar_plots_are_large_and_their_labels_do_not_collide(gonio, tmp_path):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    from virtspec_mi.instruments.goniophotometer.plot import plot_polar

    figure = plot_polar(gonio, tmp_path / "polar.png", name="soybean_abmb")
    assert Image.open(tmp_path / "polar.png").size[0] >= 1100  # was 691 x 345 px
    FigureCanvasAgg(figure).draw()
    for axes in figure.axes:
        labels = [label for label in axes.get_yticklabels() if label.get_text()]
        assert 2 <= len(labels) <= 5
        boxes = sorted((label.get_window_extent() for label in labels), key=lambda box: box.x0)
        assert all(left.x1 < right.x0 for left, right in zip(boxes, boxes[1:])), boxes  # none runs into the next
    assert figure.texts[0].get_text().count("\n") == 1  # two lines, not wrapped


def test_a_band_at_one_wavelength_is_drawn_as_an_error_bar():
    from result_kinds import sphere_grid

    one = sphere_grid().isel(point=0)
    one = one.isel(wavelength=[0])
    axes = plot_spectra(one, quantities=["reading", "hemispherical"], theta_i=8).axes[0]
    bars = [c for c in axes.collections if type(c).__name__ == "LineCollection"]
    assert len(bars) == 2  # one per quantity: an area of no width would show nothing
    for bar, quantity in zip(bars, ("reading", "hemispherical")):
        (x, low), (_, high) = bar.get_segments()[0]
        spectrum = one.spectrum(quantity, 8)
        assert high - low == pytest.approx(2 * spectrum.tolerance[0]) and x == spectrum.wavelengths[0]


def test_measure_plot_draws_reflectance_and_transmittance(mi, tmp_path, monkeypatch):
    import virtspec_mi.results.plot as plots
    from virtspec_mi.cli import main

    drawn, original = [], plots.plot_spectra

    def recording(result, path, **options):
        drawn.append(original(result, path, **options))
        return drawn[-1]

    monkeypatch.setattr(plots, "plot_spectra", recording)
    assert main(["measure", "soybean_abmb", "--wavelengths", "550,650", "--rays", "500", "--quiet", "--plot",
                 str(tmp_path / "leaf.png")]) == 0
    assert (tmp_path / "leaf.png").is_file()
    axes = drawn[0].axes[0]
    assert legend_texts(axes)[:2] == ["reflectance", "transmittance"]
    assert axes.get_ylabel() == "reflectance, transmittance"


# a specimen named by its scene file and defines: a title longer than any figure is wide
LONG_NAME = ("soybean_abmb.xml -D specimen.chlorophyll=45.0 -D specimen.water=0.015 -D specimen.dry_matter=0.004 "
             "-D specimen.thickness=2.04e-4")


def test_no_figure_clips_a_title(angular, gonio):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from result_kinds import sphere_grid

    from virtspec_mi.applications.comparison import compare
    from virtspec_mi.instruments.goniophotometer.plot import plot_hemisphere, plot_polar, plot_series

    wavelengths = np.arange(400, 701, 10)
    sweep = grid_result(np.linspace(0.1, 0.5, 31 * 3), wavelengths, [0, 30, 60])
    spectrum = grid_result(np.linspace(0.1, 0.5, 31), wavelengths, [8])
    figures = {
        "sweep": plot_sweep(sweep, name=LONG_NAME),
        "spectrum": plot_sweep(spectrum, name=LONG_NAME),
        "spectra": plot_spectra(sphere_grid().isel(point=0), quantities=["reading", "hemispherical"], theta_i=8,
                                name=LONG_NAME),
        "densities": plot_densities([angular, angular], [3.3, 4.3], [float("nan"), 0.0]),
        "comparison": plot_comparison(compare(spectrum, ([400, 500, 600], [0.1, 0.2, 0.3])), name=LONG_NAME),
        "polar": plot_polar(gonio, name=LONG_NAME),
        "hemisphere": plot_hemisphere(gonio, transmission=True),
        "series": plot_series(gonio),
    }
    for kind, figure in figures.items():
        FigureCanvasAgg(figure).draw()
        page = figure.bbox
        titles = [text for text in [*(axes.title for axes in figure.axes), *figure.texts] if text.get_text()]
        assert titles, kind
        for title in titles:
            box = title.get_window_extent()
            assert page.x0 <= box.x0 and box.x1 <= page.x1 and page.y0 <= box.y0 and box.y1 <= page.y1, \
                (kind, title.get_text(), box, page)
