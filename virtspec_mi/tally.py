"""
From requested readings to exact counts
=======================================

:func:`take_readings` is the one path from a list of readings — each a
(wavelength, θi, φi) — to exact ray counts: it sizes every reading with the ray
budget of the settings and traces all of them through the ``spectrophotometer``
kernel in as few launches as memory allows (chunks of ``settings.chunk_size`` rays
that may span many readings). :func:`virtspec_mi.measure` and sweeps both use it.

References
----------
Baranoski et al. (2001), eqs. (2) and (23).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from virtspec_mi.settings import Settings, check_wavelength_range

__all__ = ["Tallies", "take_readings"]


@dataclass(frozen=True)
class Tallies:
    """
    Exact counts of a list of readings (one entry per reading, ``int64``).

    ``absorbed = rays − reflected − transmitted − capped``.
    """

    rays: np.ndarray
    reflected: np.ndarray
    transmitted: np.ndarray
    weight_violations: np.ndarray
    capped: np.ndarray

    @property
    def absorbed(self) -> np.ndarray:
        return self.rays - self.reflected - self.transmitted - self.capped


def take_readings(
    instrument: Any,
    readings: Sequence[tuple[float, float, float]],
    settings: Settings,
) -> Tallies:
    """
    Trace every (wavelength nm, θi, φi) of ``readings``, each with its own independent
    rays, and return their exact :class:`Tallies`.

    Each reading gets ``settings.rays_per_reading`` rays (eq. 23 by default). A specimen
    with a ``wavelength_range`` attribute refuses wavelengths outside it (``ValueError``).
    """

    bsdf = instrument.bsdf
    check_wavelength_range([r[0] for r in readings], getattr(bsdf, "wavelength_range", None),
                           getattr(bsdf, "PLUGIN", "") or type(bsdf).__name__)

    from virtspec_mi.plugins.integrators.spectrophotometer import ReadingPlan, tally_readings

    n = settings.rays_per_reading
    plans = [ReadingPlan(float(w), float(t), float(p), n) for w, t, p in readings]
    counts = tally_readings(instrument, plans, settings)
    return Tallies(np.full(len(plans), n, dtype=np.int64), *counts.T)
