"""
``SampledOnlyBSDF``: the base of specimens that exist only through ``sample()``
===============================================================================

The instrument's specimens (``simple_dielectric``, ``turbid_slab``, ``abm_b``,
``abm_u``) decide each ray's fate in ``sample()`` and have no evaluable density: every
lobe is either a delta or the outcome of a random walk. This base class gives them the
rest of Mitsuba's BSDF interface once: ``eval`` and ``pdf`` are zero. It is not a plugin
itself.

Parameters the Mitsuba way: a subclass lists its numeric parameters in
:meth:`SampledOnlyBSDF.exposed_parameters` (name → current value) and applies new ones
in :meth:`SampledOnlyBSDF.set_parameters` (its own range checks, ``ValueError``, then
its derived tables). :meth:`traverse` puts each as an opaque width-1 ``mi.Float64``
(``NonDifferentiable``: the specimens are sampled, never differentiated), so
``mi.traverse(scene)`` shows them as ``specimen.bsdf.NAME``; writing one and calling
``params.update()`` reaches :meth:`parameters_changed`, which hands the new values to
``set_parameters``. Float64 keeps a value exactly as given (a float32 would round
1.66e-4), so a specimen set through ``mi.traverse`` equals one loaded with that value.

References
----------
Mitsuba 3, ``mi.BSDF`` (Python BSDF plugins), ``mi.traverse`` / ``SceneParameters``.
"""

from __future__ import annotations

from typing import Any

import drjit as dr
import mitsuba as mi

from virtspec_mi.plugins.specimen import Parameter

__all__ = ["SampledOnlyBSDF"]


class SampledOnlyBSDF(mi.BSDF):
    """
    A ``mi.BSDF`` whose subclasses implement ``sample()`` only (see the module docstring),
    and the specimen protocol (:class:`~virtspec_mi.plugins.specimen.Specimen`) in its
    general case, which a subclass overrides where it knows more.
    """

    PLUGIN: str = ""
    """The plugin's name in scenes (messages name it; ``""``: its class name)."""
    PARAMETERS: tuple[Parameter, ...] = ()
    """Its numeric parameters with their bounds and units (:meth:`exposed_parameters` shows their values)."""
    wavelength_range: tuple[float, float] | None = None
    """The wavelengths (nm) its data cover; ``None``: any."""
    wavelength_independent: bool = False
    """``True``: readings that differ only in wavelength are one reading."""

    def check_wavelengths(self, wavelengths: Any) -> None:
        """Refuse wavelengths at which a spectral parameter is out of range (none here)."""

    def eval(self, ctx, si, wo, active=True):
        return mi.Spectrum(0.0)

    def pdf(self, ctx, si, wo, active=True):
        return mi.Float(0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return mi.Spectrum(0.0), mi.Float(0.0)

    def exposed_parameters(self) -> dict[str, float]:
        """The numeric parameters ``mi.traverse`` shows, by name, with their current values (none here)."""

        return {}

    def set_parameters(self, values: dict[str, float]) -> None:
        """Apply new values of exposed parameters (range checks first: ``ValueError`` naming the parameter)."""

        if values:
            raise ValueError(f"{type(self).__name__} has no parameter {sorted(values)[0]!r} to set")

    def traverse(self, callback: Any) -> None:
        self._exposed = {name: dr.opaque(mi.Float64, value) for name, value in self.exposed_parameters().items()}
        for name, value in self._exposed.items():
            callback.put(name, value, +mi.ParamFlags.NonDifferentiable)

    def parameters_changed(self, keys: Any = None) -> None:
        exposed = getattr(self, "_exposed", {})
        values = {}
        for name in keys or exposed:
            if name in exposed:
                value = exposed[name]
                if dr.width(value) != 1:
                    raise ValueError(f"{type(self).__name__}: '{name}' must be one number (got {dr.width(value)})")
                values[name] = float(value[0])
        self.set_parameters(values)
