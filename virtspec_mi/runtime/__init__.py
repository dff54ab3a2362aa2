"""
Runtime: libLLVM, Mitsuba variant and plugin registration in one place
======================================================================

Everything that touches Dr.Jit or Mitsuba goes through :func:`mitsuba`, which on its
first call

1. points Dr.Jit at a working libLLVM (:mod:`virtspec_mi.base.llvm`) and refuses a bad one,
2. selects the Mitsuba variant (``llvm_ad_spectral``; ``VIRTSPEC_VARIANT`` overrides it,
   e.g. ``cuda_ad_spectral`` on a GPU machine),
3. registers the specimens (:data:`virtspec_mi.plugins.SPECIMENS` and the outside
   packages' entry points of the group ``virtspec_mi.specimens``:
   :func:`virtspec_mi.plugins.specimen_rows`) and the project's other plugins
   (:data:`PLUGINS`) under that variant (:func:`register`), and lets ``mi.render`` raise the
   ``spectrophotometer`` integrator's ``ValueError`` (e.g. a bad ``spp``) as itself
   rather than wrapped in Dr.Jit's ``RuntimeError``
   (:func:`virtspec_mi.instruments.integrator.clear_render_errors`).

The plugins, one per file (``bsdfs/``: the specimens of :data:`virtspec_mi.plugins.SPECIMENS`,
:func:`specimens` lists them with the outside ones; the ``spectrophotometer`` integrator
and the ``virtspec_flipped`` BSDF of :data:`PLUGINS`):

======================  ===========  ===============================================
name                    kind         module (under :mod:`virtspec_mi.plugins`)
======================  ===========  ===============================================
``simple_dielectric``   BSDF         :mod:`.bsdfs.simple_dielectric`
``turbid_slab``         BSDF         :mod:`.bsdfs.turbid_slab`
``abm_b``               BSDF         :mod:`.bsdfs.abm_b` (walk: :mod:`.bsdfs.abm_walk`)
``abm_u``               BSDF         :mod:`.bsdfs.abm_u` (walk: :mod:`.bsdfs.abm_walk`)
``tabulated``           BSDF         :mod:`.bsdfs.tabulated` (a goniophotometer table)
``microfacet``          BSDF         :mod:`.bsdfs.microfacet` (the engines' albedo models)
``prospect_d``          BSDF         :mod:`.bsdfs.prospect_d` (model: :mod:`.bsdfs.prospect_model`)
``virtspec_flipped``    BSDF         :mod:`.bsdfs.flipped` (a BSDF turned over)
``spectrophotometer``   integrator   :mod:`virtspec_mi.instruments.integrator`
======================  ===========  ===============================================

and the integrators the instruments declare (:attr:`~virtspec_mi.instruments.base.Instrument.integrators`,
e.g. the integrating sphere's ``integrating_sphere``), registered with them.
"""

from __future__ import annotations

import os
from types import ModuleType

from virtspec_mi.base.llvm import check_loaded_llvm, select_libllvm

__all__ = ["DEFAULT_VARIANT", "PLUGINS", "mitsuba", "register", "variant", "specimens"]

DEFAULT_VARIANT: str = "llvm_ad_spectral"

PLUGINS: dict[str, tuple[str, str, str]] = {
    "virtspec_flipped": ("bsdf", "virtspec_mi.plugins.bsdfs.flipped", "FlippedBSDF"),
    "spectrophotometer": ("integrator", "virtspec_mi.instruments.integrator", "Spectrophotometer"),
}
"""The project's plugins beside the specimens and the instruments: Mitsuba name → (kind, module, class)."""

_registered: set[str] = set()


def variant() -> str:
    """The Mitsuba variant virtspec-mi runs on (``VIRTSPEC_VARIANT`` or ``llvm_ad_spectral``)."""

    return os.environ.get("VIRTSPEC_VARIANT", DEFAULT_VARIANT)


def mitsuba() -> ModuleType:
    """Return the ``mitsuba`` module, set up for virtspec-mi (idempotent)."""

    name = variant()
    if name in _registered:
        import mitsuba as mi

        if mi.variant() == name:
            return mi
    import virtspec_mi.base.interrupts as interrupts

    # Importing Dr.Jit and Mitsuba's variant (C extensions, about half a second) must not be cut by a
    # KeyboardInterrupt: it would come out as a SystemError or NameError and leave the modules half made; a
    # Ctrl-C waits for its end instead (the plugins' Python modules after it take a KeyboardInterrupt as any)
    with interrupts.deferred():
        if name.startswith("llvm"):
            select_libllvm()
            check_loaded_llvm()
        import mitsuba as mi

        if mi.variant() != name:
            mi.set_variant(name)
    if name not in _registered:
        from virtspec_mi.instruments.integrator import clear_render_errors

        register()
        mi.render = clear_render_errors(mi.render)
        _registered.add(name)
    return mi


def register() -> None:
    """
    Register every specimen (:func:`virtspec_mi.plugins.specimen_rows`: the project's and
    the outside packages' entry points), every plugin of :data:`PLUGINS`, and every
    integrator an instrument of the registry declares (``"module:Class"``), under the
    current Mitsuba variant. An outside specimen that cannot be loaded, or is no BSDF
    implementing the specimen protocol, is left out with a ``RuntimeWarning`` naming it.
    """

    import importlib
    import warnings

    import mitsuba as mi

    from virtspec_mi.instruments import INSTRUMENTS
    from virtspec_mi.plugins import SPECIMENS, load_specimen, specimen_rows

    registrars = {"bsdf": mi.register_bsdf, "integrator": mi.register_integrator}
    for name, row in specimen_rows().items():
        try:
            plugin = load_specimen(name, row)
        except Exception as error:
            if name in SPECIMENS:
                raise
            warnings.warn(f"specimen entry point {name!r} ({row}) could not be registered: {error}", RuntimeWarning,
                          stacklevel=2)
            continue
        mi.register_bsdf(name, lambda props, plugin=plugin: plugin(props))
    declared = {name: ("integrator", *target.split(":")) for instrument in INSTRUMENTS.values()
                for name, target in instrument.integrators.items()}
    for name, (kind, module, cls) in {**PLUGINS, **declared}.items():
        plugin = getattr(importlib.import_module(module), cls)
        registrars[kind](name, lambda props, plugin=plugin: plugin(props))


def specimens() -> dict[str, str]:
    """
    The specimens a scene can name (``{"type": NAME}``), the project's and those of the
    installed packages' entry points (``virtspec_mi.specimens``), each with the first line
    of its class's docstring: ``vm.specimens()``. Mitsuba is set up (the classes loaded).
    """

    from virtspec_mi.plugins import load_specimen, specimen_rows

    mitsuba()
    listed = {}
    for name, row in specimen_rows().items():
        try:
            plugin = load_specimen(name, row)
        except Exception:  # warned of when registered (mitsuba() above): not a specimen
            continue
        first = ((plugin.__doc__ or "").strip().splitlines() or [""])[0].strip()
        listed[name] = first.replace(" (see the module docstring)", "")
    return listed
