"""Tests of virtspec_mi.instruments.sphere.plot: a real sphere drawn from its description."""

from __future__ import annotations

from dataclasses import replace

import pytest

from virtspec_mi.instruments.sphere.geometry import Port, Sphere
from virtspec_mi.instruments.sphere.plot import draw_sphere


def test_a_real_sphere_is_drawn_from_its_description(tmp_path):
    sphere = Sphere(150, 0.98, (Port("sample", "sample", 180, 0, 12.7, aperture=9.0, mask_reflectance=0.05),
                                Port("entrance", "entrance", 15.88, 0, 12.7),
                                Port("detector", "detector", 90, 90, 6.35, depth=3.0, field_of_view=40.0),
                                Port("trap", "open", 100, 180, shape="rectangle", width=10, height=6)),
                    beam_profile="shape=rectangle width=20 height=8 divergence=1", wall_specular=0.1)
    figure = draw_sphere(sphere, tmp_path / "sphere.png")
    assert (tmp_path / "sphere.png").stat().st_size > 1000
    labels = figure.axes[0].get_legend_handles_labels()[1]
    assert {"sample (sample)", "sample mask", "detector (detector)", "trap (open)"} <= set(labels)
    proud = replace(sphere, ports=(replace(sphere.ports[0], aperture=None, mask_reflectance=None, proud=5.0),
                                   *sphere.ports[1:]))
    assert "sample standing proud" in draw_sphere(proud).axes[0].get_legend_handles_labels()[1]
    with pytest.raises(ValueError, match="plot must end in one of"):
        draw_sphere(sphere, tmp_path / "sphere.txt")
