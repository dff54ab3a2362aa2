"""
Spectral data ranges: the wavelengths a Mitsuba object's spectra hold data for
==============================================================================

A Mitsuba spectrum holds data over a range of wavelengths and reads something else
beyond it, without a word:

- a ``regular`` spectrum (its ``range``: ``wavelength_min`` … ``wavelength_max``, e.g.
  ``d65``) and an ``irregular`` one (its ``wavelengths``, e.g. a ``conductor``'s
  tabulated η and k of a named ``material``) read 0;
- an RGB colour (``rgb``/``srgb`` textures, RGB ``bitmap`` textures) is a spectrum
  upsampled from three numbers over Mitsuba's CIE range ``mi.MI_CIE_MIN`` …
  ``mi.MI_CIE_MAX`` (360–830 nm) and extrapolated beyond it; a ``blackbody`` reads 0
  beyond that range.

A reading at such a wavelength measures no data of the specimen, so it must not be
certified: :func:`data_ranges` lists every spectrum of an object — a BSDF with its
nested textures and BSDFs, as ``mi.traverse`` finds them, or one texture — with its
range, and :func:`check_covered` refuses (``ValueError``) wavelengths outside any of
them, naming the parameter and its range. Uniform spectra and plain numbers hold at
every wavelength; the project's own plugins declare their data range themselves
(``wavelength_range``, ``check_wavelengths``).

References
----------
Mitsuba 3 documentation, "Spectra" (``regular``, ``irregular``, ``srgb``, ``blackbody``)
and "Textures" (``bitmap``); W. Jakob, J. Hanika (2019), *A low-dimensional function
space for efficient spectral upsampling*, Computer Graphics Forum 38(2) (the RGB model).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable

import numpy as np

__all__ = ["DataRange", "data_ranges", "check_covered"]

_CIE_KINDS: dict[str, str] = {
    "SRGBReflectanceSpectrum": "an RGB colour, upsampled over Mitsuba's CIE range",
    "SRGBEmitterSpectrum": "an RGB colour, upsampled over Mitsuba's CIE range",
    "BlackBodySpectrum": "a blackbody, 0 outside Mitsuba's CIE range",
}


@dataclass(frozen=True)
class DataRange:
    """One spectrum of an object: its parameter (``mi.traverse`` key prefix), range (nm) and kind in words."""

    parameter: str
    low: float
    high: float
    kind: str


def data_ranges(obj: Any) -> list[DataRange]:
    """
    Every spectrum of ``obj`` (a Mitsuba BSDF or texture) that holds data over a limited
    range of wavelengths, with that range (see the module docstring); ``[]`` when none.
    """

    import mitsuba as mi

    params = mi.traverse(obj)
    nodes: dict[int, tuple[str, Any, dict[str, str]]] = {}
    for key in params.keys():
        node = params.properties[key][2]
        prefix, _, leaf = key.rpartition(".")
        nodes.setdefault(id(node), (prefix, node, {}))[2][leaf] = key
    cie = (float(mi.MI_CIE_MIN), float(mi.MI_CIE_MAX))
    out = []
    for prefix, node, leaves in nodes.values():
        kind = node.class_name() if hasattr(node, "class_name") else type(node).__name__
        if kind == "RegularSpectrum" and "range" in leaves:
            low, high = (float(v) for v in np.ravel(np.array(params[leaves["range"]], dtype=np.float64))[:2])
            words = "a regular spectrum, 0 outside its range"
        elif kind == "IrregularSpectrum" and "wavelengths" in leaves:
            grid = np.array(params[leaves["wavelengths"]], dtype=np.float64)
            low, high, words = float(grid.min()), float(grid.max()), "an irregular spectrum, 0 outside its data"
        elif kind in _CIE_KINDS:
            (low, high), words = cie, _CIE_KINDS[kind]
        elif kind.startswith("BitmapTexture") and "data" in leaves and np.shape(params[leaves["data"]])[-1] == 3:
            (low, high), words = cie, "an RGB bitmap, upsampled over Mitsuba's CIE range"
        else:
            continue
        out.append(DataRange(prefix, low, high, words))
    return out


def check_covered(obj: Any, wavelengths: Iterable[float], owner: str, name: str | None = None) -> None:
    """
    Refuse ``wavelengths`` (nm) outside the range of any spectrum of ``obj``
    (:func:`data_ranges`) with a ``ValueError`` naming ``owner`` (e.g. ``"the specimen
    SmoothConductor"``), the parameter (``name`` for a lone texture) and its range.
    """

    values = [float(w) for w in wavelengths]
    for item in data_ranges(obj):
        outside = [w for w in values if not item.low <= w <= item.high]
        if outside:
            parameter = name if not item.parameter else item.parameter if name is None else f"{name}.{item.parameter}"
            shown = ", ".join(map(_shown, outside[:5])) + (" ..." if len(outside) > 5 else "")
            raise ValueError(f"wavelengths must satisfy {item.low:g} <= wavelength <= {item.high:g} nm for "
                             f"{owner}: its {parameter!r} is {item.kind} (got {shown})")


def _shown(value: float) -> str:
    """A wavelength with every digit it was given (``399.99999999``), a whole one without ``.0``."""

    return str(int(value)) if value.is_integer() and abs(value) < 1e16 else repr(value)
