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
and figures (:mod:`.result`); the ``virtspec fit`` command (:mod:`.command`), declared by
the application's row :class:`FittingApplication`.

References
----------
Féret et al. (2017), RSE 193:204–215; Jacquemoud & Baret (1990), RSE 34:75–91.
"""

from __future__ import annotations

import importlib
from typing import Any, ClassVar

from virtspec_mi.applications.base import Application, Command
from virtspec_mi.applications.fitting.command import FIT

__all__ = ["fit", "FitResult", "read_fit", "LOSSES", "FittingApplication"]

_LAZY = {"fit": "inversion", "LOSSES": "inversion", "FitResult": "result", "read_fit": "result"}
"""Where each name lives: imported on first use, so that ``virtspec``'s parser (which adds ``virtspec fit``
from :mod:`.command`) does not import SciPy's optimisers."""


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class FittingApplication(Application):
    """A specimen's parameters fitted to a measured spectrum: ``vm.fit``, ``virtspec fit``."""

    name: ClassVar[str] = "fitting"
    summary: ClassVar[str] = "a specimen's parameters fitted to a measured spectrum, with a confidence set"
    commands: ClassVar[tuple[Command, ...]] = (FIT,)
