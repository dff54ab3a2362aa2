"""
Plots of goniophotometer readings (PNG and SVG)
===============================================

- :func:`plot_polar`: f (BRDF above the specimen, BTDF below) in the plane of
  incidence and in the plane across it, as polar plots — the reflection lobe in the
  upper half, the transmission lobe in the lower half — one curve per θi (the angular
  distribution over θi as a series), each with its simultaneous Clopper–Pearson band
  (the certified band: all K bins at once at 1 − δ).
- :func:`plot_hemisphere`: a 2-D map of f over one hemisphere (θo radial, φo around).

The plane of incidence is drawn through the φo bins that hold φi + 180° (the mirror
side, drawn at +θo) and φi (the back side, drawn at −θo); the perpendicular plane
through φi ± 90°. Folded readings (relative azimuth) use 180° and 0°, resp. 90°.
The figures are built without ``pyplot``; the file suffix picks the format.

References
----------
Nicodemus et al. (1977), NBS Monograph 160.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.plot import check_figure_path, curve_style

__all__ = ["plot_polar", "plot_hemisphere", "plane_bins"]


def plane_bins(reading: Any, across: bool = False) -> tuple[int, int]:
    """φo bin indices (front, back) of the plane of incidence (or, ``across``, the perpendicular plane)."""

    b = reading.bins
    if b.fold_phi:
        front, back = (90.0, 90.0) if across else (180.0, 0.0)
    else:
        phi_i = reading.phi_i
        front, back = ((phi_i + 90.0, phi_i - 90.0) if across else (phi_i + 180.0, phi_i))
        front, back = front % 360.0, back % 360.0
    top = b.phi_edges[-1]

    def index(phi: float) -> int:
        k = int(np.searchsorted(b.phi_edges, phi, side="right") - 1)
        return min(max(k, 0), len(b.phi_edges) - 2) if phi <= top else len(b.phi_edges) - 2

    return index(front), index(back)


def plot_polar(reading: Any, path: str | os.PathLike | None = None, wavelength: float | None = None,
               log: bool = False) -> Any:
    """
    Polar plots of f in the plane of incidence and across it, one curve per θi with its
    certified band, at ``wavelength`` (default: the first). Returns the ``Figure``.
    """

    from matplotlib.figure import Figure

    path = check_figure_path(path)
    w = 0 if wavelength is None else int(np.argmin(np.abs(reading.wavelengths - wavelength)))
    figure = Figure(figsize=(9.6, 4.8), layout="constrained")
    theta = reading.bins.theta_centres
    lower_t, upper_t = reading.bins.theta_edges[:-1], reading.bins.theta_edges[1:]
    for panel, (across, title) in enumerate(((False, "plane of incidence"), (True, "perpendicular plane"))):
        axes = figure.add_subplot(1, 2, panel + 1, projection="polar")
        axes.set_theta_zero_location("N")
        axes.set_theta_direction(-1)
        front, back = plane_bins(reading, across)
        for i, angle in enumerate(reading.theta_i):
            style = curve_style(i, 2 * len(theta))
            for sign, column in ((1.0, front), (-1.0, back)):
                f = reading.brdf[w, i, :, column]
                band = reading.brdf_lower[w, i, :, column], reading.brdf_upper[w, i, :, column]
                # steps over each bin (piecewise constant), reflection and transmission apart
                for hemisphere in (theta < 90.0, theta > 90.0):
                    if not np.any(hemisphere):
                        continue
                    edges = np.radians(sign * np.column_stack([lower_t[hemisphere], upper_t[hemisphere]]).ravel())
                    values = np.repeat(f[hemisphere], 2)
                    axes.plot(edges, values, color=style["color"], linestyle=style["linestyle"],
                              label=f"θi = {angle:g}°" if sign > 0 and hemisphere[0] else None)
                    axes.fill_between(edges, np.repeat(band[0][hemisphere], 2), np.repeat(band[1][hemisphere], 2),
                                      color=style["color"], alpha=0.2, linewidth=0,
                                      label="certified band" if (i == 0 and sign > 0 and hemisphere[0]) else None)
            if not (across or reading.result.settings.beam == "diffuse"):
                axes.annotate("", xy=(np.radians(-angle), axes.get_rmax()), xytext=(0, 0),
                              arrowprops={"arrowstyle": "<-", "color": style["color"], "alpha": 0.5})
        if log:
            axes.set_rscale("symlog", linthresh=1e-2)
        axes.set_title(f"f (1/sr), {title}", fontsize=10)
        axes.set_thetagrids(range(0, 360, 30), labels=[f"{a if a <= 180 else a - 360}°" for a in range(0, 360, 30)],
                            fontsize=7)
        if panel == 0:
            axes.legend(loc="lower left", fontsize=7, bbox_to_anchor=(-0.15, -0.12))
    s = reading.result.settings
    figure.suptitle(f"goniophotometer, {s.beam} beam, λ = {reading.wavelengths[w]:g} nm, "
                    f"N = {int(reading.rays.max()):,} rays, K = {reading.size} bins "
                    f"(band: all bins at {1 - reading.delta:g})", fontsize=10)
    if path is not None:
        figure.savefig(path, dpi=72)
    return figure


def plot_hemisphere(reading: Any, path: str | os.PathLike | None = None, transmission: bool = False,
                    wavelength: float | None = None, theta_i: float | None = None) -> Any:
    """A 2-D map of f over the reflection (or ``transmission``) hemisphere: θo radial, φo around."""

    from matplotlib.figure import Figure

    path = check_figure_path(path)
    w = 0 if wavelength is None else int(np.argmin(np.abs(reading.wavelengths - wavelength)))
    i = 0 if theta_i is None else int(np.argmin(np.abs(reading.theta_i - theta_i)))
    b = reading.bins
    rows = b.transmitted if transmission else ~b.transmitted
    if not np.any(rows):
        raise ValueError(f"the reading has no {'transmission' if transmission else 'reflection'} bins")
    edges = b.theta_edges[:-1][rows], b.theta_edges[1:][rows]
    radial = np.append(edges[0], edges[1][-1])
    if transmission:
        radial = 180.0 - radial
    figure = Figure(figsize=(5.2, 4.6), layout="constrained")
    axes = figure.add_subplot(projection="polar")
    mesh = axes.pcolormesh(np.radians(b.phi_edges), radial, reading.brdf[w, i][rows], shading="flat")
    axes.set_ylim(0, 90)
    figure.colorbar(mesh, ax=axes, label="BTDF (1/sr)" if transmission else "BRDF (1/sr)")
    axes.set_title(f"{'transmission' if transmission else 'reflection'} hemisphere, θi = {reading.theta_i[i]:g}°, "
                   f"λ = {reading.wavelengths[w]:g} nm\n(radius: polar angle from the "
                   f"{'lower' if transmission else 'upper'} normal)", fontsize=9)
    if path is not None:
        figure.savefig(Path(path), dpi=90)
    return figure
