"""
Certified Klems BSDF files (WINDOW 6 XML) measured by the goniophotometer
=========================================================================

- :mod:`~virtspec_mi.applications.klems.measure` — :func:`klems_measure`: the readings;
- :mod:`~virtspec_mi.applications.klems.matrices` — :class:`KlemsMeasurement`, its XML file,
  its sidecar and its certificate;
- :mod:`~virtspec_mi.applications.klems.command` — ``virtspec klems SCENE`` and its alias
  ``virtspec gonio --klems FILE``, declared by the row :class:`KlemsApplication`.
"""

from __future__ import annotations

from typing import ClassVar

from virtspec_mi.applications.base import Application, Command, Extension
from virtspec_mi.applications.klems.command import GONIO_KLEMS, KLEMS

__all__ = ["KlemsApplication"]


class KlemsApplication(Application):
    """Certified Klems BSDF files: ``vm.klems_measure``, ``virtspec klems`` (alias ``virtspec gonio --klems``)."""

    name: ClassVar[str] = "klems"
    summary: ClassVar[str] = "certified Klems BSDF files (WINDOW 6 XML) from the goniophotometer"
    commands: ClassVar[tuple[Command, ...]] = (KLEMS,)
    extensions: ClassVar[tuple[Extension, ...]] = (GONIO_KLEMS,)
