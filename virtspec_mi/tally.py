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

A fixed bound (``hoeffding``, ``chebyshev``, ``exact``, or explicit ``rays``) is one
batched call. ``two-stage`` is two: one batched pilot call over all readings (seed
``settings.seed``), then one batched call with each reading's own N₂ from its pilot
counts (:func:`virtspec_mi.twostage.stage_two_rays`), traced with the distinct seed
:func:`virtspec_mi.twostage.stage_two_seed` so its rays are fresh; only the second
call's counts form the tallies (the pilot's are kept in ``Tallies.pilot``).

References
----------
Baranoski et al. (2001), eqs. (2) and (23).
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
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
    (parts of ``reflected`` and ``transmitted``). ``pilot`` holds the two-stage pilot's
    own tallies (``None`` for a fixed bound); its rays are spent but form no estimate.
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
    pilot: "Tallies | None" = None

    @property
    def absorbed(self) -> np.ndarray:
        return self.rays - self.reflected - self.transmitted - self.capped

    def select(self, index: np.ndarray) -> "Tallies":
        """The tallies of readings ``index`` (repeats allowed), pilot included."""

        def pick(value: Any) -> Any:
            if isinstance(value, np.ndarray):
                return value[index]
            return value.select(index) if isinstance(value, Tallies) else value

        return replace(self, **{f.name: pick(getattr(self, f.name)) for f in fields(self)})

    @property
    def rays_spent(self) -> np.ndarray:
        """All rays traced per reading: the estimate's plus the pilot's."""

        return self.rays if self.pilot is None else self.rays + self.pilot.rays


def take_readings(
    instrument: Any,
    readings: Sequence[tuple[float, float, float]],
    settings: Settings,
    offsets: Sequence[int] | np.ndarray | None = None,
) -> Tallies:
    """
    Trace every (wavelength nm, θi, φi) of ``readings``, each with its own independent
    rays, and return their exact :class:`Tallies`.

    Each reading gets ``settings.rays_per_reading`` rays (eq. 23 by default), or, with
    ``bound="two-stage"``, a pilot batch and its own second batch (see above).
    ``offsets`` (optional) gives each reading's first global ray index, so that a
    reading's random numbers depend only on (seed, offset) and not on the other
    readings of the call (default: consecutive ranges of the traced readings; see
    :func:`~virtspec_mi.plugins.integrators.spectrophotometer.tally_readings`); both
    two-stage batches use the same offsets, with different seeds.

    When the specimen's BSDF has ``wavelength_independent = True``, readings with the
    same (θi, φi) are traced once — with the rays (offset) of the first of them in the
    list — and all report those counts.

    A specimen with a ``wavelength_range`` attribute refuses wavelengths outside it
    (``ValueError``).
    """

    bsdf = instrument.bsdf
    check_wavelength_range([r[0] for r in readings], getattr(bsdf, "wavelength_range", None),
                           getattr(bsdf, "PLUGIN", "") or type(bsdf).__name__)
    readings = [(float(w), float(t), float(p)) for w, t, p in readings]
    if offsets is not None and len(offsets) != len(readings):
        raise ValueError(f"offsets must hold one start per reading ({len(readings)}), got {len(offsets)}")
    shared = shares_wavelengths(instrument)
    if shared:
        first: dict[tuple[float, float], int] = {}
        source = np.array([first.setdefault((t, p), k) for k, (_, t, p) in enumerate(readings)], dtype=np.int64)
        traced = np.unique(source)
    else:
        source = traced = np.arange(len(readings))
    traced_readings = [readings[k] for k in traced]
    traced_offsets = None if offsets is None else np.asarray(offsets)[traced]
    if settings.adaptive:
        tallies = _two_stage(instrument, traced_readings, settings, traced_offsets)
    else:
        rays = np.full(len(traced), settings.rays_per_reading)
        tallies = _fixed(instrument, traced_readings, settings, rays, traced_offsets)
    if shared:
        tallies = tallies.select(np.searchsorted(traced, source))
    return replace(tallies, wavelength_independent=shared)


def shares_wavelengths(instrument: Any) -> bool:
    """True when the specimen's BSDF declares ``wavelength_independent = True``."""

    return bool(getattr(instrument.bsdf, "wavelength_independent", False))


def _fixed(instrument: Any, readings: Sequence[tuple[float, float, float]], settings: Settings,
           rays: np.ndarray, offsets: np.ndarray | None) -> Tallies:
    """One batched kernel call: reading i gets ``rays[i]`` rays from global index ``offsets[i]``."""

    from virtspec_mi.plugins.integrators.spectrophotometer import ReadingPlan, tally_readings

    plans = [ReadingPlan(w, t, p, int(n)) for (w, t, p), n in zip(readings, rays)]
    counts = tally_readings(instrument, plans, settings, offsets)
    return Tallies(np.asarray(rays, dtype=np.int64), *counts.T)


def _two_stage(instrument: Any, readings: Sequence[tuple[float, float, float]], settings: Settings,
               offsets: np.ndarray | None) -> Tallies:
    """Pilot batch, N₂ per reading from its counts, fresh second batch (two calls in all)."""

    from virtspec_mi import twostage

    pilot_rays = np.full(len(readings), settings.pilot_rays_per_reading)
    pilot = _fixed(instrument, readings, settings, pilot_rays, offsets)
    columns = [pilot.reflected, pilot.transmitted] + ([] if settings.joint else [pilot.absorbed])
    second = twostage.stage_two_rays(
        np.stack(columns, axis=1), settings.pilot_rays_per_reading, settings.mu, settings.delta,
        settings.pilot_delta_value, joint=settings.joint,
    )
    stage_two = settings.updated(seed=twostage.stage_two_seed(settings.seed))
    return replace(_fixed(instrument, readings, stage_two, second, offsets), pilot=pilot)
