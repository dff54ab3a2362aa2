"""
Plots of sweeps with matplotlib (PNG and SVG)
=============================================

- :func:`plot_sweep`: a reading against θi (the paper's Fig. 5) or against
  wavelength (a spectrum), one curve per wavelength (resp. per θi) and per sweep,
  each with the band of its certified tolerance (the μ its rays guarantee; none
  where a reading is not certified).
- :func:`plot_densities`: sweeps at successive ray densities N = 10^d side by side
  (Fig. 5), their fluctuation Δ of eq. (24) (Fig. 6a) and their seconds (Fig. 6b).

The figures are built without ``pyplot`` (no display needed); the file suffix picks
the format (``.png`` or ``.svg``).

References
----------
Baranoski et al. (2001), Figs. 5 and 6, eq. (24).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np

__all__ = ["FIGURE_SUFFIXES", "check_figure_path", "plot_sweep", "plot_densities"]

FIGURE_SUFFIXES: tuple[str, ...] = (".png", ".svg")


def check_figure_path(path: str | os.PathLike | None) -> Path | None:
    """``path`` as a ``Path`` if its suffix is a figure format (``None`` passes through)."""

    if path is None:
        return None
    path = Path(path)
    if path.suffix.lower() not in FIGURE_SUFFIXES:
        raise ValueError(f"plot must end in one of {', '.join(FIGURE_SUFFIXES)} (got {path.name!r})")
    return path


def _draw(axes: Any, result: Any, quantity: str, label: str | None) -> None:
    result = result.as_grid()
    values = result.quantity(quantity)
    mu = result.certified_mu
    by_angle = len(result.theta_i) > 1 or len(result.wavelengths) == 1
    x = np.asarray(result.theta_i if by_angle else result.wavelengths, dtype=np.float64)
    order = np.argsort(x)
    curves, bands = (values, mu) if by_angle else (values.T, mu.T)  # one row per curve
    names = result.wavelengths if by_angle else result.theta_i
    unit = "nm" if by_angle else "deg"
    for name, curve, band in zip(names, curves, bands):
        text = f"{label + ', ' if label else ''}{'λ' if by_angle else 'θi'} = {name:g} {unit}"
        line, = axes.plot(x[order], curve[order], lw=1.2, label=text)
        axes.fill_between(x[order], (curve - band)[order], (curve + band)[order], color=line.get_color(),
                          alpha=0.2, lw=0)
    axes.set_xlabel("θi (degrees)" if by_angle else "wavelength (nm)")
    axes.set_ylabel(f"{quantity} (band: ± the certified tolerance at δ = {result.interval_delta:g})")


def plot_sweep(results: Any, path: str | os.PathLike | None = None, *, quantity: str = "reflectance",
               labels: Sequence[str] | None = None, title: str | None = None) -> Any:
    """
    Plot one or several sweeps and save to ``path`` (``.png``/``.svg``) when given.

    A sweep over several θi is drawn against θi (one curve per wavelength), a sweep at
    one θi against wavelength. Returns the ``matplotlib.figure.Figure``.
    """

    from matplotlib.figure import Figure

    path = check_figure_path(path)
    results = [results] if not isinstance(results, (list, tuple)) else list(results)
    labels = list(labels) if labels is not None else [None] * len(results)
    figure = Figure(figsize=(6.4, 4.2), layout="constrained")
    axes = figure.add_subplot()
    for result, label in zip(results, labels):
        _draw(axes, result, quantity, label)
    results = [r.as_grid() for r in results]
    if sum(len(r.theta_i if len(r.theta_i) == 1 else r.wavelengths) for r in results) <= 12:
        axes.legend(fontsize="small")
    axes.grid(alpha=0.3)
    s = results[0].settings
    axes.set_title(title or f"{s.beam} {quantity}, N = {int(results[0].rays.max()):,} rays per reading",
                   fontsize="medium")
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
    for result, d in zip(results, densities):
        _draw(curves, result, quantity, f"log N = {d:g}")
    curves.legend(fontsize="x-small")
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
