"""
A result kind's dataset as tables: :class:`Variable` and :class:`Coordinate`
============================================================================

A result is one ``xarray.Dataset`` of exact counts (:attr:`~virtspec_mi.results.base.ResultBase.data`);
what its files and ``to_dataset()`` add is derived from it. A kind lists what it adds in
two tables instead of writing methods:

- ``DERIVED``: name → :class:`Variable` — how the values are computed from the result,
  along which dims (every dim of the result, the readings' dims, or the kind's own), its
  ``units`` and ``long_name``, further attributes (e.g. the δ of a Clopper–Pearson
  bound), whether it is an exact count (compared with a file's, rule 6 of
  :mod:`virtspec_mi.results.integrity`) and whether a CSV row holds it;
- ``COORDS``: name → :class:`Coordinate` — labels beside the stored ones (e.g. a
  goniophotometer's bin edges).

:meth:`~virtspec_mi.results.base.ResultBase.to_dataset`,
:meth:`~virtspec_mi.results.base.ResultBase.csv_dataset` and the units of every file are
built from them, for every kind. :func:`bounds` writes the lower and upper Clopper–Pearson
bounds of some quantities at once; :func:`of_reading` gives the variables of the reading a
kind extends (a goniophotometer's R, T and A).

References
----------
CF Conventions 1.11, Sect. 3.1 (``units``) and 3.2 (``long_name``); Clopper & Pearson (1934).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable, Mapping

__all__ = ["ALL", "READINGS", "Variable", "Coordinate", "bounds", "of_reading"]

ALL: str = "all"
"""Along every dim of the result."""
READINGS: str = "readings"
"""Along the readings' dims: the result's dims without the kind's own (its bins, its configurations)."""


@dataclass(frozen=True)
class Variable:
    """One variable a kind derives from its counts (see the module docstring)."""

    units: str
    """UDUNITS spelling: ``1`` for fractions and counts, ``1/sr``, ``sr``, ``nm``, ``degree``."""
    long_name: str
    """What it is, in words."""
    values: Callable[[Any], Any]
    """Its values, from the result."""
    dims: str | tuple[str, ...] | Callable[[Any], tuple[str, ...]] = ALL
    """:data:`ALL`, :data:`READINGS`, fixed dims, or a function of the result that gives them."""
    attrs: Callable[[Any], Mapping[str, Any]] | None = None
    """Further attributes, from the result (e.g. ``{"clopper_pearson_delta": δ}``)."""
    count: bool = False
    """An exact count (``int64``): a file's own is compared with the result's as it is read."""
    csv: bool = True
    """A CSV row (one per cell of the result's dims) holds it."""

    def dims_of(self, result: Any) -> tuple[str, ...]:
        """Its dims in ``result``."""

        if self.dims == ALL:
            return tuple(result.dims)
        if self.dims == READINGS:
            return tuple(result.reading_dims)
        return tuple(self.dims(result)) if callable(self.dims) else tuple(self.dims)


@dataclass(frozen=True)
class Coordinate:
    """A label a kind adds to its dataset beside the stored ones (see the module docstring)."""

    units: str
    long_name: str
    dims: tuple[str, ...]
    """The dims it lies along (a new dim of its own, or one of the result's)."""
    values: Callable[[Any], Any]
    csv: bool = True


def bounds(quantities: Mapping[str, str], interval: Callable[[Any, str], tuple[Any, Any]],
           delta: Callable[[Any], float] | None, dims: Any = ALL) -> dict[str, Variable]:
    """
    ``<quantity>_lower`` and ``<quantity>_upper`` of each quantity (name → its words in
    the long name, e.g. ``{"reflectance": "the reflectance"}``): the ends of
    ``interval(result, quantity)``, a Clopper–Pearson interval at ``delta(result)`` (its
    ``clopper_pearson_delta`` attribute; ``None``: no such attribute, an interval made of several).
    """

    def attrs(result: Any) -> dict[str, float]:
        return {} if delta is None else {"clopper_pearson_delta": delta(result)}

    return {f"{quantity}_{side}": Variable("1", f"Clopper-Pearson {side} bound of {words}",
                                           lambda result, q=quantity, e=end: interval(result, q)[e], dims, attrs)
            for quantity, words in quantities.items() for end, side in ((0, "lower"), (1, "upper"))}


def of_reading(table: Mapping[str, Variable]) -> dict[str, Variable]:
    """The variables of the reading a kind extends (its ``result``), along the reading's dims."""

    def moved(variable: Variable) -> Variable:
        attrs = variable.attrs
        return replace(variable, values=lambda result: variable.values(result.result),
                       dims=lambda result: variable.dims_of(result.result),
                       attrs=None if attrs is None else (lambda result: attrs(result.result)))

    return {name: moved(variable) for name, variable in table.items()}
