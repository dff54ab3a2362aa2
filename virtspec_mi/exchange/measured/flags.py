"""
The command-line flags that say how to read a measured file
===========================================================

``--sample``, ``--measured-quantity``, ``--measured-scale``, ``--splice`` and
``--measured-format``: added once (:func:`add_measured_flags`) to every command that takes
a measured file (``virtspec compare``, ``plot --against``, ``fit``) and turned into a
:class:`~virtspec_mi.exchange.measured.base.MeasuredFile` by :func:`measured_from`.

References
----------
ASD Inc. (2017), *ASD File Format*, version 8 (the splices of its detectors).
"""

from __future__ import annotations

import argparse
from typing import Any

from virtspec_mi.exchange.measured.base import MEASURED_QUANTITIES, SCALES, MeasuredFile

__all__ = ["add_measured_flags", "measured_from"]


def add_measured_flags(parser: argparse.ArgumentParser) -> None:
    """Add the flags of the module docstring to ``parser``."""

    parser.add_argument("--sample", help="the spectrum of a measured file of many (its label, or its 0-based index)")
    parser.add_argument("--measured-quantity", choices=MEASURED_QUANTITIES,
                        help="what the measured file holds, when it does not tell (a file that tells is checked "
                             "against it)")
    parser.add_argument("--measured-scale", choices=tuple(SCALES),
                        help="the scale of the measured values, when the file does not tell (fraction or percent)")
    parser.add_argument("--splice", action="store_true",
                        help="apply ASD's detector splice correction (ASD files only; default: the data as they are)")
    parser.add_argument("--measured-format", help="the measured file's format when its suffix does not tell it "
                                                  "(asd, sig, sed, jcamp, envi, table, or an outside package's)")


def measured_from(args: argparse.Namespace, path: Any) -> Any:
    """``path`` as it is when no flag of the module is given, else a :class:`MeasuredFile` of it with them."""

    sample = getattr(args, "sample", None)
    options = {"sample": int(sample) if sample is not None and sample.isdigit() else sample,
               "quantity": getattr(args, "measured_quantity", None), "scale": getattr(args, "measured_scale", None),
               "splice": bool(getattr(args, "splice", False)), "format": getattr(args, "measured_format", None)}
    if path is None or not any(options.values()):
        return path
    return MeasuredFile(path, **options)
