"""
From requested readings to exact counts
=======================================

:func:`take_readings` is the one path from a list of readings — each a
(wavelength, θi, φi) — to exact ray counts: it sizes every reading with the ray
budget of the settings and traces all of them through the ``spectrophotometer``
kernel in as few launches as memory allows (chunks of ``settings.chunk_size`` rays
that may span many readings). :func:`virtspec_mi.measure` and sweeps both use it.

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

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from virtspec_mi.settings import Settings

__all__ = ["Tallies", "take_readings"]


@dataclass(frozen=True)
class Tallies:
    """
    Exact counts of a list of readings (one entry per reading, ``int64``).

    ``absorbed = rays − reflected − transmitted − capped``. ``pilot`` holds the
    two-stage pilot's own tallies (``None`` for a fixed bound); its rays are spent
    but form no estimate.
    """

    rays: np.ndarray
    reflected: np.ndarray
    transmitted: np.ndarray
    weight_violations: np.ndarray
    capped: np.ndarray
    pilot: "Tallies | None" = None

    @property
    def absorbed(self) -> np.ndarray:
        return self.rays - self.reflected - self.transmitted - self.capped

    @property
    def rays_spent(self) -> np.ndarray:
        """All rays traced per reading: the estimate's plus the pilot's."""

        return self.rays if self.pilot is None else self.rays + self.pilot.rays


def take_readings(
    instrument: Any,
    readings: Sequence[tuple[float, float, float]],
    settings: Settings,
) -> Tallies:
    """
    Trace every (wavelength nm, θi, φi) of ``readings``, each with its own independent
    rays, and return their exact :class:`Tallies`.

    Each reading gets ``settings.rays_per_reading`` rays (eq. 23 by default), or, with
    ``bound="two-stage"``, a pilot batch and its own second batch (see above).
    """

    if settings.adaptive:
        return _two_stage(instrument, readings, settings)
    return _fixed(instrument, readings, settings, np.full(len(readings), settings.rays_per_reading))


def _fixed(instrument: Any, readings: Sequence[tuple[float, float, float]], settings: Settings,
           rays: np.ndarray) -> Tallies:
    """One batched kernel call: reading i gets ``rays[i]`` rays."""

    from virtspec_mi.plugins.integrators.spectrophotometer import ReadingPlan, tally_readings

    plans = [ReadingPlan(float(w), float(t), float(p), int(n)) for (w, t, p), n in zip(readings, rays)]
    counts = tally_readings(instrument, plans, settings)
    return Tallies(np.asarray(rays, dtype=np.int64), *counts.T)


def _two_stage(instrument: Any, readings: Sequence[tuple[float, float, float]], settings: Settings) -> Tallies:
    """Pilot batch, N₂ per reading from its counts, fresh second batch (two calls in all)."""

    from virtspec_mi import twostage

    pilot = _fixed(instrument, readings, settings, np.full(len(readings), settings.pilot_rays_per_reading))
    columns = [pilot.reflected, pilot.transmitted] + ([] if settings.joint else [pilot.absorbed])
    second = twostage.stage_two_rays(
        np.stack(columns, axis=1), settings.pilot_rays_per_reading, settings.mu, settings.delta,
        settings.pilot_delta_value, joint=settings.joint,
    )
    stage_two = settings.updated(seed=twostage.stage_two_seed(settings.seed))
    result = _fixed(instrument, readings, stage_two, second)
    return Tallies(result.rays, result.reflected, result.transmitted, result.weight_violations,
                   result.capped, pilot=pilot)
