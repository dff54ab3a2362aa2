"""
Instruments
===========

The instruments that measure a specimen through the engine, each one module with one
:class:`~virtspec_mi.instruments.base.Instrument` (its options, its plan, its result)
and one row of :data:`INSTRUMENTS`, the registry: the API and the command line pick an
instrument here by name.

- ``hemispherical``: the spectrophotometer (:func:`virtspec_mi.measure`, :func:`virtspec_mi.sweep`),
  :mod:`.hemispherical`;
- ``goniophotometer``: its readings binned by outgoing direction (:func:`virtspec_mi.gonio`),
  :mod:`.goniophotometer`;
- ``sphere``: a physical integrating sphere (:func:`virtspec_mi.sphere_measure`), :mod:`.sphere`;
- ``gloss``: a specular gloss meter, the example of a fourth instrument (one module, one
  row), :mod:`.gloss`.
"""

from __future__ import annotations

from virtspec_mi.instruments.base import Instrument
from virtspec_mi.instruments.gloss import GlossMeter
from virtspec_mi.instruments.goniophotometer import Goniophotometer
from virtspec_mi.instruments.hemispherical import Hemispherical
from virtspec_mi.instruments.sphere import IntegratingSphere

__all__ = ["INSTRUMENTS"]

INSTRUMENTS: dict[str, type[Instrument]] = {
    instrument.name: instrument for instrument in (Hemispherical, Goniophotometer, IntegratingSphere, GlossMeter)
}
"""Every instrument by name (its ``name``): the API's and the command line's one registry."""
