"""
Ray budgets: how many rays certify a reading
============================================

A reading counts m of N rays; each ray is a Bernoulli trial with success probability
ρ (the reflectance, or transmittance). The paper certifies ``|m/N − ρ| < μ`` with
probability at least ``1 − δ`` by choosing N from a tail bound that needs no
knowledge of ρ:

- :func:`chebyshev_rays`: the ordinary Chebyshev bound, ``N = ⌈1/(4μ²δ)⌉``, eq. (15);
- :func:`hoeffding_rays`: the exponential Chebyshev (Hoeffding) bound,
  ``N = ⌈ln(2/δ)/(2μ²)⌉``, eq. (20)/(23) — the default of virtspec-mi;
- :func:`exact_rays`: the exact binomial rule (not in the paper, see below).

The inverses (:func:`chebyshev_mu`, :func:`hoeffding_mu`) give the tolerance that N
rays guarantee at δ, and :func:`miss_probability` is the *exact* probability that a
reading of N rays misses ρ by μ or more (used to test the instrument's statistics).

Beyond the paper, :func:`exact_rays` is the smallest fixed N whose *exact* binomial
failure probability ``sup_ρ P(|m/N − ρ| ≥ μ)`` is ≤ δ (:func:`max_miss_probability`):
the same rigorous guarantee as eq. (23) with about 0.63× the rays at μ = 0.005,
δ = 0.01 (66,501 instead of 105,967). The adaptive ``"two-stage"`` rule lives in
:mod:`virtspec_mi.budgets.twostage`.

Validation: the public functions here are entries users call (``vm.hoeffding_rays``,
``virtspec bounds``, the notebooks): each checks its arguments once
(:func:`virtspec_mi.base.checks.validated`). The rule objects of
:mod:`virtspec_mi.budgets.rules` and the other budget modules hold validated values
(the settings and options dataclasses check them) and call the trusting bodies,
``hoeffding_rays.unchecked`` and so on.

References
----------
Baranoski, G.V.G., Rokne, J.G., Xu, G. (2001). Virtual spectrophotometric
measurements for biologically and physically based rendering. The Visual Computer
17, 506–518: eqs. (10)–(23) and Table 1.

Hoeffding, W. (1963). Probability inequalities for sums of bounded random variables.
J. Amer. Statist. Assoc. 58, 13–30 (the exponential bound behind eq. (23)).

The exact failure probability, its lattice jump points and the exact rule's N (66,501
at μ = 0.005, δ = 0.01) are computed by this module (:func:`max_miss_probability`,
:func:`exact_rays`); ``tools/budget_tables.py`` tabulates them into
:mod:`virtspec_mi.budgets.tables` and ``tests/budgets/test_tables.py`` recomputes the tables.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from virtspec_mi.base.checks import MAX_RAYS, check_delta, check_mu, check_rays, validated

__all__ = [
    "chebyshev_rays",
    "hoeffding_rays",
    "chebyshev_mu",
    "hoeffding_mu",
    "exact_rays",
    "exact_mu",
    "exact_certified",
    "stated_mu",
    "EXACT_MU_MAX_RAYS",
    "EXACT_MAX_POINTS",
    "miss_probability",
    "max_miss_probability",
    "Table1Row",
    "table_1",
    "format_table_1",
]


def _any_rays(rays: Any) -> int:
    """A number of rays ≥ 1 of any size (a tolerance may be asked of more rays than one reading traces)."""

    return check_rays(rays, math.inf)


@validated(mu=check_mu, delta=check_delta)
def chebyshev_rays(mu: float, delta: float) -> int:
    """
    Rays the ordinary Chebyshev inequality needs: ``⌈1/(4μ²δ)⌉``.

    References
    ----------
    Baranoski et al. (2001), eq. (15).
    """

    return _ceil(_ratio(1.0, 4.0 * mu * mu * delta), "chebyshev", mu, delta)


@validated(mu=check_mu, delta=check_delta)
def hoeffding_rays(mu: float, delta: float) -> int:
    """
    Rays the exponential Chebyshev (Hoeffding) inequality needs: ``⌈ln(2/δ)/(2μ²)⌉``.

    References
    ----------
    Baranoski et al. (2001), eqs. (20) and (23); μ = 0.005, δ = 0.01 gives 105,967.
    """

    return _hoeffding(mu, delta, "hoeffding")


def _hoeffding(mu: float, delta: float, rule: str) -> int:
    """Eq. (23); ``rule`` names the bound in the message when N overflows."""

    return _ceil(_ratio(math.log(2.0 / delta), 2.0 * mu * mu), rule, mu, delta)


@validated(rays=_any_rays, delta=check_delta)
def chebyshev_mu(rays: int, delta: float) -> float:
    """Tolerance μ that ``rays`` rays guarantee at δ under eq. (14): ``μ = 1/(2√(Nδ))``."""

    return 1.0 / (2.0 * math.sqrt(rays * delta))


@validated(rays=_any_rays, delta=check_delta)
def hoeffding_mu(rays: int, delta: float) -> float:
    """Tolerance μ that ``rays`` rays guarantee at δ under eq. (19): ``μ = √(ln(2/δ)/(2N))``."""

    return math.sqrt(math.log(2.0 / delta) / (2.0 * rays))


@validated(rays=_any_rays, mu=check_mu)
def max_miss_probability(rays: int, mu: float, lo: float = 0.0, hi: float = 1.0) -> float:
    """
    ``sup_{ρ ∈ [lo, hi]} P(|m/N − ρ| ≥ μ)``, exactly, for ``m ~ Binomial(N, ρ)``.

    The miss probability is ``P(m ≤ a) + P(m ≥ b)`` with ``a = ⌊N(ρ − μ)⌋`` and
    ``b = ⌈N(ρ + μ)⌉``. Between consecutive *lattice jump points* ``ρ = a/N + μ``
    (where ``m = a`` joins the lower tail) and ``ρ = b/N − μ`` (where ``m = b`` joins
    the upper tail) a and b are fixed, so the miss probability is
    ``1 − P(a < m < b)``, and the probability of a fixed window of counts is
    unimodal in ρ (the ratio of the binomial pmf at its two ends is monotone in ρ).
    The miss probability is therefore quasi-convex on each piece and its supremum
    over [lo, hi] is attained at a jump point or at lo or hi, where both tails are
    taken inclusive: evaluating those points (vectorised) gives the exact supremum.
    ``P(m ≥ b, ρ) = P(N − m ≤ N − b, 1 − ρ)`` makes it symmetric about ρ = ½, so only
    half of the interval is evaluated when it straddles ½.

    ``tests/budgets/test_bounds.py`` checks the supremum against the whole binomial pmf on a
    dense grid of ρ.
    """

    from scipy import special

    n = int(rays)
    lo, hi = max(0.0, float(lo)), min(1.0, float(hi))
    if not lo <= hi:
        raise ValueError(f"lo and hi must satisfy 0 <= lo <= hi <= 1 (got {lo:g}, {hi:g})")
    if _lattice_points(n, mu, lo, hi) > EXACT_MAX_POINTS:
        raise ValueError(f"rays = {n:,} at mu = {mu!r} over [{lo:g}, {hi:g}] needs the exact law at about "
                         f"{_lattice_points(n, mu, lo, hi):,.0f} lattice points; at most {EXACT_MAX_POINTS:,} "
                         "are evaluated (about 8 s and 0.5 GB)")
    if lo > 0.5:  # mirror into the lower half
        lo, hi = 1.0 - hi, 1.0 - lo
    elif hi > 0.5:
        lo, hi = min(lo, 1.0 - hi), 0.5
    lower = np.arange(max(0, math.floor(n * (lo - mu))), math.ceil(n * (hi - mu)) + 1) / n + mu
    upper = np.arange(max(0, math.floor(n * (lo + mu))), math.ceil(n * (hi + mu)) + 1) / n - mu
    rho = np.concatenate([lower, upper, [lo, hi]])
    rho = rho[(rho >= lo) & (rho <= hi)]
    # Inclusive tails at the jump points: the 1e-9 forgives the rounding of a/N + μ.
    a = np.floor(n * (rho - mu) + 1e-9)
    b = np.ceil(n * (rho + mu) - 1e-9)
    miss = np.where(a >= 0, special.bdtr(np.maximum(a, 0), n, rho), 0.0)
    miss = miss + np.where(b <= n, special.bdtrc(np.clip(b - 1, 0, n), n, rho), 0.0)
    return float(miss.max())


EXACT_MAX_POINTS: int = 4_000_000
"""
Most lattice points at which :func:`max_miss_probability` evaluates the exact law in one
call (about N·(hi − lo + 2μ)): about 8 s and 0.5 GB on this project's machine. Beyond
it :func:`max_miss_probability` refuses and :func:`exact_rays` returns Hoeffding's N,
which certifies every ρ (at most 1.6× the exact N): at ρ over [0, 1] this happens below
μ ≈ 0.0007 (δ = 0.01).
"""


def _lattice_points(n: int, mu: float, lo: float, hi: float) -> float:
    """About how many points :func:`max_miss_probability` evaluates for N = ``n`` over [lo, hi]."""

    return n * min(1.0, hi - lo + 2.0 * mu)


@validated(mu=check_mu, delta=check_delta)
def exact_rays(mu: float, delta: float, lo: float = 0.0, hi: float = 1.0) -> int:
    """
    Smallest fixed N certified by the exact binomial law: ``sup_ρ P(|m/N − ρ| ≥ μ) ≤ δ``
    for N and every larger number of rays (ρ over [lo, hi]; all of [0, 1] by default).

    The failure probability is *not* monotone in N. The acceptance window
    ``N(ρ − μ) < m < N(ρ + μ)`` holds, in the worst case, ``⌈2μN⌉ − 1`` counts; within
    each *period* of N over which that number is constant (1/(2μ) rays long) the
    worst-case failure grows with N (the same counts cover a shrinking share of a
    widening binomial) and it drops at the start of the next period. At μ = 0.005,
    δ = 0.01 the N = 66,401 … 66,452 pass, 66,453 … 66,500 fail and every N from
    66,501 on passes. The rule returns the first N of the first period whose last
    N passes (66,501), found from the normal approximation by stepping over periods,
    and verifies with :func:`max_miss_probability` the returned N and the ends of the
    next two periods (so "N or more rays" is certified, which the two-stage rule
    relies on when it takes the largest of several N). Where that would evaluate the
    exact law at more than :data:`EXACT_MAX_POINTS` lattice points (below μ ≈ 0.0007
    over all of [0, 1]) it returns Hoeffding's N instead, which certifies every ρ and
    every larger N (and is never smaller). Results are cached, and the
    common (μ, δ) ship in a table (``virtspec_mi.budgets.tables``), so choosing N costs
    microseconds there; other (μ, δ) take one search per process (milliseconds at
    μ ≥ 0.02, seconds at μ = 0.005, about 30 s at μ = 0.001).

    At μ = 0.005, δ = 0.01 it gives 66,501 rays, 37.2 % fewer than eq. (23)'s 105,967
    (``tests/budgets/test_bounds.py`` checks N − 1 and every N up to Hoeffding's by brute force).
    """

    lo, hi = max(0.0, float(lo)), min(1.0, float(hi))
    if (lo, hi) == (0.0, 1.0) and (mu, delta) in _shipped_exact():
        return _shipped_exact()[(mu, delta)]
    return _exact_rays(mu, delta, lo, hi)


def _shipped_exact() -> dict[tuple[float, float], int]:
    """exact_rays at common (μ, δ), from ``virtspec_mi.budgets.tables`` (tests recompute them)."""

    try:
        from virtspec_mi.budgets.tables import EXACT
    except ImportError:  # while tools/budget_tables.py regenerates the tables
        return {}
    return EXACT


@functools.lru_cache(maxsize=4096)
def _exact_rays(mu: float, delta: float, lo: float, hi: float) -> int:
    from scipy import stats

    # Hoeffding's N (and every larger N) is certified for any interval: never go beyond it,
    # nor evaluate the exact law where that costs more than EXACT_MAX_POINTS points.
    ceiling = _hoeffding(mu, delta, "exact")

    class _TooCostly(Exception):
        pass

    def passes(n: int) -> bool:
        if _lattice_points(n, mu, lo, hi) > EXACT_MAX_POINTS:
            raise _TooCostly
        return max_miss_probability.unchecked(n, mu, lo, hi) <= delta

    try:
        return _search_exact(passes, mu, delta, lo, hi, ceiling, stats.norm.isf(delta / 2))
    except _TooCostly:
        return ceiling


def _search_exact(passes: Any, mu: float, delta: float, lo: float, hi: float, ceiling: int, z: float) -> int:
    """The period search of :func:`exact_rays` (``passes(N)``: the exact law holds at N)."""

    def start(j: int) -> int:  # first N of period j: 2μN > j − 1
        return max(1, math.floor((j - 1) / (2 * mu) * (1 + 1e-12)) + 1)

    def end(j: int) -> int:  # last N of period j: 2μN ≤ j
        return start(j + 1) - 1

    worst = min(max(0.5, lo), hi) if lo <= 0.5 else lo  # the ρ in [lo, hi] nearest ½
    guess = max(1.0, z * z * worst * (1 - worst) / (mu * mu))
    j = max(1, math.ceil(2 * mu * guess))
    if passes(end(j)):
        while j > 1 and passes(end(j - 1)):
            j -= 1
    else:
        while not passes(end(j)):
            j += 1
            if start(j) >= ceiling:
                return ceiling
    while not (passes(start(j)) and passes(end(j + 1)) and passes(end(j + 2))):
        j += 1
        if start(j) >= ceiling:
            return ceiling
    return start(j)


EXACT_MU_MAX_RAYS: int = 20_000
"""Largest N for which :func:`exact_mu` inverts the exact law by bisection (≤ 0.5 s);
above it the Hoeffding tolerance (eq. 19), valid for any N, is returned instead."""


@validated(rays=_any_rays, delta=check_delta)
@functools.lru_cache(maxsize=1024)
def exact_mu(rays: int, delta: float) -> float:
    """
    Tolerance μ that ``rays`` rays guarantee at δ under the exact binomial law: the
    smallest μ (to 10⁻⁶ relative, rounded up) with ``max_miss_probability(N, μ) ≤ δ``,
    i.e. ``P(|m/N − ρ| ≥ μ) ≤ δ`` for every ρ. The miss probability falls as μ grows,
    so bisection finds it. For N above :data:`EXACT_MU_MAX_RAYS` the bisection would
    cost seconds; Hoeffding's μ (eq. 19), which holds for every N and every ρ and is at
    most ~25 % larger, is returned then.

    References
    ----------
    Baranoski et al. (2001), eq. (19); the exact law of :func:`max_miss_probability`.
    """

    upper = hoeffding_mu.unchecked(rays, delta)
    if rays > EXACT_MU_MAX_RAYS or upper >= 0.5:
        return upper
    lower = 0.0
    while upper - lower > 1e-6 * upper:
        middle = 0.5 * (lower + upper)
        if max_miss_probability.unchecked(rays, middle) <= delta:
            upper = middle
        else:
            lower = middle
    return upper


def stated_mu(rays: int, mu: float, tolerance: float, rays_for_mu: Callable[[], int]) -> float:
    """
    The tolerance a reading of ``rays`` rays may state when μ was asked for, under a rule
    whose tolerance of those rays is ``tolerance`` and whose N for μ is ``rays_for_mu()``:
    μ itself where the rule certifies μ for these rays (N ≥ the rule's N; every rule here
    certifies N and all larger N), else ``tolerance`` — and never more than ``tolerance``.
    A rule whose N for μ is beyond any float (μ ~ 1e-300: ``ValueError``) certifies
    ``tolerance`` only. Values are trusted (validated where they entered).
    """

    if tolerance <= mu:
        return tolerance
    try:
        needed = rays_for_mu()
    except ValueError:  # the rule's N is beyond any float: these rays are fewer
        return tolerance
    return mu if rays >= needed else tolerance


def exact_certified(rays: int, delta: float, mu: float) -> float:
    """
    :func:`stated_mu` under the exact rule: below :data:`EXACT_MU_MAX_RAYS` rays the exact
    inverse :func:`exact_mu` (no search for N), above it μ where ``rays`` ≥ the exact
    rule's N for (μ, δ), else Hoeffding's tolerance. Values are trusted.
    """

    tolerance = exact_mu.unchecked(int(rays), delta)
    if rays <= EXACT_MU_MAX_RAYS:
        return tolerance
    return stated_mu(rays, mu, tolerance, lambda: exact_rays.unchecked(mu, delta))


@validated(rays=_any_rays, mu=check_mu)
def miss_probability(rays: int, rho: float, mu: float) -> float:
    """
    Exact probability that a reading of ``rays`` rays misses ρ by μ or more.

    ``P(|m/N − ρ| ≥ μ)`` with ``m ~ Binomial(N, ρ)``: the quantity the bounds of
    eqs. (10) and (17) majorise. The statistical tests compare observed miss counts
    with this number instead of with δ (a "≤ δ" check has almost no power).
    """

    from scipy import stats

    n = int(rays)
    # m ≤ N(ρ − μ) or m ≥ N(ρ + μ); the 1e-9 guards the lattice points against rounding.
    low = math.floor(n * (rho - mu) + 1e-9)
    high = math.ceil(n * (rho + mu) - 1e-9)
    lower = stats.binom.cdf(low, n, rho) if low >= 0 else 0.0
    upper = stats.binom.sf(high - 1, n, rho) if high <= n else 0.0
    return float(lower + upper)


@dataclass(frozen=True)
class Table1Row:
    """One row of the paper's Table 1: rays under both bounds at one δ."""

    delta: float
    chebyshev_rays: int
    hoeffding_rays: int

    @property
    def chebyshev_log10(self) -> float:
        return math.log10(self.chebyshev_rays)

    @property
    def hoeffding_log10(self) -> float:
        return math.log10(self.hoeffding_rays)


def table_1(mu: float = 0.005, deltas: Sequence[float] = (0.001, 0.01, 0.1)) -> list[Table1Row]:
    """
    The paper's Table 1: rays under eq. (15) and eq. (23) for each δ at μ.

    References
    ----------
    Baranoski et al. (2001), Table 1.
    """

    return [Table1Row(d, chebyshev_rays(mu, d), hoeffding_rays(mu, d)) for d in deltas]


# Table 1 as printed in the paper (δ → ordinary, exponential log10 N), to flag differences.
_PAPER_TABLE_1 = {0.001: (7.0, 5.18), 0.01: (6.0, 5.02), 0.1: (5.0, 4.77)}


def format_table_1(mu: float = 0.005, deltas: Sequence[float] = (0.001, 0.01, 0.1)) -> str:
    """Table 1 as text: N and log10 N to two decimals, with the paper's value where it differs."""

    lines = [
        f"Rays per reading for |m/N - rho| < mu = {mu:g} with probability >= 1 - delta",
        f"{'delta':>8}  {'Chebyshev N (15)':>17} {'log10':>6}  {'Hoeffding N (23)':>17} {'log10':>6}  note",
    ]
    notes = []
    for row in table_1(mu, deltas):
        paper = _PAPER_TABLE_1.get(row.delta) if mu == 0.005 else None
        note = ""
        if paper is not None:
            diffs = [
                f"paper {p:.2f}"
                for p, v in zip(paper, (row.chebyshev_log10, row.hoeffding_log10))
                if f"{p:.2f}" != f"{v:.2f}"
            ]
            if diffs:
                note = "; ".join(diffs) + " (truncated, not rounded)"
                notes.append(row.delta)
        lines.append(
            f"{row.delta:>8g}  {row.chebyshev_rays:>17,d} {row.chebyshev_log10:>6.2f}  "
            f"{row.hoeffding_rays:>17,d} {row.hoeffding_log10:>6.2f}  {note}"
        )
    if notes:
        lines.append(
            "The paper prints log10 N truncated to two decimals; the values here are rounded."
        )
    return "\n".join(lines)


def _ratio(numerator: float, denominator: float) -> float:
    """numerator / denominator, ``inf`` where the denominator underflowed to 0 (μ ≈ 1e-300)."""

    return numerator / denominator if denominator > 0.0 else math.inf


def _ceil(x: float, rule: str, mu: float, delta: float) -> int:
    """
    ⌈x⌉ that forgives floating-point noise just above an integer (e.g. 1e6 + 1e-10);
    ``ValueError`` naming the rule, μ and δ when x is beyond the float range.
    """

    if not math.isfinite(x):
        raise ValueError(f"the {rule} bound for mu = {mu!r}, delta = {delta!r} needs more than 1.8e308 rays per "
                         f"reading; one reading may trace at most {MAX_RAYS:,} (2**32 - 1): raise mu or delta")
    nearest = round(x)
    return int(nearest) if abs(x - nearest) <= 1e-9 * max(1.0, abs(x)) else int(np.ceil(x))
