"""
A dark Lambertian reflector (albedo 3–8 %) whose every band is known exactly, and a
recorder of the traces a target's route makes: shared by the target route tests.
"""

from __future__ import annotations

import numpy as np

DARK = [0.03, 0.05, 0.08, 0.04]
"""The reflector's albedo at evenly spaced wavelengths over 300–1000 nm (linear in between)."""


def dark_scene():
    import virtspec_mi as vm

    return vm.instrument_scene({"type": "diffuse", "reflectance": {
        "type": "regular", "wavelength_min": 300, "wavelength_max": 1000, "values": ", ".join(map(str, DARK))}})


def exact(functional) -> float:
    """The functional's exact value on the reflector."""

    return functional.value(np.interp(functional.wavelengths, np.linspace(300, 1000, len(DARK)), DARK))


def recorded_traces(monkeypatch) -> list:
    """Every allocated trace from now on, as (seed, wavelengths, rays, offsets), in order."""

    import virtspec_mi.instruments.hemispherical.allocated as allocated

    calls = []
    original = allocated.trace_allocated

    def recording(bench, settings, readings, rays, offsets=None):
        calls.append((settings.seed, [r[0] for r in readings], np.asarray(rays), np.asarray(offsets)))
        return original(bench, settings, readings, rays, offsets=offsets)

    monkeypatch.setattr(allocated, "trace_allocated", recording)
    return calls
