"""Tests of virtspec_mi.instruments.sphere.ports: real ports validated, their fractions exact, their text round-trips."""

from __future__ import annotations

import math

import pytest

from virtspec_mi.instruments.sphere.geometry import Port, Sphere, parse_port, sphere_from_parameters
from virtspec_mi.instruments.sphere.ports import disk_view_factor, port_frame, shaped_fraction


def test_port_extras_are_validated_naming_the_parameter_and_its_range():
    with pytest.raises(ValueError, match="depth must satisfy depth >= 0"):
        Port("d", "detector", 90, 90, 6.35, depth=-1)
    with pytest.raises(ValueError, match="edge_reflectance must satisfy 0 <= edge_reflectance <= 1"):
        Port("d", "detector", 90, 90, 6.35, edge_reflectance=1.2)
    with pytest.raises(ValueError, match="shape must be one of circle, ellipse, rectangle"):
        Port("d", "detector", 90, 90, 6.35, shape="square")
    with pytest.raises(ValueError, match="shape ellipse needs width > 0"):
        Port("d", "detector", 90, 90, shape="ellipse", height=3)
    with pytest.raises(ValueError, match="height must be > 0"):
        Port("d", "detector", 90, 90, shape="rectangle", width=3, height=0)
    with pytest.raises(ValueError, match="depth must be 0 for shape ellipse"):
        Port("d", "detector", 90, 90, shape="ellipse", width=3, height=4, depth=1)
    with pytest.raises(ValueError, match="width and height are for shape ellipse or rectangle"):
        Port("d", "detector", 90, 90, 6.35, width=3)
    with pytest.raises(ValueError, match="radius .* is required for a circular port"):
        Port("d", "detector", 90, 90)
    with pytest.raises(ValueError, match="role sample needs shape circle"):
        Sphere(150, 0.98, (Port("s", "sample", 180, 0, shape="ellipse", width=8, height=9),))
    assert Port("d", "detector", 90, 90, shape="rectangle", width=6, height=8).radius == 5.0


def test_shaped_fractions_are_exact():
    """The quadrature against closed forms: an ellipse of equal axes is the cap h/2R; a rectangle's share tends to
    its area over 4πR² for a large sphere; an ellipse lies between its inscribed and circumscribed caps."""

    sphere = Sphere(150, 0.98, (Port("c", "detector", 90, 90, 9.0),))
    circle = Port("e", "detector", 90, 90, shape="ellipse", width=18, height=18)
    assert shaped_fraction(circle, 75.0) == pytest.approx(sphere.cap_fraction("c"), rel=1e-12)
    rectangle = Port("r", "detector", 90, 90, shape="rectangle", width=2, height=1)
    assert shaped_fraction(rectangle, 1e4) == pytest.approx(2.0 / (4 * math.pi * 1e8), rel=1e-6)
    ellipse = Port("e", "detector", 90, 90, shape="ellipse", width=8, height=18)
    inner = Sphere(150, 0.98, (Port("c", "detector", 90, 90, 4.0),)).cap_fraction("c")
    assert inner < Sphere(150, 0.98, (ellipse,)).cap_fraction(ellipse) < sphere.cap_fraction("c")
    e1, e2 = port_frame(ellipse.axis)
    assert abs(e1 @ ellipse.axis) < 1e-12 and abs(e2 @ ellipse.axis) < 1e-12 and abs(e1 @ e2) < 1e-12


def test_real_ports_round_trip_through_their_text():
    sphere = Sphere(150, 0.98, (Port("s", "sample", 180, 0, 12.7, depth=3.0, edge_reflectance=0.5),
                                Port("d", "detector", 90, 90, shape="ellipse", width=8, height=9),
                                Port("e", "entrance", 0, 0, shape="rectangle", width=7, height=4)))
    assert sphere_from_parameters(sphere.parameters()) == sphere
    plain = Sphere(150, 0.98, (Port("s", "sample", 180, 0, 12.7),))
    assert plain.parameters()["port_s"] == "role=sample polar=180.0 azimuth=0.0 radius=12.7"  # unchanged text
    assert parse_port("d", "role=detector polar=90 shape=rectangle width=4 height=3").radius == 2.5


def test_disk_view_factor_closed_forms():
    """Coaxial equal disks: F = ½[X − √(X² − 4)], X = 2 + d²/r²; F → 1 as d → 0, and F ~ r²/d² far apart."""

    assert disk_view_factor(0.0, 5.0) == 1.0
    assert disk_view_factor(1e-6, 5.0) == pytest.approx(1.0, abs=1e-6)
    assert disk_view_factor(1e4, 1.0) == pytest.approx(1e-8, rel=1e-4)
    x = 2 + (3.0 / 2.0) ** 2
    assert disk_view_factor(3.0, 2.0) == pytest.approx((x - math.sqrt(x * x - 4)) / 2, rel=1e-14)
