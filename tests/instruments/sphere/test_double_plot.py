"""Tests of virtspec_mi.instruments.sphere.double_plot: a double sphere drawn from its scene."""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi import scenes
from virtspec_mi.instruments.sphere.double_plot import draw_double_sphere


def test_the_shipped_double_sphere_is_drawn_from_its_scene(tmp_path):
    vm.mitsuba()
    import mitsuba as mi

    options = mi.load_file(str(scenes.path("double_sphere_leaf"))).integrator().instrument_options
    figure = draw_double_sphere(options.sphere, options.transmittance_sphere, tmp_path / "double.png")
    assert (tmp_path / "double.png").stat().st_size > 1000
    ax = figure.axes[0]
    labels = ax.get_legend_handles_labels()[1]
    assert {"sample (sample)", "t_entrance (entrance)", "t_detector (detector)", "specimen (edge-on)"} <= set(labels)
    # the two walls touch the specimen's plane from either side: the transmittance wall lies below it
    walls = {line.get_label(): line.get_ydata() for line in ax.get_lines() if "wall" in line.get_label()}
    r_wall, t_wall = (walls[k] for k in sorted(walls))
    assert np.max(t_wall) > np.min(r_wall) and np.min(t_wall) < np.min(r_wall) - 20.0
    with pytest.raises(ValueError, match="plot must end in one of"):
        draw_double_sphere(options.sphere, options.transmittance_sphere, tmp_path / "double.txt")
