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
(:mod:`.samples`, on Dask workers); the ``virtspec fit`` command (:mod:`.command`), declared by
the application's row :class:`FittingApplication`.

References
----------
Féret et al. (2017), RSE 193:204–215; Jacquemoud & Baret (1990), RSE 34:75–91.
"""

from __future__ import annotations

import importlib
from typing import Any, ClassVar

import numpy as np

from virtspec_mi.applications.base import Application, Command
from virtspec_mi.applications.fitting.command import FIT
from virtspec_mi.applications.fitting.result import FitResult

__all__ = ["fit", "FitResult", "read_fit", "LOSSES", "fit_samples", "FitTable", "FittingApplication"]

_LAZY = {"fit": "inversion", "LOSSES": "inversion", "read_fit": "result", "fit_samples": "samples",
         "FitTable": "samples"}
"""Where each name lives: imported on first use, so that ``virtspec``'s parser (which adds ``virtspec fit``
from :mod:`.command`) does not import SciPy's optimisers."""


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


_FIT = ("--specimen", "prospect_d", "--free", "Cab=10:80", "--theta-i", "8", "--beam", "collimated", "--delta",
        "0.2", "--table-points", "3", "--profile-points", "0")


def _inputs(folder: Any) -> None:
    """The example's measured reflectance (a leaf's, at four wavelengths, ±0.03)."""

    from pathlib import Path

    Path(folder, "leaf.csv").write_text("wavelength,value,uncertainty\n500,0.07,0.03\n560,0.12,0.03\n"
                                        "650,0.06,0.03\n800,0.45,0.03\n")


def _api(folder: Any) -> Any:
    from pathlib import Path

    from virtspec_mi.applications.fitting.inversion import fit

    return fit(Path(folder, "leaf.csv"), "prospect_d", {"Cab": (10.0, 80.0)}, quantities=("reflectance",),
               theta_i=8.0, beam="collimated", delta=0.2, table_points=3, profile_points=0)


def _read(path: Any) -> Any:
    from virtspec_mi.applications.fitting.result import read_fit

    return read_fit(path)


class FittingApplication(Application):
    """A specimen's parameters fitted to a measured spectrum: ``vm.fit``, ``virtspec fit``."""

    name: ClassVar[str] = "fitting"
    summary: ClassVar[str] = "a specimen's parameters fitted to a measured spectrum, with a confidence set"
    commands: ClassVar[tuple[Command, ...]] = (FIT,)
    results: ClassVar[tuple[type, ...]] = (FitResult,)
    example: ClassVar[dict[str, Any]] = {
        "argv": ("fit", "{tmp}/leaf.csv", *_FIT, "--out", "{tmp}/fit.nc"), "inputs": _inputs, "api": _api,
        "counts": lambda result: np.concatenate([np.ravel(result.estimate), np.ravel(result.intervals), [result.rays]]),
        "outputs": ("fit.nc",), "read": _read, "formats": (".json", ".nc"),
        "resume": {"argv": ("fit", "{tmp}/leaf.csv", *_FIT, "--directory", "{tmp}/work", "--out", "{tmp}/again.nc"),
                   "checkpoint": "work/readings", "out": "again.nc"},
        "workers": True}
