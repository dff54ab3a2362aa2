"""Tests of virtspec_mi.instruments.sphere.geometry: the sphere description, its validation and exact cap fractions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from virtspec_mi.instruments.sphere.geometry import Baffle, Port, Sphere, parse_wall_reflectance, sphere_from_parameters


def small_sphere(**changes):
    ports = (Port("sample", "sample", 180, 0, 10), Port("entrance", "entrance", 15.54, 0, 10),
             Port("detector", "detector", 90, 90, 4))
    return Sphere(**{"diameter": 60, "wall_reflectance": 0.98, "ports": ports, **changes})


def test_cap_fraction_is_h_over_2R_and_differs_from_the_disk_convention():
    sphere = small_sphere()
    R, r = 30.0, 10.0
    h = R - math.sqrt(R * R - r * r)
    assert sphere.cap_fraction("sample") == pytest.approx(h / (2 * R), rel=1e-12)
    assert sphere.disk_fraction("sample") == pytest.approx(r * r / (4 * R * R), rel=1e-12)
    # the example: about 3 % apart for a 20 mm port on a 60 mm sphere
    ratio = sphere.disk_fraction("sample") / sphere.cap_fraction("sample")
    assert ratio == pytest.approx((1 + math.sqrt(1 - (r / R) ** 2)) / 2, rel=1e-12)
    assert 0.02 < 1 - ratio < 0.04
    assert set(sphere.cap_fractions) == {"sample", "entrance", "detector"}


def test_port_at_uses_the_exact_cap():
    sphere = small_sphere()
    port = sphere.ports[2]
    alpha = port.half_angle(sphere.radius)
    inside = sphere.radius * np.array([math.sin(alpha * 0.999) * 0, math.sin(math.pi / 2 - alpha * 0.999),
                                       math.cos(math.pi / 2 - alpha * 0.999)])
    # a point at polar 90 - 0.999 alpha (azimuth 90): inside the detector cap; at 90 - 1.001 alpha outside
    def at(polar):
        t = math.radians(polar)
        return sphere.radius * np.array([0.0, math.sin(t), math.cos(t)])
    assert sphere.port_at(at(90 - math.degrees(alpha) * 0.999)) is port
    assert sphere.port_at(at(90 - math.degrees(alpha) * 1.001)) is None
    assert sphere.port_at(inside) is port


@pytest.mark.parametrize("changes, message", [
    ({"wall_reflectance": 1.2}, "wall_reflectance must satisfy 0 <= rho_w <= 1"),
    ({"wall_reflectance": -0.1}, "wall_reflectance must satisfy 0 <= rho_w <= 1"),
    ({"wall_reflectance": ([400, 700], [0.9, 1.5])}, "wall_reflectance must satisfy"),
    ({"diameter": 0}, "diameter must be > 0"),
    ({"ports": (Port("a", "sample", 180, 0, 31),)}, "port 'a': radius must be < the sphere radius"),
    ({"ports": (Port("a", "sample", 180, 0, 10), Port("b", "detector", 165, 0, 5))}, "ports 'a' and 'b' overlap"),
    ({"ports": (Port("a", "sample", 180, 0, 10), Port("b", "sample", 0, 0, 5))}, "at most one port"),
    ({"baffle": Baffle((0, 0, 25), (0, 0, 1), 20)}, "baffle must lie inside the sphere"),
])
def test_bad_spheres_name_the_parameter(changes, message):
    with pytest.raises(ValueError, match=message):
        small_sphere(**changes)


def test_bad_ports_name_the_parameter():
    with pytest.raises(ValueError, match="port 'x': role must be one of"):
        Port("x", "window", 0, 0, 1)
    with pytest.raises(ValueError, match="port 'x': polar must satisfy"):
        Port("x", "open", 190, 0, 1)
    with pytest.raises(ValueError, match="port 'x': radius must be > 0"):
        Port("x", "open", 10, 0, 0)


def test_spectral_wall_reflectance_interpolates():
    sphere = small_sphere(wall_reflectance="400:0.97, 700:0.99")
    assert sphere.wall_reflectance_at([400, 550, 700, 900]) == pytest.approx([0.97, 0.98, 0.99, 0.99])
    assert parse_wall_reflectance("0.5") == 0.5
    with pytest.raises(ValueError, match="wall_reflectance"):
        parse_wall_reflectance("400:0.9:1")


def test_sphere_from_parameters_reads_the_xml_strings():
    sphere = sphere_from_parameters({"diameter": 60.0, "wall_reflectance": "0.95",
                                     "port_s": "role=sample polar=180 radius=10",
                                     "port_d": "role=detector polar=90 azimuth=90 radius=4",
                                     "baffle": "centre=0,10,-10 normal=0,1,1 radius=5"})
    assert [p.name for p in sphere.ports] == ["s", "d"] and sphere.wall_reflectance == 0.95
    assert sphere.baffle.normal == pytest.approx((0, 2 ** -0.5, 2 ** -0.5))
    with pytest.raises(ValueError, match="port 'd': missing radius"):
        sphere_from_parameters({"diameter": 60.0, "port_d": "role=detector polar=90"})


def test_parameters_round_trip():
    sphere = small_sphere(wall_reflectance=([400.0, 700.0], [0.97, 0.99]),
                          baffle=Baffle((0.0, 10.0, -10.0), (0.0, 1.0, 1.0), 5.0))
    assert sphere_from_parameters(sphere.parameters()) == sphere
