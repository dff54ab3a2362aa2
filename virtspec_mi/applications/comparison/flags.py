"""
How to read a measured file, as flags: :class:`MeasuredFlags`
=============================================================

``--sample``, ``--measured-quantity``, ``--measured-scale``, ``--splice`` and
``--measured-format``: the fields of one :class:`~virtspec_mi.settings.Options` class that
every application command taking a measured file declares with its own flags (``virtspec
compare``, ``virtspec fit``); :func:`virtspec_mi.exchange.measured.flags.measured_from`
turns them into a :class:`~virtspec_mi.exchange.measured.base.MeasuredFile`.

References
----------
ASD Inc. (2017), *ASD File Format*, version 8 (the splices of its detectors).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from virtspec_mi.exchange.measured.base import MEASURED_QUANTITIES, SCALES
from virtspec_mi.settings import Options, one_of, option, text, true_or_false

__all__ = ["MeasuredFlags"]



_QUANTITIES = {quantity: f"the file holds a {quantity}" for quantity in MEASURED_QUANTITIES}
_SCALES = {scale: f"values in {'fractions 0-1' if factor == 1.0 else 'percent'}" for scale, factor in SCALES.items()}


@dataclass(frozen=True)
class MeasuredFlags(Options):
    """How a measured file is read when it does not tell (the module docstring)."""

    title: ClassVar[str] = "measured file"

    sample: str | None = option(None, text("sample"), "the spectrum of a measured file of many (its label, or its "
                                "0-based index)")
    measured_quantity: str | None = option(None, one_of("measured_quantity", _QUANTITIES),
                                           "what the measured file holds, when it does not tell (a file that tells "
                                           "is checked against it)", _QUANTITIES)
    measured_scale: str | None = option(None, one_of("measured_scale", _SCALES),
                                        "the scale of the measured values, when the file does not tell", _SCALES)
    splice: bool = option(False, true_or_false("splice"), "apply ASD's detector splice correction (ASD files only; "
                          "default: the data as they are)")
    measured_format: str | None = option(None, text("measured_format"), "the measured file's format when its "
                                         "suffix does not tell it (asd, sig, sed, jcamp, envi, table, or an outside "
                                         "package's)")
