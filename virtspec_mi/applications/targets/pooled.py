"""
Measuring a linear target by pooled two-stage readings
======================================================

A linear functional L = Σₖ wₖ qₖ whose weights have one sign s is s·W·p̄, with W = Σₖ|wₖ|
and p̄ = Σₖ (|wₖ|/W)·qₖ: the probability that a ray whose wavelength is drawn with
probability |wₖ|/W ends in the fate q counts. :func:`pooled_rays` draws the wavelengths
so: the n rays of a batch are split over the wavelengths by one multinomial draw
(a generator seeded by the settings' seed, the stage and the functional). By the law of
total probability each ray's fate is then a Bernoulli(p̄) trial independent of the
others, whatever the qₖ, so the functional's count m is exactly Binomial(n, p̄) — one
proportion, as a spectrum's reading is — and the target is certified by the same
two-stage exact rule (:mod:`virtspec_mi.budgets.twostage`), ``bound="two-stage"``:

1. each functional j gets its own pilot (the settings' seed) of n₁ = ⌈10/μⱼ⌉ rays,
   μⱼ = tⱼ/Wⱼ (tⱼ its tolerance), whose Clopper–Pearson interval at δ₁ = δⱼ/10 locates p̄
   (δⱼ = δ/m, m functionals, union bound). At a loose tolerance, where the pilot would
   cost more than :data:`PILOT_SHARE` of the exact rule's N (:func:`pilot_pays`), there is
   no pilot and N₂ is the exact rule's N over every p̄ at δⱼ (a spectrum's ``bound="exact"``);
2. N₂ = the least N whose exact binomial law misses p̄ by μⱼ with probability at most
   δⱼ − δ₁ for every p̄ in that interval (:func:`~virtspec_mi.budgets.twostage.stage_two_rays`),
   N₂ fresh rays (the seed :func:`~virtspec_mi.budgets.twostage.stage_two_seed`);
3. Lⱼ = s·Wⱼ·m/N₂ ± (tⱼ + its rounding bias), each with probability ≥ 1 − δⱼ, all of them
   at once with probability ≥ 1 − δ.

Functionals that share wavelengths do not share rays (each draws its own). The pilot
only sizes; the second batch is the last: nothing is traced after the certificate, and
sampling does not stop on the data, so the guarantee is the fixed rule's. Interrupted
and resumed with a checkpoint, the same draws and traces give the same result
(:mod:`.resume`).

Against the betting route (:mod:`.sequential`): pooling forgoes Neyman's allocation over
the wavelengths (p̄(1 − p̄) ≥ Σₖ(|wₖ|/W)qₖ(1 − qₖ), by the spread of the qₖ), and a fixed
N₂ under the exact law replaces a sequence valid at every batch. For a linear target the
second weighs more: near p̄ = ½, where no sequence can beat Hoeffding's N by much, the
exact law needs ≈ z²/(2 ln(2/δ)) of it (``benchmarks/betting.py`` measures both). Only a
linear target whose functionals each have weights of one sign is pooled (:func:`poolable`);
``bound="auto"`` takes this route for it.

References
----------
Clopper, C.J., Pearson, E.S. (1934). Biometrika 26, 404–413 (the pilot's interval).
Baranoski et al. (2001), eq. (2) (a reading's fraction m/N); the exact rule and the
two-stage guarantee: :mod:`virtspec_mi.budgets.twostage`.
"""

from __future__ import annotations

import time
from statistics import NormalDist
from typing import Any

import numpy as np

from virtspec_mi.applications.targets.measure import _fates, _trace, check_certified, prepared, spent_readings
from virtspec_mi.applications.targets.result import DerivedResult
from virtspec_mi.applications.targets.targets import Target
from virtspec_mi.budgets.bounds import exact_rays
from virtspec_mi.budgets.twostage import (default_pilot_delta, default_pilot_rays, most_second_rays, stage_two_rays,
                                          stage_two_seed)
from virtspec_mi.kernel.counts import WEIGHT_ROUNDING, Counts
from virtspec_mi.settings import Settings

__all__ = ["poolable", "pilot_pays", "pooled_rays", "take_pooled", "PILOT_SHARE"]

PILOT_SHARE: float = 0.25
"""A functional takes a pilot when it costs at most this share of the exact rule's N without one (:func:`pilot_pays`)."""


def poolable(target: Target) -> str:
    """
    Why ``target`` cannot be certified by pooled readings, or ``""`` when it can: it is
    linear (no pilot of its own) and each of its functionals weighs its wavelengths with
    one sign.
    """

    if target.needs_pilot:
        return f"{target.describe()} is not linear in the spectrum (its tolerances depend on where it lies)"
    for functional in target.functionals():
        w = np.asarray(functional.weights, dtype=np.float64)
        if np.any(w > 0) and np.any(w < 0):
            return f"{functional.name} weighs some wavelengths positively and others negatively"
    return ""


def pilot_pays(mu: float, delta: float) -> bool:
    """
    Whether a functional at μ and δ takes a pilot: when its ⌈10/μ⌉ rays cost at most
    :data:`PILOT_SHARE` of the exact rule's N over every p̄ (normal approximation,
    z²/(4μ²)); else the exact rule's N alone (a loose tolerance: the pilot would cost
    about as much as it saves). Decided from μ and δ alone, before any ray.
    """

    z = NormalDist().inv_cdf(1 - delta / 2)
    return default_pilot_rays(mu) <= PILOT_SHARE * z * z / (4 * mu * mu)


def pooled_rays(weights: np.ndarray, rays: int, seed: int, stage: int, functional: int) -> np.ndarray:
    """
    ``rays`` rays split over the wavelengths with probabilities |wₖ|/Σ|w| (one multinomial
    draw): the rays of each wavelength. The draw is a function of ``seed``, ``stage``
    (:data:`STAGES`) and ``functional`` alone.
    """

    share = np.abs(np.asarray(weights, dtype=np.float64))
    generator = np.random.Generator(np.random.PCG64(np.random.SeedSequence([int(seed), stage, functional])))
    return generator.multinomial(int(rays), share / share.sum()).astype(np.int64)


def take_pooled(bench: Any, settings: Settings, target: Target, *, scene: str = "", source: dict | None = None
                ) -> DerivedResult:
    """
    Certify the linear ``target`` on ``bench`` with ``settings`` by pooled two-stage
    readings (the module docstring); a target :func:`poolable` refuses: ``ValueError``
    naming why and the bounds that take it.
    """

    start = time.perf_counter()
    target, functionals, grid, weights, each = prepared(bench, settings, target)
    why = poolable(target)
    if why:
        raise ValueError(f"bound='two-stage' pools each functional's wavelengths into one proportion, which needs a "
                         f"linear target whose weights have one sign: {why}; give bound='betting' or 'hoeffding' "
                         "(or 'auto')")
    tolerances = np.asarray(target.tolerances(None, float(settings.delta)), dtype=np.float64)
    quantity, pilot_delta = functionals[0].quantity, default_pilot_delta(each)
    scales = np.abs(weights).sum(axis=1)
    mus = np.minimum(tolerances / scales, 0.5)
    pilots = [default_pilot_rays(float(mu)) if pilot_pays(float(mu), each) else 0 for mu in mus]
    # one stride per stage, more than any functional's rays there: every functional's rays from ranges of their own
    strides = (max(pilots), max(most_second_rays(float(mu), each, pilot_delta) for mu in mus))
    total = Counts.zeros(len(grid))
    estimates, certified, seconds, batches = [], [], 0.0, []
    for j, (w, t, scale, mu, pilot) in enumerate(zip(weights, tolerances, scales, mus, pilots)):
        if pilot:
            hits, _, _ = _pooled_trace(bench, settings, grid, w, pilot, settings.seed, (0, j, strides[0]), quantity,
                                       scene, source)
            second = int(stage_two_rays([[int(hits)]], pilot, float(mu), each, pilot_delta)[0])
        else:  # the exact rule over every p̄, as a spectrum's bound="exact"
            second = exact_rays(float(mu), each)
        assert second <= strides[1], "the exact rule never asks for more than Hoeffding's N (most_second_rays)"
        hits, tally, rays = _pooled_trace(bench, settings, grid, w, second, stage_two_seed(settings.seed),
                                          (1, j, strides[1]), quantity, scene, source)
        traced = np.flatnonzero(rays > 0)
        counts = tally.counts
        check_certified(target, counts)
        total.add(traced, counts)
        seconds += tally.seconds
        sign = -1.0 if np.any(w < 0) else 1.0
        estimates.append(sign * scale * hits / second)
        certified.append(float(t) + scale * WEIGHT_ROUNDING * float(np.sum(counts.rounded_weights)) / second)
        batches.append(second)
    used = np.flatnonzero(total.rays > 0)
    reported = target.values(np.array(estimates), np.array(certified))
    spent = total.map(lambda counts: counts[used])
    readings = spent_readings(bench, settings, grid, used, spent, seconds, scene, source)
    return DerivedResult(target=target, values=tuple(reported), readings=readings, rays=int(sum(batches)),
                         pilot_rays=int(sum(pilots)), delta=float(settings.delta), statements=len(functionals),
                         functional_tolerances=tuple(certified), met=bool(target.met(reported)),
                         seconds=time.perf_counter() - start, bound="two-stage", batches=tuple(batches))


def _pooled_trace(bench: Any, settings: Settings, grid: np.ndarray, weights: np.ndarray, rays: int, seed: int,
                  draw: tuple[int, int, int], quantity: str, scene: str, source: dict | None
                  ) -> tuple[int, Any, np.ndarray]:
    """
    ``rays`` pooled rays (:func:`pooled_rays`) of ``draw`` = (stage, functional j, stride S)
    traced at ``seed``, wavelength k of the K from global index (j·K + k)·S: the count of
    ``quantity``'s fate, the tally and the rays per grid wavelength.
    """

    stage, functional, stride = draw
    every = pooled_rays(weights, rays, seed, stage, functional)
    offsets = (functional * len(grid) + np.arange(len(grid), dtype=np.int64)) * int(stride)
    _, tally = _trace(bench, settings, grid, every, int(seed), scene, source, offsets)
    return int(np.sum(_fates(tally.counts, quantity))), tally, every
