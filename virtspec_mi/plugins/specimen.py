"""
The specimen protocol: what the instrument reads of a specimen's BSDF
=====================================================================

A specimen is a Mitsuba BSDF the instrument measures. Beyond Mitsuba's BSDF interface
the engine, the targets and the fit read three things of it, stated once here:

- its **wavelength range** (:attr:`Specimen.wavelength_range`): the wavelengths (nm) its
  data cover, ``None`` for any; readings outside it are refused before tracing, a target
  is fitted inside it, a fit's measured spectrum must lie inside it — with
  :meth:`Specimen.check_wavelengths`, which refuses wavelengths at which one of its
  spectral parameters is out of range (a ``turbid_slab``'s spectra);
- its **wavelength independence** (:attr:`Specimen.wavelength_independent`): ``True``
  when readings that differ only in wavelength are the same reading, so the engine
  traces them once (model only what is needed);
- its **parameters** (:attr:`Specimen.PARAMETERS`): each number ``mi.traverse`` shows,
  with its bounds and units (:class:`Parameter`), which a sweep or a fit varies.

:class:`Specimen` states them as a ``typing.Protocol``: a specimen's BSDF class (a
``mi.BSDF`` subclass: nanobind takes one base only, so the protocol is declared, not
inherited) declares the three and ``check_wavelengths`` itself — the project's
specimens (:mod:`virtspec_mi.plugins.bsdfs`, most of them through
:class:`~virtspec_mi.plugins.bsdfs.sampled_only.SampledOnlyBSDF`, which states the
general case: any wavelength, not wavelength-independent, no parameter) and an outside
package's leaf model alike (the entry-point group ``virtspec_mi.specimens``,
:data:`virtspec_mi.plugins.SPECIMENS`; :func:`missing` names what a class lacks).
:func:`specimen_of` reads any BSDF through the protocol: one of Mitsuba's own BSDFs
(``diffuse``, ``roughconductor`` …) declares none of it and reads as what is known of it
(any wavelength — the data range of each Mitsuba spectrum it holds is checked by
:func:`virtspec_mi.kernel.spectra.check_covered` — not wavelength-independent, so every
wavelength is traced, and no parameter declared: ``mi.traverse`` still shows its own).

References
----------
Mitsuba 3, "Custom plugins in Python" (``mi.BSDF`` subclasses, ``mi.register_bsdf``);
Python Packaging User Guide, "Entry points specification".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol, Sequence, runtime_checkable

__all__ = ["Specimen", "Parameter", "SpecimenView", "specimen_of", "missing", "MEMBERS"]


@dataclass(frozen=True)
class Parameter:
    """
    One numeric parameter of a specimen: its ``name`` (as ``mi.traverse`` shows it, short
    form), the ``lowest`` and ``highest`` values the model takes (``-inf``/``inf`` for none),
    its ``units`` (``"1"`` for a pure number) and what it ``means``.
    """

    name: str
    lowest: float
    highest: float
    units: str
    means: str = ""

    def within(self, value: float) -> bool:
        """Whether ``value`` lies in [lowest, highest] (the specimen's own check may be stricter at an end)."""

        return self.lowest <= float(value) <= self.highest

    def describe(self) -> str:
        """``Cab (ug/cm2, 0-150)`` as a message lists it."""

        bounds = "any" if math.isinf(self.lowest) and math.isinf(self.highest) else f"{self.lowest:g}-{self.highest:g}"
        return f"{self.name} ({self.units}, {bounds})"


@runtime_checkable
class Specimen(Protocol):
    """
    The protocol of a specimen's BSDF (see the module docstring). ``PLUGIN`` (its name in
    scenes, for messages) and ``walk_steps`` (a walk's mean events, a queueing hint for the
    kernel) are optional; the class declares the others, an instance may override a
    value (a table's range is its data's).
    """

    PARAMETERS: tuple[Parameter, ...]
    """Every numeric parameter ``mi.traverse`` shows, with its bounds and units."""

    wavelength_range: tuple[float, float] | None
    """The wavelengths (nm, lowest and highest) its data cover; ``None``: any."""

    wavelength_independent: bool
    """``True``: readings that differ only in wavelength are one reading (traced once)."""

    def check_wavelengths(self, wavelengths: Sequence[float]) -> None:
        """Refuse (``ValueError`` naming the parameter) wavelengths at which a spectral parameter is out of range."""


MEMBERS: tuple[str, ...] = ("PARAMETERS", "wavelength_range", "wavelength_independent", "check_wavelengths")
"""What a specimen's class declares (:class:`Specimen`)."""


def missing(plugin: Any) -> list[str]:
    """The members of :class:`Specimen` that ``plugin`` (a class or a BSDF) does not declare; ``[]`` when none."""

    return [name for name in MEMBERS if not hasattr(plugin, name)]


@dataclass(frozen=True)
class SpecimenView:
    """
    A BSDF read through the protocol (:func:`specimen_of`): its ``name`` in messages, its
    wavelength range, its independence flag, its parameters, its wavelength check.
    """

    name: str
    wavelength_range: tuple[float, float] | None
    wavelength_independent: bool
    parameters: tuple[Parameter, ...]
    bsdf: Any

    def check_wavelengths(self, wavelengths: Sequence[float]) -> None:
        """The specimen's own check (none for a BSDF outside the protocol)."""

        if not missing(self.bsdf):
            self.bsdf.check_wavelengths(wavelengths)

    def parameter(self, name: str) -> Parameter | None:
        """The declared parameter ``name`` (short form), or ``None``."""

        return next((p for p in self.parameters if p.name == name), None)


def specimen_of(bsdf: Any) -> SpecimenView:
    """
    ``bsdf`` read through the protocol: a :class:`Specimen` as it declares itself; any
    other BSDF (one of Mitsuba's own) as the defaults say — any wavelength, not
    wavelength-independent, no parameter declared.
    """

    if not missing(bsdf):
        span = bsdf.wavelength_range
        return SpecimenView(getattr(bsdf, "PLUGIN", "") or _class_name(bsdf),
                            None if span is None else (float(span[0]), float(span[1])),
                            bool(bsdf.wavelength_independent), tuple(bsdf.PARAMETERS), bsdf)
    return SpecimenView(_class_name(bsdf), None, False, (), bsdf)


def _class_name(bsdf: Any) -> str:
    return bsdf.class_name() if hasattr(bsdf, "class_name") else type(bsdf).__name__
