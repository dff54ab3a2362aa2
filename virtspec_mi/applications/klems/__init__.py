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

from typing import Any, ClassVar

import numpy as np

from virtspec_mi.applications.base import Application, Command, Extension
from virtspec_mi.applications.klems.command import GONIO_KLEMS, KLEMS
from virtspec_mi.applications.klems.matrices import KlemsMeasurement

__all__ = ["KlemsApplication"]


def _api(folder: Any) -> Any:
    from virtspec_mi.applications.klems.measure import klems_measure

    return klems_measure("diamond_collimated", basis="quarter", rays=2000, isotropic=True, progress=False)


def _read(path: Any) -> Any:
    """The measurement of a Klems file (its sidecar: the XML's ``FILE.nc``), or of a sidecar."""

    from virtspec_mi.applications.klems.matrices import read_klems_sidecar, sidecar_path

    return read_klems_sidecar(sidecar_path(path) if str(path).endswith(".xml") else path)


class KlemsApplication(Application):
    """Certified Klems BSDF files: ``vm.klems_measure``, ``virtspec klems`` (alias ``virtspec gonio --klems``)."""

    name: ClassVar[str] = "klems"
    summary: ClassVar[str] = "certified Klems BSDF files (WINDOW 6 XML) from the goniophotometer"
    commands: ClassVar[tuple[Command, ...]] = (KLEMS,)
    extensions: ClassVar[tuple[Extension, ...]] = (GONIO_KLEMS,)
    results: ClassVar[tuple[type, ...]] = (KlemsMeasurement,)
    example: ClassVar[dict[str, Any]] = {
        "argv": ("klems", "diamond_collimated", "--out", "{tmp}/k.xml", "--basis", "quarter", "--rays", "2000",
                 "--isotropic", "--quiet"),
        "api": _api, "counts": lambda measured: np.ravel(measured.counts), "outputs": ("k.xml", "k.nc"),
        "read": _read, "formats": (".xml",),
        "resume": {"argv": ("klems", "diamond_collimated", "--out", "{tmp}/again.xml", "--basis", "quarter", "--rays",
                            "200000", "--quiet"), "checkpoint": "again.xml.parts", "out": "again.xml"}}
