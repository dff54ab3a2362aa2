"""
Rays for many cells at once: union budgets and a two-stage binomial rule
========================================================================

A table of C cells is certified *jointly*, |Ê_c − E_c| < ε for every cell at once with
probability ≥ 1 − δ, by giving each cell (and each quantity Q certified in it) the
failure probability δ/(C·|Q|) (the union bound: the failure events need not be
independent).

Fixed rule (``hoeffding``): every cell gets N = ⌈ln(2C|Q|/δ)/(2ε²)⌉ rays
(Hoeffding 1963, eq. 2.3; Baranoski et al. 2001, eq. 23).

Two-stage rule (``two-stage``), per cell:

1. a pilot of n₁ rays (by default ⌈40/ε⌉, :func:`table_pilot_rays`) gives, per quantity,
   the Clopper–Pearson interval [lo, hi] at δ₁ = δ_c/10 (split over the quantities),
   δ_c = δ/C;
2. a *fresh* second batch of N₂ rays, the smallest N for which every p in [lo, hi]
   has P(|p̂ − p| ≥ ε) ≤ δ₂ (δ₂ = δ_c − δ₁, split over the quantities; the largest N₂
   over the quantities is traced), by the binomial tail bounds of Zubkov & Serov
   (2013, Theorem 1): for S ~ Bin(N, p) and 0 ≤ k < N,

       Φ(sgn(k/N − p)·√(2N·KL(k/N ‖ p))) ≤ P(S ≤ k) ≤ Φ(sgn((k+1)/N − p)·√(2N·KL((k+1)/N ‖ p))),

   so P(p̂ ≥ p + ε) ≤ Φ̄(√(2N·KL(p + ε − 1/N ‖ p))) and
   P(p̂ ≤ p − ε) ≤ Φ̄(√(2N·KL(p − ε + 1/N ‖ p))) (KL grows as its first argument moves
   away from p). Each tail is held to δ₂/2: 2N·min_p KL(p ± ε' ‖ p) ≥ z², z = Φ̄⁻¹(δ₂/2),
   ε' = ε − 1/N; the left side grows with N, so N₂ and every larger N pass
   (:func:`binomial_rays`). It needs about z²p(1 − p)/ε² rays, the normal
   approximation's count, where Hoeffding's Theorem 1 (the Chernoff bound
   exp(−N·KL), :func:`chernoff_rays`) needs 2 ln(2/δ₂)p(1 − p)/ε² — 25 % more at
   δ₂ ≈ 10⁻⁵ — and never more than Hoeffding's N at the same δ₂ (which is the cap);
3. the estimate is the second batch alone: P(miss) ≤ δ₁ + δ₂ = δ_c.

The cells' N₂ are traced in few classes (:func:`stage_two_classes`): each rounded *up* to
the next power of :data:`CLASS_STEP` (more rays than a cell needs certify it all the
same), never past Hoeffding's N at the cell's δ₂ (which certifies alone), so cells of one
class are one sweep.

KL(q‖p) = q ln(q/p) + (1 − q) ln((1 − q)/(1 − p)) is the Bernoulli relative entropy.
The minimum over an interval is exact and cheap: u(p) = KL(p + ε ‖ p) is strictly
convex on (0, 1 − ε] — its derivative ln(1 + a) − a − ln(1 − b) − b with a = ε/p,
b = ε/(1 − p) is increasing in p, each of the two terms being monotone — so its minimum
over [lo, hi] is at the clip of its unique stationary point p* (found by bisection) into
the interval; the lower-tail exponent is u(1 − p). Beyond p > 1 − ε the upper deviation
cannot happen (exponent ∞), likewise the lower one for p < ε.

Why not the project's exact two-stage rule (:mod:`virtspec_mi.budgets.twostage`): at ε = 10⁻³
and δ_c ≈ 10⁻⁵ its exact binomial search costs 0.1–7 s per distinct pilot count, and a
table has hundreds of them. This rule costs milliseconds for all cells, spends about
the exact rule's rays (it is the normal approximation made rigorous) and, near 0 or 1
(low roughness: E ≈ 1), a small fraction of Hoeffding's (≈ 4p(1 − p) of them).

References
----------
Zubkov, A.M., Serov, A.A. (2013). A complete proof of universal inequalities for the
distribution function of the binomial law. Theory of Probability and its Applications
57(3), 539–544: Theorem 1.
Hoeffding, W. (1963). Probability inequalities for sums of bounded random variables.
Journal of the American Statistical Association 58, 13–30: Theorem 1, eqs. (2.1), (2.3).
Clopper, C.J., Pearson, E.S. (1934). Biometrika 26, 404–413.
Baranoski, G.V.G., Rokne, J.G., Xu, G. (2001). The Visual Computer 17, 506–518: eq. (23).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from virtspec_mi.base.checks import MAX_RAYS, check_delta, check_mu
from virtspec_mi.budgets.intervals import clopper_pearson

__all__ = ["bernoulli_kl", "upper_exponent", "chernoff_rays", "binomial_rays", "union_hoeffding_rays",
           "union_hoeffding_rays_array", "pilot_intervals", "stage_two_shares",
           "stage_two_rays", "table_pilot_rays", "CLASS_STEP", "stage_two_classes"]

CLASS_STEP: float = 2.0 ** 0.125
"""The rays of two cells traced together (one class of :func:`stage_two_classes`) differ by at most this factor."""


def bernoulli_kl(q: ArrayLike, p: ArrayLike) -> NDArray[np.float64]:
    """KL(q‖p) of two Bernoulli laws (0·ln 0 = 0; +∞ where q > 0 = p or q < 1 = p)."""

    q, p = np.broadcast_arrays(np.asarray(q, dtype=np.float64), np.asarray(p, dtype=np.float64))
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(q > 0, q * np.log(q / p), 0.0)
        b = np.where(q < 1, (1 - q) * np.log((1 - q) / (1 - p)), 0.0)
    return a + b


def _derivative(p: NDArray[np.float64], eps: float) -> NDArray[np.float64]:
    a, b = eps / p, eps / (1.0 - p)
    return np.log1p(a) - a - np.log1p(-b) - b


def upper_exponent(lo: ArrayLike, hi: ArrayLike, epsilon: ArrayLike) -> NDArray[np.float64]:
    """
    min over p ∈ [lo, hi] of KL(p + ε ‖ p): the upper-tail Chernoff exponent of the worst p
    (+∞ when every p of the interval exceeds 1 − ε: the upper deviation cannot occur).
    Broadcasts over ``lo``, ``hi`` and ``epsilon`` (0 < ε < 1).
    """

    lo, hi, eps = np.broadcast_arrays(np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64),
                                      np.asarray(epsilon, dtype=np.float64))
    top = 1.0 - eps
    # stationary point p* of the convex u(p) on (0, 1 − ε): bisection on the increasing derivative
    left, right = np.minimum(eps, 0.5) * 1e-9, top.copy()
    for _ in range(100):
        middle = 0.5 * (left + right)
        negative = _derivative(middle, eps) < 0
        left, right = np.where(negative, middle, left), np.where(negative, right, middle)
    star = 0.5 * (left + right)
    p = np.clip(star, lo, np.minimum(hi, top))
    value = bernoulli_kl(np.minimum(p + eps, 1.0), p)
    return np.where(lo > top, np.inf, value)


def chernoff_rays(lo: ArrayLike, hi: ArrayLike, epsilon: float, delta: float) -> NDArray[np.int64]:
    """
    Smallest N with exp(−N·U) + exp(−N·L) ≤ δ, each tail at δ/2, where U and L are the
    worst upper- and lower-tail exponents over p ∈ [lo, hi] (Hoeffding 1963, Theorem 1):
    P(|p̂ − p| ≥ ε) ≤ δ for every p in the interval and every N ≥ the result.

    References
    ----------
    Hoeffding (1963), Theorem 1, eq. (2.1).
    """

    epsilon, delta = check_mu(epsilon), check_delta(delta)
    lo, hi = np.broadcast_arrays(np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64))
    upper = upper_exponent(lo, hi, epsilon)
    lower = upper_exponent(1.0 - hi, 1.0 - lo, epsilon)
    worst = np.minimum(upper, lower)
    with np.errstate(divide="ignore"):
        rays = np.where(np.isinf(worst), 1.0, np.ceil(math.log(2.0 / delta) / worst * (1 + 1e-12)))
    if np.any(rays > MAX_RAYS):
        raise ValueError(f"epsilon = {epsilon:g} at delta = {delta:g} needs more than {MAX_RAYS:,} rays per cell "
                         "(2**32 - 1, what one reading may trace); raise epsilon or delta")
    return rays.astype(np.int64)


def binomial_rays(lo: ArrayLike, hi: ArrayLike, epsilon: float, delta: ArrayLike) -> NDArray[np.int64]:
    """
    Smallest N with P(|p̂ − p| ≥ ε) ≤ δ for every p ∈ [lo, hi] (and every larger N) by the
    binomial tail bounds of Zubkov & Serov (2013), each tail at δ/2: 2N·U(ε − 1/N) ≥ z²,
    z = Φ̄⁻¹(δ/2), U(ε') the smaller of the worst upper- and lower-tail exponents over
    the interval (see the module docstring); never more than Hoeffding's N at δ.

    References
    ----------
    Zubkov & Serov (2013), Theorem 1; Hoeffding (1963), eq. (2.3).
    """

    from scipy.special import ndtri

    epsilon = check_mu(epsilon)
    lo, hi, delta = np.broadcast_arrays(np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64),
                                        np.asarray(delta, dtype=np.float64))
    if not np.all((delta > 0) & (delta < 1)):
        raise ValueError("delta must satisfy 0 < delta < 1 for every cell")
    z2 = (-ndtri(delta / 2.0)) ** 2

    def exponent(n: NDArray[np.float64]) -> NDArray[np.float64]:
        eps = epsilon - 1.0 / n
        return np.minimum(upper_exponent(lo, hi, eps), upper_exponent(1.0 - hi, 1.0 - lo, eps))

    cap = np.ceil(np.log(2.0 / delta) / (2.0 * epsilon * epsilon) * (1 - 1e-12))  # Hoeffding: valid for every p
    if np.any(cap > MAX_RAYS):
        raise ValueError(f"epsilon = {epsilon:g} at delta = {float(delta.min()):g} needs more than {MAX_RAYS:,} rays "
                         "per cell (2**32 - 1, what one reading may trace); raise epsilon or delta")
    with np.errstate(divide="ignore"):
        low = np.minimum(np.ceil(z2 / (2.0 * exponent(np.full(lo.shape, np.inf)))), cap)  # U(ε') ≤ U(ε): a lower bound
    low = np.maximum(low, np.floor(1.0 / epsilon) + 1.0)  # ε' = ε − 1/N > 0
    high = cap.copy()

    def passes(n: NDArray[np.float64]) -> NDArray[np.bool_]:
        with np.errstate(divide="ignore", invalid="ignore"):
            return (2.0 * n * exponent(n) >= z2) | (n >= cap)

    # 2N·U(ε − 1/N) grows with N: bisection for the smallest N that passes (N ≥ cap always does)
    low = np.where(passes(low), low, low + 1.0)
    done = passes(low)
    while not np.all(done | (high - low <= 0)):
        middle = np.floor((low + high) / 2.0)
        ok = passes(middle)
        high = np.where(~done & ok, middle, high)
        low = np.where(~done & ~ok, middle + 1.0, low)
        done = done | (high <= low)
    rays = np.where(passes(low), low, high)
    return rays.astype(np.int64)


def union_hoeffding_rays(epsilon: float, delta: float, statements: int) -> int:
    """Rays per cell for ``statements`` Hoeffding statements at once: ⌈ln(2S/δ)/(2ε²)⌉ (union bound)."""

    epsilon, delta = check_mu(epsilon), check_delta(delta)
    if statements < 1:
        raise ValueError(f"statements must be >= 1 (got {statements})")
    rays = math.ceil(math.log(2.0 * statements / delta) / (2.0 * epsilon * epsilon) * (1 - 1e-12))
    if rays > MAX_RAYS:
        raise ValueError(f"epsilon = {epsilon:g} for {statements:,} statements at delta = {delta:g} needs {rays:,} "
                         f"rays per cell, more than the {MAX_RAYS:,} one reading may trace; raise epsilon or delta")
    return rays


def union_hoeffding_rays_array(epsilon: float, delta: ArrayLike) -> NDArray[np.int64]:
    """Hoeffding's N = ⌈ln(2/δ)/(2ε²)⌉ for each δ of an array (one statement each)."""

    delta = np.asarray(delta, dtype=np.float64)
    return np.ceil(np.log(2.0 / delta) / (2.0 * epsilon * epsilon) * (1 - 1e-12)).astype(np.int64)


def table_pilot_rays(epsilon: float) -> int:
    """The pilot size n₁ of a table's two-stage rule at tolerance ``epsilon``: ⌈40/ε⌉."""

    return math.ceil(40.0 / epsilon - 1e-9)


def stage_two_classes(need: ArrayLike, epsilon: float, delta: ArrayLike) -> NDArray[np.int64]:
    """
    The second-batch rays traced for cells that need ``need`` rays (:func:`binomial_rays` at
    tolerance ``epsilon`` and each cell's ``delta``): each rounded up to the next power of
    :data:`CLASS_STEP`, capped by Hoeffding's N at that δ (:func:`union_hoeffding_rays_array`).
    """

    classes = np.ceil(CLASS_STEP ** np.ceil(np.log(need) / np.log(CLASS_STEP) - 1e-9))
    return np.minimum(classes, union_hoeffding_rays_array(epsilon, delta)).astype(np.int64)


def stage_two_shares(intervals: dict[str, list[tuple[np.ndarray, np.ndarray]]], total: float) -> dict[str, np.ndarray]:
    """
    Each cell's δ₂ (per quantity) out of ``total``, in proportion to the largest variance
    p(1 − p) its pilot intervals allow (floored at 1 % of the largest), so that Σ over
    cells and quantities is ``total``.

    The union bound only needs the cells' failure probabilities to add up to δ; their
    shares may differ, and may depend on the pilots (which are independent of the second
    batches): cells near 0 or 1 need few rays whatever their δ (N ∝ p(1 − p)·ln(1/δ)),
    cells near ½ gain most from a larger one. Minimising Σ N_c under Σ δ_c fixed gives
    δ_c ∝ p_c(1 − p_c) (Lagrange); the pilot's worst case stands in for p_c.

    Parameters
    ----------
    intervals
        Per group of cells (e.g. a beam), a list over the certified quantities of the
        pilot intervals (lo, hi), arrays of one shape.
    total
        δ₂ of the whole table (e.g. 0.9 δ).
    """

    weights: dict[str, np.ndarray] = {}
    for key, parts in intervals.items():
        w = None
        for lo, hi in parts:
            p = np.clip(0.5, lo, hi)
            v = p * (1.0 - p)
            w = v if w is None else np.maximum(w, v)
        weights[key] = w
    largest = max(float(np.max(w)) for w in weights.values())
    floor = 0.01 * largest if largest > 0 else 1.0
    weights = {k: np.maximum(w, floor) for k, w in weights.items()}
    count = {k: len(intervals[k]) for k in intervals}
    mass = sum(float(w.sum()) * count[k] for k, w in weights.items())
    return {k: total * w / mass for k, w in weights.items()}


def pilot_intervals(counts: ArrayLike, pilot_rays: int, delta: float) -> tuple[np.ndarray, np.ndarray]:
    """Clopper–Pearson intervals (lo, hi) of pilot counts at δ each (vectorised)."""

    return clopper_pearson(np.asarray(counts), pilot_rays, delta)


def stage_two_rays(pilot_counts: ArrayLike, pilot_rays: int, epsilon: float, pilot_delta: float,
                   delta: float) -> NDArray[np.int64]:
    """
    Second-batch rays N₂ per cell from pilot counts of shape (cells, quantities): the
    largest over the quantities of :func:`binomial_rays` at δ/|Q| over the pilot's
    Clopper–Pearson interval at δ₁/|Q|.

    Parameters
    ----------
    pilot_counts
        Per cell, the pilot count of each certified quantity (e.g. escaped rays).
    pilot_rays
        n₁.
    epsilon
        Tolerance ε of every cell.
    pilot_delta, delta
        δ₁ and δ₂ of one cell (all its quantities together).
    """

    counts = np.atleast_2d(np.asarray(pilot_counts, dtype=np.int64))
    share = counts.shape[1]
    lo, hi = pilot_intervals(counts, pilot_rays, pilot_delta / share)
    return binomial_rays(lo, hi, epsilon, delta / share).max(axis=1)
