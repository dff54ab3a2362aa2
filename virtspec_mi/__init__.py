"""
virtspec-mi: a virtual spectrophotometer built as Mitsuba 3 plugins
===================================================================

Certified reflectance / transmittance / absorptance readings of Mitsuba BSDFs
(Baranoski, Rokne & Xu 2001). Importing the package is cheap; the first use of a
Mitsuba-backed name (``measure``, ``sweep``, ``instrument_scene`` …) selects a
working libLLVM, the ``llvm_ad_spectral`` variant and registers the plugins.
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

__all__ = [
    "__version__",
    "measure",
    "sweep",
    "gonio",
    "read_result",
    "read_gonio",
    "GonioResult",
    "fluctuation",
    "sphere_measure",
    "Sphere",
    "Port",
    "Baffle",
    "SphereResult",
    "Result",
    "Settings",
    "InstrumentGeometry",
    "instrument_scene",
    "load_scene",
    "find_instrument",
    "tabulated_bsdf",
    "read_table",
    "hoeffding_rays",
    "chebyshev_rays",
    "hoeffding_mu",
    "chebyshev_mu",
    "BUDGETS",
    "mitsuba",
    "albedo_table",
]

_LAZY = {
    "measure": "virtspec_mi.api",
    "sweep": "virtspec_mi.api",
    "read_result": "virtspec_mi.api",
    "gonio": "virtspec_mi.api",
    "read_gonio": "virtspec_mi.api",
    "GonioResult": "virtspec_mi.gonio_result",
    "fluctuation": "virtspec_mi.api",
    "sphere_measure": "virtspec_mi.api",
    "Sphere": "virtspec_mi.sphere",
    "Port": "virtspec_mi.sphere",
    "Baffle": "virtspec_mi.sphere",
    "SphereResult": "virtspec_mi.sphere_readout",
    "Result": "virtspec_mi.result",
    "Settings": "virtspec_mi.settings",
    "InstrumentGeometry": "virtspec_mi.geometry",
    "instrument_scene": "virtspec_mi.scene",
    "load_scene": "virtspec_mi.scene",
    "find_instrument": "virtspec_mi.scene",
    "tabulated_bsdf": "virtspec_mi.scene",
    "read_table": "virtspec_mi.bsdf_table",
    "hoeffding_rays": "virtspec_mi.bounds",
    "chebyshev_rays": "virtspec_mi.bounds",
    "hoeffding_mu": "virtspec_mi.bounds",
    "chebyshev_mu": "virtspec_mi.bounds",
    "BUDGETS": "virtspec_mi.budgets",
    "mitsuba": "virtspec_mi.runtime",
    "albedo_table": "virtspec_mi.exchange.albedo",
}


def _prefer_working_libllvm() -> None:
    """Point Dr.Jit at a working libLLVM as early as possible (never raises at import)."""

    from virtspec_mi.llvm import LLVMError, select_libllvm

    try:
        select_libllvm()
    except LLVMError:
        pass  # reported with the fix when Mitsuba is first used (virtspec_mi.runtime)


_prefer_working_libllvm()


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'virtspec_mi' has no attribute {name!r}")
