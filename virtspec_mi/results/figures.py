"""
A result kind's figures as a table: :class:`Figure`
===================================================

A kind lists the figures it draws in one table, ``FIGURES`` (name → :class:`Figure`): the
function that draws it and the quantities it shows. :meth:`ResultBase.plot
<virtspec_mi.results.base.ResultBase.plot>` draws one of them for every kind: the one
named (``figure="series"``), else the first that shows the quantity asked (``None``: the
kind's first figure), and the command line's figure flags name them
(:class:`virtspec_mi.instruments.command.FigureFlag`).

References
----------
Matplotlib's object-oriented interface (``matplotlib.figure.Figure``), used by every drawing.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Mapping

__all__ = ["Figure", "chosen_figure", "spectra", "sweep"]


@dataclass(frozen=True)
class Figure:
    """One figure a result kind draws (see the module docstring)."""

    draw: Callable[..., Any]
    """``draw(result, path, quantity, **options)`` → a ``matplotlib.figure.Figure`` (written to ``path`` if given)."""
    description: str
    """What it shows, in words."""
    quantities: tuple[str, ...] | None = None
    """The quantities it shows (``None``: every quantity of the kind)."""

    def shows(self, quantity: str | None) -> bool:
        """Whether it shows ``quantity`` (``None``: its default, always)."""

        return quantity is None or self.quantities is None or quantity in self.quantities


def chosen_figure(figures: Mapping[str, Figure], kind: str, figure: str | None, quantity: str | None) -> Figure:
    """
    The figure named ``figure``, else the first that shows ``quantity``; ``ValueError``
    naming the figures of the ``kind`` (in words) and what each shows.
    """

    listed = "; ".join(f"{name!r}: {item.description}" for name, item in figures.items())
    if figure is not None:
        if figure not in figures:
            raise ValueError(f"figure must be one of the {kind}'s figures ({listed}; got {figure!r})")
        if not figures[figure].shows(quantity):
            raise ValueError(f"the {kind}'s figure {figure!r} shows {', '.join(figures[figure].quantities or ())}, "
                             f"not {quantity!r}")
        return figures[figure]
    for item in figures.values():
        if item.shows(quantity):
            return item
    raise ValueError(f"no figure of the {kind} shows {quantity!r} ({listed})")


def spectra(default: tuple[str, ...] | None = None) -> Figure:
    """
    Quantities over wavelength at one θi, each with the band of its certified tolerance
    (:func:`virtspec_mi.results.plot.plot_spectra`): the one asked, ``quantities=`` among
    the options, else ``default`` (``None``: the kind's first quantity).
    """

    def draw(result: Any, path: Any, quantity: str | None, quantities: Any = None, **options: Any) -> Any:
        from virtspec_mi.results.plot import plot_spectra

        chosen = quantities or ((result.check_quantity(quantity),) if quantity is not None else default)
        return plot_spectra(result, path, quantities=chosen, **options)

    shown = "its first quantity" if default is None else " and ".join(default)
    return Figure(draw, f"{shown} over wavelength at one theta_i, with the bands of their certified tolerance")


def _sweep(result: Any, path: Any, quantity: str | None, **options: Any) -> Any:
    from virtspec_mi.results.plot import plot_sweep

    return plot_sweep(result, path, quantity=result.check_quantity(quantity), **options)


sweep: Figure = Figure(_sweep, "one quantity against theta_i (one curve per wavelength) or wavelength, with the band "
                               "of its certified tolerance (:func:`virtspec_mi.results.plot.plot_sweep`)")
"""A reading's quantity against θi or wavelength (a sweep's figure)."""
