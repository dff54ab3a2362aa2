"""
Certificates of a goniophotometer reading: CDFs, bin fractions, BRDF values
===========================================================================

A goniophotometer reading of N rays tallies the escaping rays in K direction bins
(:mod:`virtspec_mi.instruments.goniophotometer.bins`): m_k rays in bin k, an estimate m_k/N of the bin's
probability p_k and f_k = (m_k/N)/Ω_k of its mean BRDF/BTDF (Ω_k = ∫_bin |cos θo| dωo).
The paper (Baranoski et al. 2001, Sect. 6) names the ray-density analysis of such
*spatial* readings as future work; the certificates below are derived here. Every
reading is N i.i.d. rays (each ray's fate and direction are one draw of the specimen's
exit law: the kernel's rays are independent), so each is a statement about i.i.d.
samples. All hold per reading at δ (as the R/T certificates of :mod:`virtspec_mi.budgets.rules`).

1. **Cumulative distributions: DKW–Massart** (:func:`dkw_mu`, :func:`dkw_rays`).
   Give every ray a value X ∈ ℝ ∪ {+∞}: θo for an escaping ray, +∞ for an absorbed one
   (or the reflected-only θo, or φo, or any one-dimensional exit statistic). The
   empirical CDF F̂_N(x) = #{X ≤ x}/N of N i.i.d. rays satisfies (Dvoretzky, Kiefer &
   Wolfowitz 1956 with Massart's 1990 constant, valid whenever the right side is ≤ 1,
   for every distribution, atoms included)

       P( sup_x |F̂_N(x) − F(x)| > μ ) ≤ 2 exp(−2Nμ²),

   so N = ⌈ln(2/δ)/(2μ²)⌉ — *the paper's eq. (23) N for one proportion* — certifies
   every threshold at once, and N rays certify μ = √(ln(2/δ)/(2N)). The reading's CDF
   of θo (and of φo) at the bin edges, F̂(e_j) = Σ_{bins below e_j} m_k/N, is such an
   empirical CDF evaluated at (left limits of) thresholds, so it carries this
   guarantee for free.

2. **All bin fractions at once: union bound** (:func:`union_rays`, :func:`union_mu`).
   Each m_k ~ Binomial(N, p_k); Hoeffding gives P(|m_k/N − p_k| ≥ μ) ≤ 2e^{−2Nμ²}, and
   the union over the K bins P(∃k: |m_k/N − p_k| ≥ μ) ≤ 2K e^{−2Nμ²} ≤ δ when

       N = ⌈ln(2K/δ)/(2μ²)⌉     (eq. 23 at δ/K: it grows only with log K).

   The *exact-binomial union* (:func:`union_exact_rays`) asks each bin for the smallest
   N whose worst-case binomial miss probability max_p P(|Bin(N,p)/N − p| ≥ μ) is ≤ δ/K
   (the ``exact`` rule of :mod:`virtspec_mi.budgets.bounds` at δ/K): ~20 % fewer rays.
   Flattened in one order, the bins are increments of one empirical CDF, so DKW also
   gives |m_k/N − p_k| ≤ 2μ_DKW for every k at once, independent of K;
   :func:`bins_mu` states the smaller of the two (both fixed before the rays are seen).

3. **BRDF values: simultaneous Clopper–Pearson** (:func:`brdf_intervals`). Each bin's
   exact Clopper–Pearson interval [p_lo, p_hi] of p_k at level δ/K covers p_k with
   probability ≥ 1 − δ/K; by the union bound all K cover at once with ≥ 1 − δ, and
   f_k ∈ [p_lo/Ω_k, p_hi/Ω_k] since Ω_k is exact. A small bin's relative width grows
   as 1/√(N p_k) ∝ 1/√(N f_k Ω_k).

4. **Relative tolerance on f_k above a floor** (:func:`relative_rays`,
   :func:`relative_tolerance`). Multiplicative Chernoff bounds give
   P(|m_k − Np_k| ≥ εNp_k) ≤ e^{−ε²Np_k/3} + e^{−ε²Np_k/2} ≤ 2e^{−ε²Np_k/3} for
   0 < ε ≤ 1. For every bin whose true f_k ≥ f_floor, p_k ≥ f_floor·Ω_k ≥ f_floor·Ω_min, so
   with the union over K bins, |f̂_k − f_k| ≤ ε f_k for all such bins at once with
   probability ≥ 1 − δ when

       N = ⌈3 ln(2K/δ) / (ε² f_floor Ω_min)⌉.

   (Bins below the floor carry their Clopper–Pearson interval only.)

Which of these sizes a reading (``guarantee=``), and whether a two-stage pilot may size
it, is the rule table's to say (:data:`virtspec_mi.budgets.rules.GUARANTEES`); the
functions here are the formulas, and they trust their arguments: μ, δ, K, ε and the
floor are validated where they enter (the goniophotometer's options,
:func:`virtspec_mi.budgets.rules.gonio_rays`).

A printed certificate is what the spent rays give: the μ (or ε) for the reading's N,
rounded up; a reading whose R/T are not certified (weight violations, capped walks,
invalid directions: :attr:`virtspec_mi.results.readings.Result.certified`) carries none, and a
bound ≥ 1 (too few rays) certifies nothing; both say "not certified". Rounded BSDF
weights add their bias (rounded_weights·ε_w/N) to μ, as for R and T.

References
----------
Dvoretzky, A., Kiefer, J., Wolfowitz, J. (1956). Ann. Math. Statist. 27, 642–669.
Massart, P. (1990). The tight constant in the Dvoretzky–Kiefer–Wolfowitz inequality.
Ann. Probab. 18, 1269–1283.
Hoeffding, W. (1963). J. Amer. Statist. Assoc. 58, 13–30 (Baranoski et al. 2001, eq. 23).
Clopper, C.J., Pearson, E.S. (1934). Biometrika 26, 404–413.
Mitzenmacher, M., Upfal, E. (2005). Probability and Computing, Thm. 4.4, 4.5 (Chernoff).
"""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from virtspec_mi.budgets.bounds import exact_certified, exact_mu, exact_rays, hoeffding_mu, hoeffding_rays
from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.base.checks import check_rays_needed, shown_value

__all__ = [
    "dkw_rays",
    "dkw_mu",
    "union_rays",
    "union_mu",
    "union_exact_rays",
    "union_exact_mu",
    "bins_mu",
    "relative_rays",
    "relative_tolerance",
    "brdf_intervals",
]


def dkw_rays(mu: float, delta: float) -> int:
    """N certifying sup_x |F̂_N(x) − F(x)| < μ at δ (DKW–Massart): ⌈ln(2/δ)/(2μ²)⌉, the paper's eq. (23)."""

    return hoeffding_rays.unchecked(mu, delta)


def dkw_mu(rays: Any, delta: float) -> Any:
    """The sup-error μ = √(ln(2/δ)/(2N)) that N rays certify for an empirical CDF at δ."""

    return _per_rays(lambda n: hoeffding_mu.unchecked(n, delta), rays)


def union_rays(mu: float, delta: float, bins: int) -> int:
    """N certifying |m_k/N − p_k| < μ for all K bins at once at δ: ⌈ln(2K/δ)/(2μ²)⌉."""

    return hoeffding_rays.unchecked(mu, delta / bins)


def union_mu(rays: Any, delta: float, bins: int) -> Any:
    """The μ = √(ln(2K/δ)/(2N)) that N rays certify for all K bin fractions at once."""

    share = delta / bins
    return _per_rays(lambda n: hoeffding_mu.unchecked(n, share), rays)


def union_exact_rays(mu: float, delta: float, bins: int) -> int:
    """The exact-binomial union: each bin's smallest certified N at δ/K (:func:`virtspec_mi.budgets.bounds.exact_rays`)."""

    return exact_rays.unchecked(mu, delta / bins)


def union_exact_mu(rays: Any, delta: float, bins: int, mu: float | None = None) -> Any:
    """
    The exact-binomial μ of N rays at δ/K (:func:`virtspec_mi.budgets.bounds.exact_mu`); with the
    μ asked for, μ itself where N is at least the exact rule's N for (μ, δ/K)
    (:func:`virtspec_mi.budgets.bounds.exact_certified`: the exact inverse is only computed up
    to :data:`~virtspec_mi.budgets.bounds.EXACT_MU_MAX_RAYS` rays, Hoeffding's μ beyond).
    """

    share = delta / bins
    if mu is None:
        return _per_rays(lambda n: exact_mu.unchecked(n, share), rays)
    return _per_rays(lambda n: exact_certified(n, share, mu), rays)


def bins_mu(rays: Any, delta: float, bins: int) -> Any:
    """The smaller of the union μ and twice the DKW μ: both certify every bin fraction at once."""

    return np.minimum(union_mu(rays, delta, bins), 2 * dkw_mu(rays, delta))


def relative_rays(tolerance: float, floor: float, delta: float, bins: int, smallest_solid_angle: float) -> int:
    """
    N certifying |f̂_k − f_k| ≤ ε·f_k for every bin with f_k ≥ ``floor`` (sr⁻¹) at once at δ:
    ⌈3 ln(2K/δ)/(ε² · floor · Ω_min)⌉ (multiplicative Chernoff + union; ε = ``tolerance`` ≤ 1).
    ``ValueError`` where that N is more than one reading may trace.
    """

    need = 3.0 * math.log(2.0 / (delta / bins)) / (tolerance**2 * floor * float(smallest_solid_angle))
    return check_rays_needed(math.ceil(need) if math.isfinite(need) else math.inf,
                             f"relative_tolerance = {shown_value(tolerance)} above brdf_floor = {shown_value(floor)}")


def relative_tolerance(rays: Any, floor: float, delta: float, bins: int, smallest_solid_angle: float) -> Any:
    """The relative ε that N rays certify for every bin with f_k ≥ ``floor``; NaN where ε > 1 (none)."""

    n = np.asarray(rays, dtype=np.float64)
    eps = np.sqrt(3.0 * math.log(2.0 / (delta / bins)) / (n * floor * float(smallest_solid_angle)))
    return np.where(eps <= 1.0, eps, np.nan)


def brdf_intervals(counts: Any, rays: Any, solid_angles: Any, delta: float, bins: int) -> tuple[np.ndarray, np.ndarray]:
    """
    Simultaneous Clopper–Pearson intervals ``(lower, upper)`` of f_k (sr⁻¹): each bin at
    δ/K, divided by its projected solid angle Ω_k (broadcast: counts (…, K…), rays (…)).
    """

    lower, upper = clopper_pearson.unchecked(counts, rays, delta / bins)
    return lower / solid_angles, upper / solid_angles


def _per_rays(function: Callable[[int], float], rays: Any) -> Any:
    """``function`` of each distinct N (a number or an array of whole numbers)."""

    values = np.asarray(rays)
    if values.ndim == 0:
        return float(function(int(values)))
    unique, inverse = np.unique(values, return_inverse=True)
    return np.array([function(int(n)) for n in unique])[inverse].reshape(values.shape)
