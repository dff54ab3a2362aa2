"""
virtspec-mi: a virtual spectrophotometer built as Mitsuba 3 plugins
===================================================================

Certified reflectance / transmittance / absorptance readings of Mitsuba BSDFs
(Baranoski, Rokne & Xu 2001). Importing the package is cheap; the first use of a
Mitsuba-backed name (``measure``, ``sweep``, ``instrument_scene`` …) selects a
working libLLVM, the ``llvm_ad_spectral`` variant and registers the plugins.
"""

from __future__ import annotations

import sys as _sys

if _sys.argv[:1] == ["-m"] or _sys.argv[0].replace("\\", "/").rsplit("/", 1)[-1] in ("virtspec", "virtspec.exe"):
    # The virtspec command (python -m virtspec_mi, its console script): Ctrl-C taken from the package's first line,
    # before any import (virtspec_mi.base.interrupts.stop_now, written here with what Python has already loaded):
    # never Python's traceback, nor a KeyboardInterrupt swallowed inside an import lock's callback.
    import os as _os
    import signal as _signal

    def _stop_now(signum: int, frame: Any) -> None:
        _os.write(2, b"virtspec: interrupted\n" if signum == _signal.SIGINT else b"virtspec: terminated by SIGTERM\n")
        _os._exit(128 + signum)

    for _signum in (_signal.SIGINT, _signal.SIGTERM):
        _signal.signal(_signum, _stop_now)

import importlib
from typing import Any

from virtspec_mi.base.version import __version__  # noqa: E402  (one place: base.version)

_OWN: tuple[str, ...] = ("__version__", "scenes")
"""The root's own names beside the lazy ones (the version, the shipped scenes' module)."""

_LAZY = {
    "measure": "virtspec_mi.api",
    "sweep": "virtspec_mi.api",
    "read_result": "virtspec_mi.api",
    "gonio": "virtspec_mi.api",
    "read_gonio": "virtspec_mi.api",
    "fluctuation": "virtspec_mi.results.readings",
    "sphere_measure": "virtspec_mi.api",
    "take": "virtspec_mi.api",
    "Result": "virtspec_mi.results.readings",
    "Settings": "virtspec_mi.settings",
    "INSTRUMENTS": "virtspec_mi.instruments",
    "InstrumentGeometry": "virtspec_mi.geometry.disks",
    "instrument_scene": "virtspec_mi.runtime.scene",
    "load_scene": "virtspec_mi.runtime.scene",
    "find_bench": "virtspec_mi.runtime.scene",
    "tabulated_bsdf": "virtspec_mi.runtime.scene",
    "read_table": "virtspec_mi.plugins.bsdfs.bsdf_table",
    "hoeffding_rays": "virtspec_mi.budgets.bounds",
    "chebyshev_rays": "virtspec_mi.budgets.bounds",
    "hoeffding_mu": "virtspec_mi.budgets.bounds",
    "chebyshev_mu": "virtspec_mi.budgets.bounds",
    "BUDGETS": "virtspec_mi.budgets.rules",
    "mitsuba": "virtspec_mi.runtime",
    "specimens": "virtspec_mi.runtime",
    "albedo_table": "virtspec_mi.applications.tables.albedo",
    "read_albedo_table": "virtspec_mi.applications.tables.table",
    "AlbedoTable": "virtspec_mi.applications.tables.table",
    "TableComparison": "virtspec_mi.applications.tables.table",
    "KlemsMeasurement": "virtspec_mi.applications.klems.matrices",
    "write_klems": "virtspec_mi.applications.klems.matrices",
    "compare": "virtspec_mi.applications.comparison",
    "read_measured": "virtspec_mi.applications.comparison",
    "Comparison": "virtspec_mi.applications.comparison",
    "MeasuredSpectrum": "virtspec_mi.applications.comparison",
    "MeasuredFile": "virtspec_mi.exchange.measured",
    "read_samples": "virtspec_mi.exchange.measured",
    "colour_difference": "virtspec_mi.applications.targets.difference",
    "DerivedResult": "virtspec_mi.applications.targets.result",
    "DerivedSweep": "virtspec_mi.applications.targets.result",
    "fit": "virtspec_mi.applications.fitting",
    "read_fit": "virtspec_mi.applications.fitting",
    "FitResult": "virtspec_mi.applications.fitting",
    "fit_samples": "virtspec_mi.applications.fitting",
    "FitTable": "virtspec_mi.applications.fitting",
}


def _prefer_working_libllvm() -> None:
    """Point Dr.Jit at a working libLLVM as early as possible (never raises at import)."""

    from virtspec_mi.base.llvm import LLVMError, select_libllvm

    try:
        select_libllvm()
    except LLVMError:
        pass  # reported with the fix when Mitsuba is first used (virtspec_mi.runtime)


_prefer_working_libllvm()


from virtspec_mi import scenes  # noqa: E402  (the shipped scenes by name: paths only, no Mitsuba)


_ROWS = {"take": "virtspec_mi.api", "INSTRUMENTS": "virtspec_mi.instruments",
         "TARGETS": "virtspec_mi.applications.targets.targets"}
"""Where the tables whose rows export names are: the API's generated functions, the instruments, the targets."""


def _table(name: str) -> Any:
    return importlib.import_module(_ROWS[name])


def _rows() -> list[str]:
    """The names the tables' rows export: each instrument's ``exports``, each target's constructor (``vm.colour``)."""

    return [*_table("INSTRUMENTS").exports(), *_table("TARGETS").TARGETS]


def __dir__() -> list[str]:
    """The public names (lazy ones included, and the API functions generated from the registry)."""

    return sorted({*_public(), *_table("take").aliases()})


def _public() -> list[str]:
    """``__all__``: the root's own names, the lazy ones, and those the rows export (not a hand-kept list)."""

    return list(dict.fromkeys([*_OWN, *_LAZY, *_rows()]))


def __getattr__(name: str) -> Any:
    if name == "__all__":  # built from the tables on each access (a row added at run time is listed)
        return _public()
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    if not name.startswith("_"):  # an instrument's subcommand without a function of its own: generated (vm.gloss)
        api = _table("take")  # the API, resolved on access as every lazy name
        if name in api.aliases():
            return api.alias(name)
        instruments = _table("INSTRUMENTS")  # the registry, as the lazy INSTRUMENTS
        if name in instruments.exports():  # an instrument's own public names (vm.GonioResult, vm.Sphere …)
            return instruments.exported(name)
        targets = _table("TARGETS").TARGETS  # a target's constructor (vm.colour, vm.band …): its row of TARGETS
        if name in targets:
            return targets[name].make
    raise AttributeError(f"module 'virtspec_mi' has no attribute {name!r}")
