"""
Rays for a ratio of two proportions to a stated tolerance: an integrating sphere's reading
==========================================================================================

An integrating sphere reads R = s · p₁/p₂ (s: the standard's value; p₁, p₂: the detector
fractions with the sample and with the standard, each m/N of its own rays). Its certified
interval is the extreme combinations of the two fractions' Clopper–Pearson intervals at
δ/2 each, [s·p₁⁻/p₂⁺, s·p₁⁺/p₂⁻], which hold together with probability ≥ 1 − δ by the
union bound (:func:`ratio_interval`). Its half-width — the larger distance from the
estimate to an end — depends on N and on the fractions themselves, so a tolerance on R
cannot fix N in advance.

:func:`ratio_rays` sizes N from a pilot, as the two-stage rule sizes one proportion: the
pilot's counts give each fraction a Clopper–Pearson interval at δ₁/2; at the corner of
that box where R's interval is widest (p₁ at its upper end, p₂ at its lower end), N is the
least whose expected counts (N·p) give a half-width ≤ ``tolerance``, found by bisection
on N. The second stage then traces N fresh rays per configuration, and its interval at
δ is valid whatever N the pilot chose (the second stage's rays are independent of the
pilot's). Whether the tolerance is met is then read from the interval itself: the sizing
aims at it, the certificate never depends on it.

References
----------
Clopper, C.J., Pearson, E.S. (1934). Biometrika 26, 404–413. Baranoski et al. (2001),
eq. (23) (the two-stage idea: a pilot sizes the reading); Goebel (1967) (the sphere's
reading as a ratio to the standard's).
"""

from __future__ import annotations

import numpy as np

from virtspec_mi.budgets.intervals import clopper_pearson

__all__ = ["MOST_RATIO_RAYS", "ratio_bounds", "half_width", "ratio_interval", "ratio_half_width", "ratio_rays"]

MOST_RATIO_RAYS: int = 2**31
"""The most rays :func:`ratio_rays` gives a reading (a tolerance that needs more is refused, naming it)."""


def ratio_bounds(first: np.ndarray, second: np.ndarray, standard: float) -> np.ndarray:
    """
    [s·p₁⁻/p₂⁺, s·p₁⁺/p₂⁻] from the two fractions' intervals ``first`` and ``second``
    (last axis: lower, upper), last axis of length 2: the extreme combinations, which hold
    whenever both intervals do (infinite above when p₂⁻ = 0).
    """

    first, second = np.asarray(first, dtype=np.float64), np.asarray(second, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return standard * np.stack([first[..., 0] / second[..., 1], first[..., 1] / second[..., 0]], axis=-1)


def half_width(estimate: np.ndarray, interval: np.ndarray) -> np.ndarray:
    """The larger distance from ``estimate`` to an end of ``interval`` (last axis: lower, upper)."""

    return np.maximum(estimate - interval[..., 0], interval[..., 1] - estimate)


def ratio_interval(k1: np.ndarray, n1: np.ndarray, k2: np.ndarray, n2: np.ndarray, standard: float,
                   delta: float) -> np.ndarray:
    """:func:`ratio_bounds` of counts k₁ of n₁ and k₂ of n₂ (each fraction's Clopper–Pearson interval at δ/2)."""

    return ratio_bounds(np.stack(clopper_pearson.unchecked(k1, n1, delta / 2), axis=-1),
                        np.stack(clopper_pearson.unchecked(k2, n2, delta / 2), axis=-1), standard)


def ratio_half_width(k1: np.ndarray, n1: np.ndarray, k2: np.ndarray, n2: np.ndarray, standard: float,
                     delta: float) -> np.ndarray:
    """:func:`half_width` of s·(k₁/n₁)/(k₂/n₂) in :func:`ratio_interval` (infinite when k₂ = 0)."""

    with np.errstate(divide="ignore", invalid="ignore"):
        estimate = standard * (np.asarray(k1) / np.asarray(n1)) / (np.asarray(k2) / np.asarray(n2))
        half = half_width(estimate, ratio_interval(k1, n1, k2, n2, standard, delta))
    return np.where(np.asarray(k2) > 0, half, np.inf)


def ratio_rays(k1: np.ndarray, k2: np.ndarray, pilot_rays: int, tolerance: float, standard: float, delta: float,
               pilot_delta: float) -> np.ndarray:
    """
    Second-stage rays per reading (the same N for both fractions) from the pilot's counts
    ``k1``, ``k2`` of ``pilot_rays`` each: the least N whose expected counts at the widest
    corner of the pilot's box (module docstring) give :func:`ratio_half_width` at δ ≤
    ``tolerance``. ``ValueError`` naming the tolerance when a reading would need more than
    :data:`MOST_RATIO_RAYS` (or its standard's fraction may be 0).
    """

    k1, k2 = (np.atleast_1d(np.asarray(k, dtype=np.float64)) for k in (k1, k2))
    _, p1 = clopper_pearson.unchecked(k1, pilot_rays, pilot_delta / 2)  # the widest corner: p1 high, p2 low
    p2, _ = clopper_pearson.unchecked(k2, pilot_rays, pilot_delta / 2)
    if np.any(p2 <= 0):
        raise ValueError(f"tolerance = {tolerance:g}: the pilot of {pilot_rays:,} rays saw no light reach the detector "
                         "with the standard in some reading (its fraction may be 0): no number of rays can promise the "
                         "tolerance; give more pilot_rays or a brighter sphere")

    def half(n: np.ndarray) -> np.ndarray:
        return ratio_half_width(np.round(p1 * n), n, np.maximum(np.round(p2 * n), 1.0), n, standard, delta)

    low, high = np.ones_like(p1), np.full_like(p1, float(MOST_RATIO_RAYS))
    if np.any(half(high) > tolerance):
        worst = int(np.argmax(half(high)))
        raise ValueError(f"tolerance = {tolerance:g} on the reading needs more than {MOST_RATIO_RAYS:,} rays per "
                         f"configuration at the pilot's fractions ({p1[worst]:.3g} with the sample, {p2[worst]:.3g} "
                         "with the standard): give a larger tolerance")
    while np.any(high - low > 1):  # bisection on log N: high always meets the tolerance, low (but 1) never
        open_ = high - low > 1
        middle = np.where(open_, np.clip(np.floor(np.sqrt(low * high)), low + 1, high - 1), high)
        meets = half(middle) <= tolerance
        high, low = np.where(open_ & meets, middle, high), np.where(open_ & ~meets, middle, low)
    return np.where(half(low) <= tolerance, low, high).astype(np.int64)
