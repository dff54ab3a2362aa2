"""
A drawing of a sphere, made from its description
================================================

:func:`draw_sphere` draws a :class:`~virtspec_mi.instruments.sphere.geometry.Sphere` as
it is walked: the wall's great circle in the drawing plane (the plane through the centre
spanned by the sample port's axis and the entrance port's, or the detector's), and every
part projected orthographically onto that plane — each port's rim (an ellipse when the
port lies out of the plane; an elliptical or rectangular opening by its outline), a port
wall's cylinder out to its outer end, a holder mask's annulus, a specimen standing proud on
its post, the baffle, a detector's field of view (the cone's edges), and a traced beam's
edge rays. Nothing is drawn that the walk does not take: the figure is the scene's.

References
----------
Goebel (1967) (the sphere); the walk of a real sphere: :mod:`virtspec_mi.instruments.sphere.real`.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from virtspec_mi.instruments.sphere.geometry import Sphere
from virtspec_mi.instruments.sphere.real import port_frame

__all__ = ["draw_sphere"]


def _plane(sphere: Sphere) -> tuple[np.ndarray, np.ndarray]:
    """(e_u, e_v): the drawing plane, e_v along the sample port's axis (down in the figure for a bottom port)."""

    first = sphere.port("sample") or sphere.port("entrance") or (sphere.ports[0] if sphere.ports else None)
    v = np.array([0.0, 0.0, 1.0]) if first is None else -first.axis
    for role in ("entrance", "detector", "specular", "reference", "open"):
        other = sphere.port(role)
        if other is not None and other is not first:
            u = other.axis - (other.axis @ v) * v
            if np.linalg.norm(u) > 1e-6:
                return u / np.linalg.norm(u), v
    u = np.array([1.0, 0.0, 0.0]) - v[0] * v
    return u / np.linalg.norm(u), v


def _ring(centre: np.ndarray, axis: np.ndarray, radius: float, points: int = 96) -> np.ndarray:
    e1, e2 = port_frame(axis)
    phi = np.linspace(0.0, 2.0 * math.pi, points)
    return centre + radius * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2)


def draw_sphere(sphere: Sphere, path: str | os.PathLike | None = None, *, theta_i: float = 8.0,
                title: str | None = None) -> Any:
    """
    A matplotlib ``Figure`` of ``sphere`` (see the module docstring); written to ``path``
    (PNG, SVG or PDF by its suffix) when given. ``theta_i`` (degrees) places a traced
    beam's edge rays (in the drawing plane).
    """

    from matplotlib.figure import Figure

    u, v = _plane(sphere)
    R = sphere.radius

    def flat(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        points = np.atleast_2d(points)
        return points @ u, points @ v

    figure = Figure(figsize=(5.2, 5.2))
    ax = figure.add_subplot(1, 1, 1)
    phi = np.linspace(0.0, 2.0 * math.pi, 361)
    ax.plot(R * np.cos(phi), R * np.sin(phi), color="0.6", lw=1.0, label=f"wall (rho_w, mirror share "
                                                                            f"{sphere.wall_specular:g})")
    colours = {"sample": "C3", "entrance": "C0", "reference": "C2", "detector": "C1", "specular": "C4",
               "open": "C7"}
    for port in sphere.ports:
        offset = R * port.cos_half_angle(R)
        colour = colours[port.role]
        if port.shape == "circle":
            rim = _ring(port.axis * offset, port.axis, port.radius)
        else:
            e1, e2 = port_frame(port.axis)
            a, b = port.width / 2.0, port.height / 2.0
            t = np.linspace(0.0, 2.0 * math.pi, 97)
            if port.shape == "ellipse":
                x, y = a * np.cos(t), b * np.sin(t)
            else:
                x, y = np.clip(a * np.sqrt(2) * np.cos(t), -a, a), np.clip(b * np.sqrt(2) * np.sin(t), -b, b)
            lift = np.sqrt(np.maximum(R * R - x * x - y * y, 0.0))
            rim = x[:, None] * e1 + y[:, None] * e2 + lift[:, None] * port.axis
        ax.plot(*flat(rim), color=colour, lw=1.6, label=f"{port.name} ({port.role})")
        if port.depth:
            outer = _ring(port.axis * (offset + port.depth), port.axis, port.radius)
            ax.plot(*flat(outer), color=colour, lw=1.0, ls="--")
            for k in (0, 24, 48, 72):
                ax.plot(*flat(np.stack([rim[k], outer[k]])), color=colour, lw=1.0)
        if port.aperture is not None:
            plane = port.axis * (offset + port.depth)
            ax.plot(*flat(_ring(plane, port.axis, port.aperture)), color="k", lw=1.0, label=f"{port.name} mask")
        if port.proud:
            face = _ring(port.axis * (offset - port.proud), port.axis, port.radius)
            ax.plot(*flat(face), color=colour, lw=2.0, label=f"{port.name} standing proud")
            for k in (0, 24, 48, 72):
                ax.plot(*flat(np.stack([face[k], rim[k]])), color=colour, lw=1.0)
        if port.field_of_view is not None:
            gamma = math.radians(port.field_of_view)
            inward = -port.axis
            side = u - (u @ inward) * inward
            side = side / np.linalg.norm(side) if np.linalg.norm(side) > 1e-9 else v
            for sign in (-1.0, 1.0):
                ray = math.cos(gamma) * inward + sign * math.sin(gamma) * side
                ax.plot(*flat(np.stack([port.axis * offset, port.axis * offset + 0.5 * R * ray])), color=colour,
                        lw=0.8, ls=":")
    if sphere.baffle is not None:
        b = sphere.baffle
        ax.plot(*flat(_ring(np.array(b.centre), np.array(b.normal), b.radius)), color="0.3", lw=1.2, label="baffle")
    sample = sphere.port("sample")
    if sphere.beam_profile is not None and sample is not None:
        centre = sample.axis * (R * sample.cos_half_angle(R) + sample.depth - sample.proud)
        theta = math.radians(theta_i)
        towards = -math.cos(theta) * v - math.sin(theta) * u  # travel: onto the sample, tilted by theta_i
        a, _ = sphere.beam_profile.half_sizes()
        across = np.cross(np.cross(u, v), towards)
        for sign in (-1.0, 0.0, 1.0):
            end = centre + sign * a * across
            start = end - 1.9 * R * math.cos(theta) * towards
            ax.plot(*flat(np.stack([start, end])), color="C3", lw=0.8 if sign else 1.2, alpha=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("mm")
    ax.set_ylabel("mm (sample port axis)")
    ax.set_title(title or f"{sphere.diameter:g} mm sphere: drawing plane through the sample port's axis")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=7, frameon=False)
    if path is not None:
        from virtspec_mi.results.plot import check_figure_path

        figure.savefig(check_figure_path(path), dpi=150, bbox_inches="tight")
    return figure
