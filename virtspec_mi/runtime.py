"""
Runtime: libLLVM, Mitsuba variant and plugin registration in one place
======================================================================

Everything that touches Dr.Jit or Mitsuba goes through :func:`mitsuba`, which on its
first call

1. points Dr.Jit at a working libLLVM (:mod:`virtspec_mi.llvm`) and refuses a bad one,
2. selects the Mitsuba variant (``llvm_ad_spectral``; ``VIRTSPEC_VARIANT`` overrides it,
   e.g. ``cuda_ad_spectral`` on a GPU machine),
3. registers the project's plugins (:mod:`virtspec_mi.plugins`) under that variant, and
   lets ``mi.render`` raise the ``spectrophotometer`` integrator's ``ValueError`` (e.g. a
   bad ``spp``) as itself rather than wrapped in Dr.Jit's ``RuntimeError``
   (:func:`virtspec_mi.plugins.integrators.spectrophotometer.clear_render_errors`).
"""

from __future__ import annotations

import os
from types import ModuleType

from virtspec_mi.llvm import check_loaded_llvm, select_libllvm

__all__ = ["DEFAULT_VARIANT", "mitsuba", "variant"]

DEFAULT_VARIANT: str = "llvm_ad_spectral"

_registered: set[str] = set()


def variant() -> str:
    """The Mitsuba variant virtspec-mi runs on (``VIRTSPEC_VARIANT`` or ``llvm_ad_spectral``)."""

    return os.environ.get("VIRTSPEC_VARIANT", DEFAULT_VARIANT)


def mitsuba() -> ModuleType:
    """Return the ``mitsuba`` module, set up for virtspec-mi (idempotent)."""

    name = variant()
    if name.startswith("llvm"):
        select_libllvm()
        check_loaded_llvm()
    import mitsuba as mi

    if mi.variant() != name:
        mi.set_variant(name)
    if name not in _registered:
        from virtspec_mi.plugins import register
        from virtspec_mi.plugins.integrators.spectrophotometer import clear_render_errors

        register()
        mi.render = clear_render_errors(mi.render)
        _registered.add(name)
    return mi
