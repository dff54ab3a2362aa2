"""
virtspec-mi's Mitsuba plugins
=============================

One plugin per file: ``bsdfs/`` holds specimens, ``integrators/`` the instrument.
:func:`register` registers them all under the current Mitsuba variant; call it
through :func:`virtspec_mi.runtime.mitsuba`, which sets the variant first.

=====================  ===========  ==========================================
name                   kind         module
=====================  ===========  ==========================================
``simple_dielectric``  BSDF         :mod:`.bsdfs.simple_dielectric`
``turbid_slab``        BSDF         :mod:`.bsdfs.turbid_slab`
``abm_b``              BSDF         :mod:`.bsdfs.abm_b` (walk: :mod:`.bsdfs.abm_walk`)
``abm_u``              BSDF         :mod:`.bsdfs.abm_u` (walk: :mod:`.bsdfs.abm_walk`)
``tabulated``          BSDF         :mod:`.bsdfs.tabulated` (a goniophotometer table)
``spectrophotometer``  integrator   :mod:`.integrators.spectrophotometer`
``integrating_sphere`` integrator   :mod:`.integrators.integrating_sphere`
=====================  ===========  ==========================================
"""

from __future__ import annotations

__all__ = ["PLUGINS", "register"]

PLUGINS: dict[str, tuple[str, str, str]] = {
    "simple_dielectric": ("bsdf", ".bsdfs.simple_dielectric", "SimpleDielectric"),
    "turbid_slab": ("bsdf", ".bsdfs.turbid_slab", "TurbidSlab"),
    "abm_b": ("bsdf", ".bsdfs.abm_b", "ABMB"),
    "abm_u": ("bsdf", ".bsdfs.abm_u", "ABMU"),
    "tabulated": ("bsdf", ".bsdfs.tabulated", "Tabulated"),
    "spectrophotometer": ("integrator", ".integrators.spectrophotometer", "Spectrophotometer"),
    "integrating_sphere": ("integrator", ".integrators.integrating_sphere", "IntegratingSphere"),
}


def register() -> None:
    """Register every plugin of :data:`PLUGINS` under the current Mitsuba variant."""

    import importlib

    import mitsuba as mi

    registrars = {"bsdf": mi.register_bsdf, "integrator": mi.register_integrator}
    for name, (kind, module, cls) in PLUGINS.items():
        plugin = getattr(importlib.import_module(module, __name__), cls)
        registrars[kind](name, lambda props, plugin=plugin: plugin(props))
