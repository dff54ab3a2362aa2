"""
Instruments
===========

The instruments that measure a specimen through the engine, each one module with one
:class:`~virtspec_mi.instruments.base.Instrument` (its options, its plan, its result and
its ``virtspec`` subcommands, :class:`~virtspec_mi.instruments.command.Command`) and one
row of :data:`INSTRUMENTS`, the registry: the API (:func:`virtspec_mi.take`), the command
line (one subcommand per command of each row), the result files (each row's result kind)
and the ``spectrophotometer`` integrator's ``instrument`` parameter are generated from it.

- ``hemispherical``: the spectrophotometer (``virtspec measure``, ``virtspec sweep``),
  :mod:`.hemispherical`;
- ``goniophotometer``: its readings binned by outgoing direction (``virtspec gonio``),
  :mod:`.goniophotometer`;
- ``sphere``: a physical integrating sphere (``virtspec sphere``), :mod:`.sphere`;
- ``gloss``: a specular gloss meter, the example of a fourth instrument (one module, one
  row), :mod:`.gloss`;
- ``double_sphere``: a double integrating sphere (``virtspec double_sphere``), the
  sphere folder's :mod:`.sphere.double`.

An outside package adds an instrument without editing this one, as xarray's backends do:
an entry point of the group :data:`ENTRY_POINTS` (``virtspec_mi.instruments``) whose value
is its :class:`~virtspec_mi.instruments.base.Instrument` class, e.g. in its
``pyproject.toml``::

    [project.entry-points."virtspec_mi.instruments"]
    tiny = "tiny_instrument:Tiny"

References
----------
Python Packaging User Guide, "Entry points specification"; xarray, "How to add a new
backend" (the ``xarray.backends`` entry-point group).
"""

from __future__ import annotations

import sys
from typing import Any

from virtspec_mi.base.entry_points import discovered as entry_point_rows
from virtspec_mi.instruments.base import Instrument
from virtspec_mi.instruments.gloss import GlossMeter
from virtspec_mi.instruments.goniophotometer import Goniophotometer
from virtspec_mi.instruments.hemispherical import Hemispherical
from virtspec_mi.instruments.sphere import IntegratingSphere
from virtspec_mi.instruments.sphere.double import DoubleSphere
from virtspec_mi.instruments.hemispherical.allocated import Allocated, Allocation

__all__ = ["INSTRUMENTS", "ENTRY_POINTS", "ALLOCATING", "Allocation", "discovered", "commanding", "exported", "exports"]

ENTRY_POINTS = "virtspec_mi.instruments"
"""The entry-point group of outside instruments."""


def discovered(builtin: tuple[type[Instrument], ...]) -> dict[str, type[Instrument]]:
    """
    The instruments ``builtin`` and those of every installed package's entry point of
    :data:`ENTRY_POINTS`, by name (:func:`virtspec_mi.base.entry_points.discovered`: an entry
    point that cannot be loaded, is not an :class:`~virtspec_mi.instruments.base.Instrument`
    class or takes a name already taken is left out with a ``RuntimeWarning`` naming it).
    """

    return entry_point_rows(ENTRY_POINTS, builtin, Instrument)


INSTRUMENTS: dict[str, type[Instrument]] = discovered((Hemispherical, Goniophotometer, IntegratingSphere, GlossMeter,
                                                             DoubleSphere))
"""Every instrument by name (its ``name``): the built-in ones, then the outside ones (:data:`ENTRY_POINTS`)."""


ALLOCATING: type[Instrument] = Allocated
"""
The instrument that takes readings with rays allocated per wavelength (an
:class:`Allocation`: a derived quantity's Nₖ ∝ |wₖ|, a sequential target's next batch) —
the spectrophotometer's :class:`~virtspec_mi.instruments.hemispherical.allocated.Allocated`,
no row of its own (no subcommand): how an application finds it without naming it.
"""


def commanding(word: str) -> type[Instrument]:
    """
    The instrument of :data:`INSTRUMENTS` that has the subcommand ``word``, or whose
    subcommand's API function is ``word`` (``measure``, ``sweep``, ``gonio``,
    ``sphere_measure``, ``gloss`` …): how the API and the command line find the instrument
    behind one of their words without naming it. ``ValueError`` for any other word.
    """

    for instrument in INSTRUMENTS.values():
        if any(word in (command.name, command.function) for command in instrument.commands):
            return instrument
    words = sorted({w for i in INSTRUMENTS.values() for c in i.commands for w in (c.name, c.function) if w})
    raise ValueError(f"no instrument has the command or API function {word!r} (known: {', '.join(words)})")


def exported(name: str) -> Any:
    """
    The public name ``name`` that an instrument of :data:`INSTRUMENTS` exports at the top
    level (:attr:`~virtspec_mi.instruments.base.Instrument.exports`: ``vm.GonioResult``,
    ``vm.Sphere`` …), from its own module; ``AttributeError`` when none does.
    """

    for instrument in INSTRUMENTS.values():
        if name in instrument.exports:
            return getattr(sys.modules[instrument.__module__], name)
    raise AttributeError(name)


def exports() -> list[str]:
    """Every name the instruments of :data:`INSTRUMENTS` export at the top level."""

    return [name for instrument in INSTRUMENTS.values() for name in instrument.exports]
