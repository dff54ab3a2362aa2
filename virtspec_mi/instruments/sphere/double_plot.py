"""
A drawing of a double sphere, made from its two descriptions
============================================================

:func:`draw_double_sphere` draws the two spheres of a double-sphere instrument
(:mod:`virtspec_mi.instruments.sphere.double`) as the walk places them: the transmittance
sphere moved onto the reflectance sphere's sample port by the same rigid motion
(:func:`virtspec_mi.instruments.sphere.double.double_layout`), both walls' great circles in
the drawing plane of the reflectance sphere (:mod:`virtspec_mi.instruments.sphere.plot`:
through its sample port's axis and its entrance port's), every port's rim projected onto
it, the specimen edge-on in the shared port plane and the beam's axis from the entrance
port onto the specimen at ``theta_i``. Nothing is drawn that the walk does not take.

References
----------
Pickering et al. (1993), Appl. Opt. 32(4), 399–410, Fig. 1 (a double integrating sphere).
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from virtspec_mi.instruments.sphere.double import _rigid
from virtspec_mi.instruments.sphere.geometry import Sphere
from virtspec_mi.instruments.sphere.plot import _plane, _ring
from virtspec_mi.instruments.sphere.walk import holder_frame

__all__ = ["draw_double_sphere"]

_COLOURS = {"sample": "C3", "entrance": "C0", "reference": "C2", "detector": "C1", "specular": "C4", "open": "C7"}


def draw_double_sphere(reflectance: Sphere, transmittance: Sphere, path: str | os.PathLike | None = None, *,
                       theta_i: float = 8.0, specimen_radius: float | None = None, title: str | None = None) -> Any:
    """
    A matplotlib ``Figure`` of the two spheres (see the module docstring); written to
    ``path`` (PNG, SVG or PDF by its suffix) when given. ``specimen_radius`` (mm; default
    the reflectance sphere's sample port) is the specimen disk drawn edge-on.
    """

    from matplotlib.figure import Figure

    m, shift = _rigid(reflectance, transmittance)
    u, v = _plane(reflectance)

    def flat(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        points = np.atleast_2d(points)
        return points @ u, points @ v

    figure = Figure(figsize=(5.4, 6.4))
    ax = figure.add_subplot(1, 1, 1)
    phi = np.linspace(0.0, 2.0 * math.pi, 361)
    for label, sphere, rotate, move, style in (("reflectance sphere", reflectance, np.eye(3), np.zeros(3), "-"),
                                               ("transmittance sphere", transmittance, m, shift, "--")):
        R = sphere.radius
        circle = move + R * (np.cos(phi)[:, None] * u + np.sin(phi)[:, None] * v)  # its great circle in the plane
        ax.plot(*flat(circle), color="0.55", lw=1.0, ls=style, label=f"{label} wall ({sphere.diameter:g} mm)")
        for port in sphere.ports:
            axis = rotate @ port.axis
            rim = _ring(move + axis * R * port.cos_half_angle(R), axis, port.radius)
            prefix = "" if move is not shift else "t_"
            ax.plot(*flat(rim), color=_COLOURS[port.role], lw=1.6, ls=style,
                    label=f"{prefix}{port.name} ({port.role})")
    sample = reflectance.port("sample")
    centre = reflectance.port_plane_centre(sample)
    frame = holder_frame(sample.axis, False)
    radius = sample.radius if specimen_radius is None else float(specimen_radius)
    ax.plot(*flat(_ring(centre, sample.axis, radius)), color="C2", lw=3.0, label="specimen (edge-on)")
    theta = math.radians(theta_i)
    towards = frame @ np.array([math.sin(theta), 0.0, math.cos(theta)])
    hit = reflectance.wall_point(centre, towards)
    ax.plot(*flat(np.stack([hit, centre])), color="C3", lw=1.0, label=f"beam axis (theta_i {theta_i:g} deg)")
    ax.set_aspect("equal")
    ax.set_xlabel("mm")
    ax.set_ylabel("mm (sample port axis)")
    ax.set_title(title or "double integrating sphere: the specimen between the two spheres")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=7, frameon=False)
    if path is not None:
        from virtspec_mi.results.plot import check_figure_path

        figure.savefig(check_figure_path(path), dpi=150, bbox_inches="tight")
    return figure
