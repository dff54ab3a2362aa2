"""
Figures of certified derived quantities
=======================================

:func:`plot_derived` draws a :class:`~.result.DerivedResult`: a colour target as a swatch
of the estimate beside the sRGB colours of the certified box's lower and upper corners,
titled with its certified ΔE₀₀ radius; any other target as its values with their
certified intervals as error bars (asymmetric where the map is nonlinear). Saved to
``path`` (``.png`` or ``.svg``) when given; returns the ``matplotlib.figure.Figure``.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from virtspec_mi.results.plot import check_figure_path

__all__ = ["plot_derived"]


def plot_derived(result: Any, path: str | os.PathLike | None = None) -> Any:
    """Draw ``result`` (see the module docstring)."""

    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    path = check_figure_path(path)
    figure = Figure(figsize=(6.4, 3.6), layout="constrained")
    axes = figure.add_subplot()
    if result.colour is not None:
        c = result.colour
        swatches = [("lower corner", c.sRGB_interval[:, 0]), ("estimate", c.sRGB),
                    ("upper corner", c.sRGB_interval[:, 1])]
        for i, (name, rgb) in enumerate(swatches):
            axes.add_patch(Rectangle((i, 0), 0.9, 1, color=np.clip(rgb, 0, 1)))
            axes.text(i + 0.45, -0.08, name, ha="center", va="top", fontsize="small")
        axes.set_xlim(-0.1, 2.9)
        axes.set_ylim(-0.25, 1.05)
        axes.set_axis_off()
        axes.set_title(f"{result.target.describe()}\ncertified dE00 <= {c.dE00_radius:.3g} around L*a*b* "
                       f"({', '.join(f'{v:.2f}' for v in c.Lab)}) at delta = {result.delta:g}",
                       fontsize="medium", wrap=True)
    else:
        names = [v.name for v in result.values]
        values = np.array([v.value for v in result.values])
        errors = np.array([[v.value - v.lower for v in result.values], [v.upper - v.value for v in result.values]])
        axes.errorbar(np.arange(len(names)), values, yerr=errors, fmt="o", capsize=6)
        axes.set_xticks(np.arange(len(names)), names)
        axes.set_xlim(-0.5, len(names) - 0.5)
        axes.grid(alpha=0.3)
        axes.set_title(f"{result.target.describe()}: certified together at delta = {result.delta:g}",
                       fontsize="medium", wrap=True)
    if path is not None:
        figure.savefig(path, dpi=110)
    return figure
