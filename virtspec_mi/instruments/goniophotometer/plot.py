"""
Plots of goniophotometer readings (PNG and SVG)
===============================================

- :func:`plot_polar`: f (BRDF above the specimen, BTDF below) in the plane of
  incidence and in the plane across it, as polar plots — the reflection lobe in the
  upper half, the transmission lobe in the lower half — one curve per θi (the angular
  distribution over θi as a series), each with its simultaneous Clopper–Pearson band
  (the certified band: all K bins at once at 1 − δ).
- :func:`plot_hemisphere`: a 2-D map of f over one hemisphere (θo radial, φo around).
- :func:`plot_series`: the angular distribution over θi as a series — one column per
  θi: f in the plane of incidence against θo (reflected, then transmitted) with the
  certified band, and the empirical CDF of θo with its DKW band (± ``cdf_mu``).

The plane of incidence is drawn through the φo bins that hold φi + 180° (the mirror
side, drawn at +θo) and φi (the back side, drawn at −θo); the perpendicular plane
through φi ± 90°. Folded readings (relative azimuth) use 180° and 0°, resp. 90°.
The polar plots (:data:`POLAR_SIZE`, at :data:`DPI`) write four or five radial tick labels
along the horizon (:data:`HORIZON`), clear of the lobes and of each other; their
title takes two lines (what, then the rays and bins). The figures are built without
``pyplot``; the file suffix picks the format.

References
----------
Nicodemus et al. (1977), NBS Monograph 160.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.results.plot import check_figure_path, curve_style

__all__ = ["HORIZON", "POLAR_SIZE", "DPI", "plot_polar", "plot_hemisphere", "plot_series", "plane_bins"]

POLAR_SIZE: tuple[float, float] = (12.0, 6.8)
"""The polar plots' size in inches: 1,200 × 680 px at :data:`DPI`."""

DPI: int = 100
"""Dots per inch of the goniophotometer figures' PNG files."""

HORIZON: float = 90.0
"""
Where :func:`plot_polar` writes its radial tick labels (degrees, on the mirror side): along
the horizon θo = 90°, which parts the reflection lobe (drawn within ±90° of the upper
normal) from the transmission lobe (beyond); a curve only ends there, none crosses it.
"""


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
               log: bool = False, name: str | None = None) -> Any:
    """
    Polar plots of f in the plane of incidence and across it, one curve per θi with its
    certified band, at ``wavelength`` (default: the first; the title says which);
    ``name`` (e.g. a file name) heads the title. Returns the ``Figure``.
    """

    from matplotlib.figure import Figure

    path = check_figure_path(path)
    w = 0 if wavelength is None else int(np.argmin(np.abs(reading.wavelengths - wavelength)))
    from matplotlib.ticker import MaxNLocator

    figure = Figure(figsize=POLAR_SIZE, layout="constrained")
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
        axes.set_title(f"f (1/sr), {title}", fontsize=11, pad=14)
        axes.set_thetagrids(range(0, 360, 30), labels=[f"{a if a <= 180 else a - 360}°" for a in range(0, 360, 30)],
                            fontsize=9)
        axes.yaxis.set_major_locator(MaxNLocator(4))  # few radial labels: they do not run into each other
        axes.set_rlabel_position(HORIZON)  # between the lobes, away from the beam's arrows (drawn at −θi)
        axes.tick_params(axis="y", labelsize=8)
        if panel == 0:
            axes.legend(loc="lower left", fontsize=9, bbox_to_anchor=(-0.12, -0.1))
    return _finish(figure, reading, w, f"{name + ': ' if name else ''}goniophotometer", "band: all bins", 12, path)


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
                   f"{'lower' if transmission else 'upper'} normal)", fontsize=9, wrap=True)
    if path is not None:
        figure.savefig(Path(path), dpi=DPI)
    return figure


def plot_series(reading: Any, path: str | os.PathLike | None = None, wavelength: float | None = None,
                log: bool = False) -> Any:
    """
    The angular distribution over θi as a series: one column per θi, rows f in the plane
    of incidence (BRDF against the signed θo, + on the mirror side; BTDF against the angle
    from the lower normal), each bin a step with its simultaneous Clopper–Pearson band,
    and the empirical CDF of θo with its DKW band (± ``cdf_mu``; none where not
    certified), at ``wavelength`` (default: the first). Returns the ``Figure``.
    """

    from matplotlib.figure import Figure

    path = check_figure_path(path)
    w = 0 if wavelength is None else int(np.argmin(np.abs(reading.wavelengths - wavelength)))
    b = reading.bins
    lower_t, upper_t, theta = b.theta_edges[:-1], b.theta_edges[1:], b.theta_centres
    sides = [(name, rows) for name, rows in (("BRDF, reflected", theta < 90.0), ("BTDF, transmitted", theta > 90.0))
             if np.any(rows)]
    columns = len(reading.theta_i)
    figure = Figure(figsize=(2.6 * columns + 1.2, 2.2 * (len(sides) + 1) + 0.6), layout="constrained")
    grid = figure.subplots(len(sides) + 1, columns, squeeze=False, sharex="row", sharey="row")
    front, back = plane_bins(reading)
    for i, angle in enumerate(reading.theta_i):
        style = curve_style(0, 2 * len(theta))
        for row, (name, rows) in enumerate(sides):
            axes = grid[row, i]
            for sign, column in ((1.0, front), (-1.0, back)):
                if name.startswith("BRDF"):
                    polar, outer = lower_t[rows], upper_t[rows]
                else:  # the angle from the lower normal
                    polar, outer = 180.0 - upper_t[rows], 180.0 - lower_t[rows]
                start, stop = np.minimum(sign * polar, sign * outer), np.maximum(sign * polar, sign * outer)
                order = np.argsort(start)
                x = np.column_stack([start[order], stop[order]]).ravel()  # each bin a step, left to right

                def steps(values: np.ndarray) -> np.ndarray:
                    return np.repeat(values[w, i, rows, column][order], 2)

                axes.plot(x, steps(reading.brdf), color=style["color"], linestyle=style["linestyle"],
                          label="f" if sign > 0 else None)
                axes.fill_between(x, steps(reading.brdf_lower), steps(reading.brdf_upper), color=style["color"],
                                  alpha=0.25, linewidth=0, label="certified band" if sign > 0 else None)
            if log:
                axes.set_yscale("symlog", linthresh=1e-2)
            axes.axvline(0.0, color="0.7", linewidth=0.5)
            if name.startswith("BRDF") and reading.result.settings.beam != "diffuse":
                axes.axvline(float(angle), color="0.4", linewidth=0.8, linestyle=":")  # the mirror direction
            axes.set_title(f"θi = {angle:g}°" if row == 0 else "", fontsize=9)
            axes.set_xlabel("θo from its normal, in the plane (deg; + forward)"
                            if row == len(sides) - 1 else "", fontsize=7)
            if i == 0:
                axes.set_ylabel(f"{name} (1/sr)", fontsize=8)
                if row == 0:
                    axes.legend(fontsize=7)
        axes = grid[-1, i]
        cdf, mu = reading.cdf_theta_o[w, i], float(reading.cdf_mu[w, i])
        axes.step(b.theta_edges, cdf, where="post", color=style["color"], label="empirical CDF of θo")
        if np.isfinite(mu):
            axes.fill_between(b.theta_edges, np.clip(cdf - mu, 0, 1), np.clip(cdf + mu, 0, 1), step="post",
                              color=style["color"], alpha=0.25, linewidth=0, label=f"DKW band ± {mu:.3g}")
        axes.axvline(90.0, color="0.7", linewidth=0.5)
        axes.set_xlabel("θo (deg; > 90 transmitted)", fontsize=7)
        if i == 0:
            axes.set_ylabel("F(θo)", fontsize=8)
        axes.legend(fontsize=6, loc="lower right")
    return _finish(figure, reading, w, "goniophotometer over θi", "bands: all at once", 9, path)


def _finish(figure: Any, reading: Any, w: int, what: str, band: str, size: int,
            path: str | os.PathLike | None) -> Any:
    """The figure's title (the specimen, beam, λ, N, K and the band's level), saved to ``path`` when given."""

    specimen = reading.specimen_label
    of = f" of {specimen}" if specimen else ""
    figure.suptitle(f"{what}{of}, {reading.result.settings.beam} beam, λ = {reading.wavelengths[w]:g} nm\n"
                    f"N = {int(reading.rays.max()):,} rays, K = {reading.size} bins ({band} at "
                    f"{1 - reading.delta:g})", fontsize=size, wrap=True)
    if path is not None:
        figure.savefig(path, dpi=DPI)
    return figure
