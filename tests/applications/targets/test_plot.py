"""
Tests of :mod:`virtspec_mi.applications.targets.plot`: the figures of certified derived quantities.

Values are drawn at their estimates with error bars reaching exactly their certified bounds;
a colour as three swatches (the certified box's lower corner, the estimate, its upper corner)
in their sRGB clipped to [0, 1], titled with the ΔE₀₀ radius; a figure path is checked and
written.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.applications.targets.plot import plot_derived

VALUES = "0.1, 0.3, 0.7, 0.4, 0.2, 0.6, 0.8, 0.5"


@pytest.fixture(scope="module")
def scene(mi):
    return vm.instrument_scene({"type": "diffuse", "reflectance": {"type": "regular", "wavelength_min": 300,
                                                                   "wavelength_max": 1000, "values": VALUES}})


def test_values_are_drawn_with_their_certified_intervals(scene, tmp_path):
    result = vm.measure(scene, target=vm.index("NDVI", tolerance=0.05), delta=0.1, seed=2)
    figure = plot_derived(result, tmp_path / "ndvi.png")
    assert (tmp_path / "ndvi.png").stat().st_size > 0
    axes = figure.axes[0]
    line = axes.lines[0]
    np.testing.assert_allclose(line.get_ydata(), [v.value for v in result.values])
    segments = axes.collections[0].get_segments()  # one vertical bar per value: from lower to upper
    for segment, value in zip(segments, result.values):
        np.testing.assert_allclose(sorted(segment[:, 1]), [value.lower, value.upper])
    assert [t.get_text() for t in axes.get_xticklabels()] == [v.name for v in result.values]
    assert "certified together at delta = 0.1" in axes.get_title()


def test_a_colour_is_three_swatches(scene):
    result = vm.measure(scene, target=vm.colour(tolerance_dE00=4.0), delta=0.1, seed=1)
    figure = result.plot()
    axes = figure.axes[0]
    colour = result.colour
    expected = [colour.sRGB_interval[:, 0], colour.sRGB, colour.sRGB_interval[:, 1]]
    assert len(axes.patches) == 3
    for patch, rgb in zip(axes.patches, expected):
        np.testing.assert_allclose(patch.get_facecolor()[:3], np.clip(rgb, 0, 1), atol=1e-6)
    assert f"certified dE00 <= {colour.dE00_radius:.3g}" in axes.get_title()
    assert [t.get_text() for t in axes.texts] == ["lower corner", "estimate", "upper corner"]


def test_a_bad_figure_path_is_refused(scene, tmp_path):
    result = vm.measure(scene, target=vm.band((500, 530), tolerance=0.05), delta=0.1, seed=0, bound="hoeffding")
    with pytest.raises(ValueError, match=r"plot must end in one of .*\.png.* \(got 'figure.txt'\)"):
        plot_derived(result, tmp_path / "figure.txt")
    assert not (tmp_path / "figure.txt").exists()
