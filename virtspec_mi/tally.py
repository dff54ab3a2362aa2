"""
From requested readings to exact counts
=======================================

:func:`take_readings` is the one path from a list of readings — each a
(wavelength, θi, φi) — to exact ray counts: it sizes every reading with the ray
budget of the settings and traces all of them through the ``spectrophotometer``
kernel in as few launches as memory allows (chunks of ``settings.chunk_size`` rays
that may span many readings). :func:`virtspec_mi.measure` and sweeps both use it.

Model only what is needed: a specimen whose BSDF declares
``wavelength_independent = True`` (e.g. ``simple_dielectric``) is traced once per
incidence (θi, φi); readings that differ only in wavelength share those rays and
counts (:attr:`Tallies.wavelength_independent` says so).

References
----------
Baranoski et al. (2001), eqs. (2) and (23).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from virtspec_mi.settings import Settings, check_wavelength_range

__all__ = ["Tallies", "take_readings", "shares_wavelengths"]


@dataclass(frozen=True)
class Tallies:
    """
    Exact counts of a list of readings (one entry per reading, ``int64``).

    ``absorbed = rays − reflected − transmitted − capped``. ``specular`` and ``regular``
    count the reflected and the transmitted rays whose sampled event was a delta event
    (parts of ``reflected`` and ``transmitted``).
    """

    rays: np.ndarray
    reflected: np.ndarray
    transmitted: np.ndarray
    weight_violations: np.ndarray
    capped: np.ndarray
    specular: np.ndarray | None = None
    regular: np.ndarray | None = None
    wavelength_independent: bool = False
    """True when readings differing only in wavelength share one traced set of rays."""

    @property
    def absorbed(self) -> np.ndarray:
        return self.rays - self.reflected - self.transmitted - self.capped


def take_readings(
    instrument: Any,
    readings: Sequence[tuple[float, float, float]],
    settings: Settings,
    offsets: Sequence[int] | np.ndarray | None = None,
) -> Tallies:
    """
    Trace every (wavelength nm, θi, φi) of ``readings``, each with its own independent
    rays, and return their exact :class:`Tallies`.

    Each reading gets ``settings.rays_per_reading`` rays (eq. 23 by default).
    ``offsets`` (optional) gives each reading's first global ray index, so that a
    reading's random numbers depend only on (seed, offset) and not on the other
    readings of the call (default: consecutive ranges of the traced readings; see
    :func:`~virtspec_mi.plugins.integrators.spectrophotometer.tally_readings`).

    When the specimen's BSDF has ``wavelength_independent = True``, readings with the
    same (θi, φi) are traced once — with the rays (offset) of the first of them in the
    list — and all report those counts.

    A specimen with a ``wavelength_range`` attribute refuses wavelengths outside it
    (``ValueError``).
    """

    bsdf = instrument.bsdf
    check_wavelength_range([r[0] for r in readings], getattr(bsdf, "wavelength_range", None),
                           getattr(bsdf, "PLUGIN", "") or type(bsdf).__name__)

    from virtspec_mi.plugins.integrators.spectrophotometer import ReadingPlan, tally_readings

    n = settings.rays_per_reading
    readings = [(float(w), float(t), float(p)) for w, t, p in readings]
    shared = shares_wavelengths(instrument)
    if shared:
        first: dict[tuple[float, float], int] = {}
        source = np.array([first.setdefault((t, p), k) for k, (_, t, p) in enumerate(readings)], dtype=np.int64)
        traced = np.unique(source)
    else:
        source = traced = np.arange(len(readings))
    plans = [ReadingPlan(*readings[k], n) for k in traced]
    if offsets is not None and len(offsets) != len(readings):
        raise ValueError(f"offsets must hold one start per reading ({len(readings)}), got {len(offsets)}")
    chosen = None if offsets is None else np.asarray(offsets)[traced]
    counts = tally_readings(instrument, plans, settings, chosen)
    if shared:
        counts = counts[np.searchsorted(traced, source)]
    return Tallies(np.full(len(readings), n, dtype=np.int64), *counts.T, wavelength_independent=shared)


def shares_wavelengths(instrument: Any) -> bool:
    """True when the specimen's BSDF declares ``wavelength_independent = True``."""

    return bool(getattr(instrument.bsdf, "wavelength_independent", False))
