"""
Coverage harness: do certified readings miss as often as the binomial law says?
===============================================================================

For specimens whose reflectance ρ is known exactly, :func:`coverage` takes K
independent readings in **one** :func:`virtspec_mi.engine.readings.trace_readings` call (at
551 nm, one reading per azimuth φi = 360°·k/K: every reading has its own rays, and
these isotropic specimens do not depend on φi — nor on wavelength, but readings that
differ only in wavelength share rays, see :mod:`virtspec_mi.engine.readings`), counts the *misses* ``|m/N − ρ| ≥ μ`` and compares that count
with its exact law: Binomial(K, q), with q the exact miss probability of the rule —
:func:`virtspec_mi.budgets.bounds.miss_probability` at the rule's N for a fixed rule, the
exact mixture over the pilot count (:func:`virtspec_mi.budgets.twostage.two_stage_law`) for
``two-stage``. The test is two-sided (an exact binomial test): a plain "misses ≤ δK"
check has almost no power, because the rules are conservative (at ρ = ½ eq. (23)'s N
misses with probability 0.0011, not 0.01: :func:`virtspec_mi.budgets.bounds.max_miss_probability`).

Specimens (:data:`SPECIMENS`): the paper's diamond (``simple_dielectric``, η = 2.419)
under a collimated beam at θi = 0°, 45° and 80° (ρ = Fresnel reflectance,
:func:`virtspec_mi.references.quadrature.fresnel_reflectance`; the rest transmitted), Mitsuba's
``diffuse`` with albedo 0.3 (ρ = 0.3, the rest absorbed) and an absorber (``diffuse``
with reflectance 0: ρ = 0, so q = 0 and no reading may miss).

References
----------
Clopper, C.J., Pearson, E.S. (1934). Biometrika 26, 404–413 (the miss rate's interval).
The exact law of a miss is :func:`virtspec_mi.budgets.bounds.miss_probability` (fixed
rules) and :func:`virtspec_mi.budgets.twostage.two_stage_law` (the two-stage rule).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from virtspec_mi.settings import Settings

__all__ = ["Specimen", "SPECIMENS", "Coverage", "coverage", "predicted_miss_probability"]


@dataclass(frozen=True)
class Specimen:
    """A specimen whose reflectance is known exactly, and how to measure it."""

    name: str
    bsdf: dict
    theta_i: float
    beam: str
    reflectance: float
    other: str
    """Fate of the rays not reflected: ``"transmitted"`` or ``"absorbed"``."""


def _specimens() -> tuple[Specimen, ...]:
    from virtspec_mi.references.quadrature import fresnel_reflectance

    diamond = [
        Specimen(f"diamond {theta:g} deg", {"type": "simple_dielectric", "eta": 2.419}, theta, "collimated",
                 float(fresnel_reflectance(theta, 2.419)), "transmitted")
        for theta in (0.0, 45.0, 80.0)
    ]
    return (
        *diamond,
        Specimen("diffuse 0.3", {"type": "diffuse", "reflectance": 0.3}, 30.0, "collimated", 0.3, "absorbed"),
        Specimen("absorber", {"type": "diffuse", "reflectance": 0.0}, 30.0, "collimated", 0.0, "absorbed"),
    )


SPECIMENS: tuple[Specimen, ...] = _specimens()
"""Diamond collimated at 0°, 45°, 80°; ``diffuse`` albedo 0.3; an absorber (ρ = 0)."""


@dataclass(frozen=True)
class Coverage:
    """Outcome of :func:`coverage` for one specimen and one rule."""

    specimen: str
    bound: str
    mu: float
    delta: float
    readings: int
    rays: float
    """Mean rays per reading behind the estimate."""
    rays_spent: float
    """Mean rays traced per reading (two-stage: pilot included)."""
    seconds: float
    """Wall time of the one :func:`~virtspec_mi.engine.readings.trace_readings` call (tracing and sizing)."""
    misses: int
    miss_probability: float
    """q, the exact probability that one reading misses."""
    mean_abs_error: float
    """Mean |m/N − ρ| over the readings."""
    max_abs_error: float
    """Largest |m/N − ρ| over the readings."""
    pvalue: float
    """Two-sided exact binomial test of ``misses`` against Binomial(readings, q)."""
    miss_interval: tuple[float, float]
    """Clopper–Pearson 95 % interval of the observed miss rate."""

    def passed(self, level: float = 1e-4) -> bool:
        """The miss count is consistent with Binomial(K, q) at the given level."""

        return self.pvalue > level

    @property
    def within_delta(self) -> bool:
        """The observed miss rate is consistent with ≤ δ (its 95 % interval reaches below δ)."""

        return self.miss_interval[0] <= self.delta


def predicted_miss_probability(specimen: Specimen, settings: Settings) -> float:
    """Exact probability that one reading of ``specimen`` under ``settings`` misses by μ or more."""

    from virtspec_mi.budgets import bounds
    from virtspec_mi.budgets import twostage

    rho = specimen.reflectance
    if settings.adaptive:
        return twostage.two_stage_law(
            rho, settings.mu, settings.delta, settings.pilot_rays_per_reading, settings.pilot_delta_value,
            joint=settings.joint, other=specimen.other,
        ).miss_probability
    # N from the rule itself (not the settings' sizing, which the power test tampers with)
    rays = settings.rays if settings.rays is not None else settings.budget.rays(settings.mu, settings.quantity_delta)
    return bounds.miss_probability(rays, rho, settings.mu)


def coverage(
    specimen: Specimen,
    bound: str,
    *,
    mu: float = 0.05,
    delta: float = 0.2,
    readings: int = 1000,
    seed: int = 0,
    **settings: Any,
) -> Coverage:
    """
    Take ``readings`` independent readings of ``specimen`` under ``bound`` in one batched
    :func:`~virtspec_mi.engine.readings.trace_readings` call (the spectrophotometer's plan)
    and test the miss count against its exact binomial law.

    ``settings`` go to :class:`Settings` (``joint``, ``pilot_rays``, ``pilot_delta``,
    ``rays``, ``chunk_size`` …). Defaults are the cheap test setting μ = 0.05, δ = 0.2.
    """

    from scipy import stats

    from virtspec_mi.budgets.intervals import clopper_pearson
    from virtspec_mi.engine.readings import trace_readings
    from virtspec_mi.instruments import commanding
    from virtspec_mi.runtime.scene import find_bench, instrument_scene

    if readings < 1:
        raise ValueError(f"readings must be a whole number >= 1 (got {readings!r})")
    azimuths = 360.0 * np.arange(readings) / readings
    config = Settings(theta_i=specimen.theta_i, beam=specimen.beam, wavelengths=551.0, mu=mu,
                      delta=delta, bound=bound, seed=seed, **settings)
    bench = find_bench(instrument_scene(specimen.bsdf))
    start = time.perf_counter()
    plan = commanding("measure")().init(bench, config, None, np.array([config.theta_i]), None)
    tally = trace_readings(bench, plan, 0, [(551.0, config.theta_i, phi) for phi in azimuths])
    tallies, pilot = tally.counts, tally.pilot
    seconds = time.perf_counter() - start
    n, m, rho = tallies.rays, tallies.reflected, specimen.reflectance
    # |m/N − ρ| ≥ μ on the counts, with the same lattice convention as miss_probability
    miss = (m <= np.floor(n * (rho - mu) + 1e-9)) | (m >= np.ceil(n * (rho + mu) - 1e-9))
    misses = int(miss.sum())
    q = predicted_miss_probability(specimen, config)
    if q <= 0.0:
        pvalue = 1.0 if misses == 0 else 0.0
    else:
        pvalue = float(stats.binomtest(misses, readings, min(q, 1.0)).pvalue)
    lower, upper = clopper_pearson(misses, readings, 0.05)
    return Coverage(
        specimen=specimen.name, bound=bound, mu=config.mu, delta=config.delta, readings=readings,
        rays=float(n.mean()), rays_spent=float((n if pilot is None else n + pilot.rays).mean()), seconds=seconds, misses=misses,
        miss_probability=float(q), mean_abs_error=float(np.mean(np.abs(m / n - rho))),
        max_abs_error=float(np.max(np.abs(m / n - rho))), pvalue=pvalue,
        miss_interval=(float(lower), float(upper)),
    )
