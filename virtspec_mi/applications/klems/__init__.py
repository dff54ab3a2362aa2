"""
Certified Klems BSDF files (WINDOW 6 XML) measured by the goniophotometer
=========================================================================

- :mod:`~virtspec_mi.applications.klems.measure` — :func:`klems_measure`: the readings;
- :mod:`~virtspec_mi.applications.klems.matrices` — :class:`KlemsMeasurement`, its XML file,
  its sidecar and its certificate.
"""

from __future__ import annotations

from typing import ClassVar

from virtspec_mi.applications.base import Application, Extension
from virtspec_mi.applications.klems.matrices import KlemsMeasurement
from virtspec_mi.applications.klems.measure import KlemsFlags, respond

__all__ = ["KlemsApplication"]


class KlemsApplication(Application):
    """Certified Klems BSDF files: ``vm.klems_measure``, ``virtspec gonio --klems``."""

    name: ClassVar[str] = "klems"
    summary: ClassVar[str] = "certified Klems BSDF files (WINDOW 6 XML) from the goniophotometer"
    extensions: ClassVar[tuple[Extension, ...]] = (Extension("gonio", KlemsFlags, respond, "klems"),)
    results: ClassVar[tuple[type, ...]] = (KlemsMeasurement,)
