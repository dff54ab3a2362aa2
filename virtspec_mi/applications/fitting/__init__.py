"""
Fitting: a specimen's parameters from a measured spectrum
=========================================================

:func:`fit` inverts the instrument: the free parameters of a specimen (ABM-B/ABM-U's
pigments, PROSPECT-D's N, Cab, Car, Cw, Cm, a slab's μa and μs, a rough surface's α …)
whose certified forward spectrum matches a measured reflectance and/or transmittance,
with a confidence set and the parameters the data leave unconstrained
(:mod:`.inversion`); each parameter estimated on its optimal spectral window
(:mod:`.windows`, ``loss="windows"``); the forward readings on common random numbers, kept
for resuming (:mod:`.forward`); the inputs checked (:mod:`.problem`); the result, its files
and figures (:mod:`.result`); every spectrum of a file of many fitted, a table of fits
(:mod:`.samples`, on Dask workers); the ``virtspec fit`` command (:mod:`.command`).

References
----------
Féret et al. (2017), RSE 193:204–215; Jacquemoud & Baret (1990), RSE 34:75–91.
"""

from __future__ import annotations

import importlib
from typing import Any, ClassVar

from virtspec_mi.applications.base import Application
from virtspec_mi.applications.fitting.result import FitResult

__all__ = ["fit", "FitResult", "read_fit", "LOSSES", "fit_samples", "FitTable"]

_LAZY = {"fit": "inversion", "LOSSES": "inversion", "FitResult": "result", "read_fit": "result",
         "fit_samples": "samples", "FitTable": "samples"}
"""Where each name lives: imported on first use, so that ``virtspec``'s parser (which adds ``virtspec fit``
from :mod:`.command`) does not import SciPy's optimisers."""


class FittingApplication(Application):
    """Specimen parameters fitted to a measured spectrum: ``vm.fit``, ``virtspec fit``."""

    name: ClassVar[str] = "fitting"
    summary: ClassVar[str] = "specimen parameters fitted to a measured spectrum, with a confidence set"
    results: ClassVar[tuple[type, ...]] = (FitResult,)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
