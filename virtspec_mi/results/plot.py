"""
Plots of results with matplotlib (PNG and SVG)
==============================================

- :func:`plot_sweep`: a reading against θi (the paper's Fig. 5) or against
  wavelength (a spectrum), one curve per wavelength (resp. per θi) and per sweep,
  each with the band of its certified tolerance (the μ' its rays guarantee; none
  where a reading is not certified). ``wavelengths=`` / ``theta_i=`` pick readings.
- :func:`plot_spectra`: quantities of a result of any kind over wavelength at one θi,
  each with the band of its certified tolerance (a sphere's reading and the
  hemispherical value of the same rays).
- :func:`plot_densities`: sweeps at successive ray densities N = 10^d side by side
  (Fig. 5), their fluctuation Δ of eq. (24) (Fig. 6a) and their seconds (Fig. 6b).
- :func:`plot_comparison`: a result over a measured spectrum (a
  :class:`virtspec_mi.applications.comparison.Comparison`) with a panel of the residuals and their
  combined tolerance.

Every figure names what was measured in its title (a name when given, the quantity,
the beam, θi, the rays and the specimen: its scene, defines and parameter point; wrapped
to the figure's width), gives the certified band a legend entry that says what its
half-width μ' is (the tolerance the reading's rays guarantee; a single point's band is an
error bar) and draws markers on sparse grids
(≤ :data:`SPARSE` points). It tells its curves apart: up to :data:`LEGEND` curves each
by colour and line style (:func:`curve_style`; both cycle), each with a legend entry;
more (e.g. a sweep of 31 wavelengths) by a sequential colour map (:data:`COLOUR_MAP`)
over each curve's wavelength (resp. θi), with a colour bar, in solid lines, with bands
so faint that all of them stacked are half opaque; several results then each have a
line style (and marker) of their own, named in the legend. The figures are built
without ``pyplot`` (no display needed); the file suffix picks the format (``.png``
or ``.svg``).

References
----------
Baranoski et al. (2001), Figs. 5 and 6, eq. (24).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np

__all__ = [
    "FIGURE_SUFFIXES",
    "SPARSE",
    "LEGEND",
    "COLOUR_MAP",
    "check_figure_path",
    "describe",
    "select",
    "curve_style",
    "plot_sweep",
    "plot_spectra",
    "plot_densities",
    "plot_comparison",
]

FIGURE_SUFFIXES: tuple[str, ...] = (".png", ".svg")

SPARSE: int = 20
"""Curves with at most this many points are drawn with markers."""

LEGEND: int = 12
"""A figure lists at most this many curves in its legend; with more it colours them by :data:`COLOUR_MAP`."""

COLOUR_MAP: str = "viridis"
"""The sequential colour map of many curves over their wavelength (resp. θi): lighter as it grows."""

_COLOURS = 10  # matplotlib's default "tab10" cycle: C0 … C9
_LINE_STYLES = ("-", "--", "-.", ":")
_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")
_BAND = "certified ±μ'"
_MU = "μ': the tolerance its rays guarantee"  # what the band's half-width is, said in every legend
_BAND_ALPHA = 0.2  # a certified band's opacity among few curves
_STACKED_BANDS = 0.5  # among many, the opacity of all bands stacked: each the fainter the more curves


def check_figure_path(path: str | os.PathLike | None) -> Path | None:
    """``path`` as a ``Path`` if its suffix is a figure format (``None`` passes through)."""

    if path is None:
        return None
    path = Path(path)
    if path.suffix.lower() not in FIGURE_SUFFIXES:
        raise ValueError(f"plot must end in one of {', '.join(FIGURE_SUFFIXES)} (got {path.name!r})")
    return path


def curve_style(index: int, points: int) -> dict[str, Any]:
    """
    Colour, line style and marker of curve ``index`` (0, 1, …) of ``points`` points:
    colour ``C{index % 10}``, line style cycling so that curves 10 apart differ
    (``(index + index // 10) % 4``), a marker only on sparse curves.
    """

    style: dict[str, Any] = {"color": f"C{index % _COLOURS}",
                             "linestyle": _LINE_STYLES[(index + index // _COLOURS) % len(_LINE_STYLES)]}
    if points <= SPARSE:
        style.update(marker=_MARKERS[index % len(_MARKERS)], markersize=4)
    return style


def describe(result: Any, quantity: str = "reflectance", name: str | None = None) -> str:
    """
    A two-line title naming what was measured (a result of any kind): ``name`` (e.g. a
    file name) and the specimen (its scene, ``-D`` defines and parameter point:
    :attr:`~virtspec_mi.results.base.ResultBase.specimen_label`), then the quantity, beam,
    θi and rays per reading.
    """

    s = result.settings
    angles = np.atleast_1d(result.coords["theta_i"])
    if s.beam == "diffuse":
        incidence = "diffuse illumination"
    else:
        theta = f"θi = {angles[0]:g}°" if len(angles) == 1 else f"θi = {angles.min():g}–{angles.max():g}°"
        incidence = f"{s.beam} beam, {theta}" + (f", φi = {s.phi_i:g}°" if s.phi_i else "")
    low, high = int(np.min(result.rays)), int(np.max(result.rays))
    rays = f"N = {low:,}" if low == high else f"N = {low:,}–{high:,}"
    head = " — ".join(filter(None, (name, result.specimen_label))) or "virtspec-mi result"
    return f"{head}\n{quantity}, {incidence}, {rays} rays per reading"


def select(result: Any, wavelengths: Sequence[float] | None = None, theta_i: Sequence[float] | None = None) -> Any:
    """
    The readings of ``result`` (any kind) at the given wavelengths and/or θi (each must be
    one of the result's; ``None`` keeps all), as a result with a θi dimension.
    """

    result = result.as_grid()
    rows = _indices("wavelengths", np.asarray(result.coords["wavelength"]), wavelengths)
    columns = _indices("theta_i", np.asarray(result.coords["theta_i"]), theta_i)
    return result.isel(wavelength=rows, theta_i=columns)


def _indices(name: str, have: np.ndarray, wanted: Sequence[float] | None) -> np.ndarray:
    if wanted is None:
        return np.arange(len(have))
    indices = []
    for value in np.atleast_1d(np.asarray(wanted, dtype=np.float64)):
        match = np.flatnonzero(np.isclose(have, value, rtol=0, atol=1e-6))
        if not len(match):
            raise ValueError(f"{name} must be among the result's {name} "
                             f"({', '.join(f'{v:g}' for v in have[:12])}{' ...' if len(have) > 12 else ''}; "
                             f"got {value:g})")
        indices.append(int(match[0]))
    return np.array(indices)


def _curves(result: Any, quantity: str) -> tuple[bool, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    The curves of one result (any kind): whether they run against θi (one curve per
    wavelength; else against wavelength, one per θi), the abscissae in order, the readings
    and their certified half-widths (one row per curve) and each curve's wavelength (resp. θi).
    """

    result = result.as_grid()
    by_angle = len(result.theta_i) > 1 or len(result.wavelengths) == 1
    x = np.asarray(result.theta_i if by_angle else result.wavelengths, dtype=np.float64)
    order = np.argsort(x)
    values, mu = np.asarray(result.quantity(quantity)), np.asarray(result.certified_mu)
    curves, bands = (values, mu) if by_angle else (values.T, mu.T)
    each = np.asarray(result.wavelengths if by_angle else result.theta_i, dtype=np.float64)
    return by_angle, x[order], curves[:, order], bands[:, order], each


def _draw(axes: Any, results: Sequence[Any], quantity: str, labels: Sequence[str | None]) -> None:
    """
    Draw the curves of ``results`` (each with the band of its certified tolerance) and their
    legend. At most :data:`LEGEND` curves in all: each its own colour and line style
    (:func:`curve_style`) and legend entry. More (their wavelengths, resp. θi, not all one):
    each curve coloured by its wavelength (resp. θi) on :data:`COLOUR_MAP`, with a colour
    bar, its band so faint that all of them stacked are half opaque; each result its line
    style (and small markers), with a legend entry (its label, else "result 1", …) when
    there are several.
    """

    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.lines import Line2D

    drawn = [_curves(result, quantity) for result in results]
    by_angle = drawn[0][0]
    symbol, unit, variable = ("λ", " nm", "wavelength (nm)") if by_angle else ("θi", "°", "θi (°)")
    every = np.concatenate([each for *_, each in drawn])
    low, high = float(every.min()), float(every.max())
    mapped = len(every) > LEGEND and high > low
    colours = ScalarMappable(Normalize(low, high), COLOUR_MAP)
    alpha = 1.0 - (1.0 - _STACKED_BANDS) ** (1.0 / len(every)) if mapped else _BAND_ALPHA
    count = 0
    for r, ((_, x, curves, bands, each), label) in enumerate(zip(drawn, labels)):
        for value, curve, band in zip(each, curves, bands):
            style = {**curve_style(r, len(x)), "color": colours.to_rgba(value), "markersize": 2.5} if mapped else \
                curve_style(count, len(x))
            line, = axes.plot(x, curve, lw=1.2, label=f"{label + ', ' if label else ''}{symbol} = {value:g}{unit}",
                              **style)
            _band(axes, x, curve, band, line.get_color(), alpha)
            count += 1
    axes.set_xlabel("θi (degrees)" if by_angle else "wavelength (nm)")
    axes.set_ylabel(quantity)
    delta = results[0].interval_delta
    if not mapped:
        span = f"{low:g}" if low == high else f"{low:g}…{high:g}"
        _legend(axes, delta, summary=f"{count} curves, {symbol} = {span}{unit} (colours and line styles cycle)")
        return
    axes.get_figure().colorbar(colours, ax=axes, label=variable)
    entries = [Line2D([], [], label=label or f"result {r + 1}", **{**curve_style(r, len(x)), "color": "0.3"})
               for r, ((_, x, *_), label) in enumerate(zip(drawn, labels))]
    _legend(axes, delta, entries if len(results) > 1 else [],
            summary=f"{len(results)} results (line styles cycle; colour: {variable})")


def _band(axes: Any, x: np.ndarray, y: np.ndarray, half_width: np.ndarray, colour: Any, alpha: float) -> None:
    """
    The certified band ``y ± half_width`` over ``x``: a shaded area, or for a single
    point (one wavelength) an error bar, which an area of no width would not show.
    """

    if len(x) > 1:
        axes.fill_between(x, y - half_width, y + half_width, color=colour, lw=0, alpha=alpha)
    else:
        axes.errorbar(x, y, yerr=half_width, fmt="none", ecolor=colour, elinewidth=6, alpha=max(alpha, 0.35),
                      capsize=0)


def _legend(axes: Any, delta: float, entries: Sequence[Any] | None = None, summary: str = "") -> None:
    """
    The legend: ``entries`` (default: the axes' labelled curves) when at most :data:`LEGEND`,
    else one line, ``summary``, saying how many; always the certified band.
    """

    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    entries = axes.get_legend_handles_labels()[0] if entries is None else list(entries)
    if len(entries) > LEGEND:
        entries = [Line2D([], [], color="none", label=summary)]
    band = Patch(facecolor="grey", alpha=0.35, lw=0, label=f"{_BAND} (δ = {delta:g} per reading; {_MU})")
    axes.legend(handles=[*entries, band], fontsize="small")


def plot_sweep(results: Any, path: str | os.PathLike | None = None, *, quantity: str = "reflectance",
               labels: Sequence[str] | None = None, title: str | None = None, name: str | None = None,
               wavelengths: Sequence[float] | None = None, theta_i: Sequence[float] | None = None) -> Any:
    """
    Plot one or several results and save to ``path`` (``.png``/``.svg``) when given.

    A sweep over several θi is drawn against θi (one curve per wavelength), a result
    at one θi against wavelength. More than :data:`LEGEND` curves in all are coloured
    by their wavelength (resp. θi) on :data:`COLOUR_MAP` with a colour bar, each result
    (``labels``) in a line style of its own. ``wavelengths`` / ``theta_i`` keep only
    those readings; ``name`` goes into the title (:func:`describe`), ``title`` replaces
    it. Returns the ``matplotlib.figure.Figure``.
    """

    from matplotlib.figure import Figure

    path = check_figure_path(path)
    results = [results] if not isinstance(results, (list, tuple)) else list(results)
    if wavelengths is not None or theta_i is not None:
        results = [select(r, wavelengths, theta_i) for r in results]
    labels = list(labels) if labels is not None else [None] * len(results)
    figure = Figure(figsize=(6.4, 4.4), layout="constrained")
    axes = figure.add_subplot()
    _draw(axes, results, quantity, labels)
    axes.grid(alpha=0.3)
    axes.set_title(title or describe(results[0].as_grid(), quantity, name), fontsize="medium", wrap=True)
    if path is not None:
        figure.savefig(path, dpi=110)
    return figure


def plot_spectra(result: Any, path: str | os.PathLike | None = None, *, quantities: Sequence[str] | None = None,
                 theta_i: float | None = None, title: str | None = None, name: str | None = None) -> Any:
    """
    Quantities of ``result`` (any kind; default its first) over wavelength at one θi
    (``None``: the only one), one curve each with the band of its certified tolerance
    (:meth:`~virtspec_mi.results.base.ResultBase.spectrum`), saved to ``path``
    (``.png``/``.svg``) when given. Returns the ``matplotlib.figure.Figure``.
    """

    from matplotlib.figure import Figure

    path = check_figure_path(path)
    quantities = list(quantities) if quantities else [result.QUANTITIES[0]]
    spectra = [result.spectrum(quantity, theta_i) for quantity in quantities]
    figure = Figure(figsize=(6.4, 4.4), layout="constrained")
    axes = figure.add_subplot()
    for k, spectrum in enumerate(spectra):
        x, y, band = spectrum.wavelengths, spectrum.values, spectrum.tolerance
        line, = axes.plot(x, y, lw=1.2, label=spectrum.quantity, **curve_style(k, len(x)))
        _band(axes, x, y, band, line.get_color(), _BAND_ALPHA)
    axes.set_xlabel("wavelength (nm)")
    axes.set_ylabel(", ".join(dict.fromkeys(spectrum.measures for spectrum in spectra)))
    _legend(axes, spectra[0].delta, summary=f"{len(spectra)} quantities (colours and line styles cycle)")
    axes.grid(alpha=0.3)
    shown = select(result, theta_i=[spectra[0].theta_i])
    axes.set_title(title or describe(shown, ", ".join(quantities), name), fontsize="medium", wrap=True)
    if path is not None:
        figure.savefig(path, dpi=110)
    return figure


def plot_densities(results: Sequence[Any], densities: Sequence[float], deltas: Sequence[float],
                   path: str | os.PathLike | None = None, *, quantity: str = "reflectance") -> Any:
    """
    The paper's Figs. 5–6 from sweeps at ray densities log₁₀ N = ``densities``: the
    curves, Δ (eq. 24) between successive densities, and the seconds per density.
    ``deltas[j]`` is Δ between densities j − 1 and j (``deltas[0]`` is unused, NaN).
    """

    from matplotlib.figure import Figure

    path = check_figure_path(path)
    figure = Figure(figsize=(12, 3.8), layout="constrained")
    curves, fluct, cost = figure.subplots(1, 3)
    _draw(curves, results, quantity, [f"log N = {d:g}" for d in densities])
    curves.set_title("Fig. 5: readings at each ray density", fontsize="medium")
    fluct.plot(list(densities)[1:], list(deltas)[1:], "o-")
    fluct.set_xlabel("log10 N")
    fluct.set_ylabel("Δ, eq. (24)")
    fluct.set_title("Fig. 6a: average fluctuation", fontsize="medium")
    cost.plot(densities, [r.seconds for r in results], "o-")
    cost.set_xlabel("log10 N")
    cost.set_ylabel("seconds")
    cost.set_yscale("log")
    cost.set_title("Fig. 6b: processing time", fontsize="medium")
    for axes in (curves, fluct, cost):
        axes.grid(alpha=0.3)
    if path is not None:
        figure.savefig(path, dpi=110)
    return figure


def plot_comparison(comparison: Any, path: str | os.PathLike | None = None, *, title: str | None = None,
                    name: str | None = None) -> Any:
    """
    A result over a measured spectrum (``comparison``: a :class:`virtspec_mi.applications.comparison.Comparison`):
    above, the simulated spectrum with its certified band and the measured one (with
    its uncertainty when known; wavelengths outside the measured range shaded: not
    compared); below, the residuals simulated − measured with the combined tolerance
    ±(μ' + u). Saved to ``path`` when given; returns the figure.
    """

    from matplotlib.figure import Figure

    path = check_figure_path(path)
    c = comparison
    figure = Figure(figsize=(6.4, 5.6), layout="constrained")
    top, bottom = figure.subplots(2, 1, sharex=True, height_ratios=(2.2, 1))
    x, y, mu = c.simulated_spectrum()
    line, = top.plot(x, y, lw=1.3, label=f"simulated: {c.result_name}", **curve_style(0, len(x)))
    top.fill_between(x, y - mu, y + mu, color=line.get_color(), alpha=0.25, lw=0,
                     label=f"{_BAND} (δ = {c.interval_delta:g} per point; {_MU})")
    m = c.spectrum
    sparse = len(m.wavelengths) <= SPARSE
    if m.uncertainty is not None and sparse:
        top.errorbar(m.wavelengths, m.values, yerr=m.uncertainty, capsize=3, lw=1.3,
                     label=f"measured: {m.source} (± its uncertainty)", **curve_style(1, len(m.wavelengths)))
    else:
        measured, = top.plot(m.wavelengths, m.values, lw=1.3, label=f"measured: {m.source}",
                             **curve_style(1, len(m.wavelengths)))
        if m.uncertainty is not None:
            top.fill_between(m.wavelengths, m.values - m.uncertainty, m.values + m.uncertainty, facecolor="none",
                             edgecolor=measured.get_color(), hatch="///", lw=0, label="measurement uncertainty")
    for axes in (top, bottom):
        for k, (low, high) in enumerate(_outside(x, m.wavelengths)):
            axes.axvspan(low, high, color="0.85", lw=0, zorder=0,
                         label="not compared (outside the measured range)" if axes is top and k == 0 else None)
    top.set_ylabel(c.quantity)
    top.legend(fontsize="small")
    bottom.axhline(0.0, color="0.3", lw=0.8)
    tolerance = c.tolerance
    bottom.fill_between(c.wavelengths, -tolerance, tolerance, color="C0", alpha=0.2, lw=0,
                        label="combined tolerance ±(μ' + u)" if np.any(c.measurement_uncertainty) else _BAND)
    bottom.plot(c.wavelengths, c.residuals, lw=1.2, color="C3",
                **({"marker": "o", "markersize": 4} if len(c.wavelengths) <= SPARSE else {}),
                label=f"simulated − measured: {c.points_within} of {int(c.certified.sum())} within")
    bottom.set_xlabel("wavelength (nm)")
    bottom.set_ylabel("residual")
    reach = float(np.nanmax(np.concatenate([np.abs(c.residuals), tolerance, [1e-6]])))
    bottom.set_ylim(-1.15 * reach, 2.0 * reach)  # room above the data for the legend
    bottom.legend(fontsize="small", loc="upper center", ncols=2)
    for axes in (top, bottom):
        axes.grid(alpha=0.3)
    delta_e = f"ΔE2000 = {c.delta_E:.2f} ({c.illuminant})" if not c.delta_E_note else "ΔE2000 not computed"
    top.text(0.01, 0.98, f"RMSE = {c.rmse:.4f}, {delta_e}", transform=top.transAxes, va="top", fontsize="small")
    shown = select(c.result, theta_i=[c.theta_i])  # the angle compared
    top.set_title(title or describe(shown, c.quantity, name or c.result_name), fontsize="medium", wrap=True)
    if path is not None:
        figure.savefig(path, dpi=110)
    return figure


def _outside(x: np.ndarray, measured: np.ndarray) -> list[tuple[float, float]]:
    """The spans of ``x`` beyond the measured range (at most one on each side)."""

    spans = []
    if x.min() < measured.min():
        spans.append((float(x.min()), float(measured.min())))
    if x.max() > measured.max():
        spans.append((float(measured.max()), float(x.max())))
    return spans
