"""
Two-stage certified readings: a pilot batch sizes a fresh second batch
======================================================================

The fixed rules of :mod:`virtspec_mi.budgets.bounds` size every reading for the worst case
ρ = ½. The ``"two-stage"`` rule spends a small pilot batch per reading to learn where
ρ lies, then sizes the reading for that region only:

1. trace ``n₁`` pilot rays (default ``⌈10/μ⌉``: 2,000 at μ = 0.005) and take the
   Clopper–Pearson interval [lo, hi] of each certified quantity at δ₁
   (default δ/10: 0.001 at δ = 0.01; :func:`virtspec_mi.budgets.intervals.clopper_pearson`);
2. trace ``N₂ = exact_rays(μ, δ − δ₁, lo, hi)`` *fresh* rays — the smallest N
   (and every larger one) whose exact binomial failure probability is ≤ δ − δ₁ for
   every ρ in the interval (:func:`virtspec_mi.budgets.bounds.exact_rays`) — taking the
   largest N₂ over the quantities;
3. report the second batch's counts only.

Guarantee: the pilot interval misses ρ with probability ≤ δ₁; when it holds, N₂ is
certified for ρ, and the second batch's rays are independent of the pilot (so of N₂),
hence ``P(|m/N₂ − ρ| ≥ μ) ≤ δ₁ + (δ − δ₁) = δ`` for each quantity, as for a fixed rule.
With ``joint=True`` reflectance and transmittance are certified *together*: each
pilot interval at δ₁/2 and each sizing at (δ − δ₁)/2 (Bonferroni), so both are within
μ at once with probability ≥ 1 − δ.

Rays per reading: 2,000 + N₂, on average 19,393 / 50,524 / 70,401 at ρ = 0.05 / 0.2 /
0.5 (μ = 0.005, δ = 0.01; :func:`two_stage_law` computes them exactly) against
105,967 for eq. (23).

Validation: :func:`two_stage_law` is an entry users call and checks its arguments
once; the sizing (:func:`stage_two_rays`) and the defaults take the settings' validated
values (:class:`virtspec_mi.settings.Settings` checks μ, δ, n₁ and 0 < δ₁ < δ).

References
----------
Clopper, C.J., Pearson, E.S. (1934). Biometrika 26, 404–413 (the pilot's interval).
Baranoski et al. (2001), eq. (23), for comparison. The expected rays and the exact
miss probability are computed by :func:`two_stage_law` (the mixture over the pilot
count); ``tools/budget_tables.py`` tabulates the sizing at the defaults and
``tests/budgets/test_tables.py`` recomputes it.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from virtspec_mi.budgets.bounds import exact_rays, hoeffding_rays, miss_probability
from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.base.checks import check_delta, check_mu, check_rays, validated

__all__ = [
    "STAGE_TWO_SEED_MASK",
    "default_pilot_rays",
    "default_pilot_delta",
    "stage_two_seed",
    "stage_two_rays",
    "most_second_rays",
    "TwoStageLaw",
    "two_stage_law",
]

STAGE_TWO_SEED_MASK: int = 0x5BD1E995
"""The second batch traces with ``seed XOR`` this mask: a different random stream from
the pilot's (which uses ``seed``), so its rays are fresh; the map is a bijection of seeds."""


def default_pilot_rays(mu: float) -> int:
    """Default pilot size ``⌈10/μ⌉`` (2,000 at μ = 0.005) for a validated μ."""

    rays = 10.0 / mu - 1e-9
    if not math.isfinite(rays):
        raise ValueError(f"the default two-stage pilot ceil(10/mu) for mu = {mu!r} is beyond the float range; "
                         "give pilot_rays (1 ... 2**32 - 1)")
    return math.ceil(rays)


def default_pilot_delta(delta: float) -> float:
    """Default pilot failure probability δ₁ = δ/10 (0.001 at δ = 0.01) for a validated δ."""

    return delta / 10.0


def stage_two_seed(seed: int) -> int:
    """Seed of the second batch: ``seed XOR`` :data:`STAGE_TWO_SEED_MASK` (≠ ``seed``)."""

    return int(seed) ^ STAGE_TWO_SEED_MASK


def stage_two_rays(
    pilot_counts: Any,
    pilot_rays: int,
    mu: float,
    delta: float,
    pilot_delta: float,
    joint: bool = False,
) -> np.ndarray:
    """
    Second-batch rays N₂ per reading from its pilot counts.

    Parameters
    ----------
    pilot_counts
        Shape ``(readings, quantities)``: per reading the pilot's count of each certified
        quantity (reflected, transmitted, absorbed; or reflected, transmitted with ``joint``).
    pilot_rays, mu, delta, pilot_delta
        n₁, μ, the reading's δ and the pilot's δ₁ (0 < δ₁ < δ), validated by the settings.
    joint
        Certify the quantities together: δ₁ and δ − δ₁ are split evenly over them.

    Returns
    -------
    ndarray of int64
        The largest N₂ over the quantities of each reading.

    The one check left is the caller's contract, which no user input reaches: every count
    is a count of the pilot's rays (0 ≤ count ≤ n₁).
    """

    counts = np.atleast_2d(np.asarray(pilot_counts, dtype=np.int64))
    n1 = int(pilot_rays)
    if np.any(counts < 0) or np.any(counts > n1):
        raise ValueError(f"pilot_counts must satisfy 0 <= count <= pilot_rays = {n1}")
    return _sizing(counts, n1, mu, delta, pilot_delta, bool(joint))


def most_second_rays(mu: float, delta: float, pilot_delta: float, quantities: int = 1) -> int:
    """
    The most rays a second batch can get when ``quantities`` columns are certified together
    (δ₁ and δ − δ₁ split evenly over them; 1: each column on its own): Hoeffding's N at
    (δ − δ₁)/quantities — the exact rule over any interval of ρ never needs more. The key
    range a keyed run reserves for a two-stage reading.
    """

    return hoeffding_rays(mu, (delta - pilot_delta) / quantities)


def _sizing(counts: np.ndarray, n1: int, mu: float, delta: float, pilot_delta: float, joint: bool) -> np.ndarray:
    """:func:`stage_two_rays` of valid counts (:func:`two_stage_law` calls it directly)."""

    share = counts.shape[1] if joint else 1
    d1, d2 = pilot_delta / share, (delta - pilot_delta) / share
    shipped = None if joint and share != 2 else _shipped_stage_two().get((mu, delta, n1, pilot_delta, joint))
    if shipped is not None:
        return np.asarray(shipped, dtype=np.int64)[counts].max(axis=1)
    table = {k: _rays_for_count(int(k), n1, mu, d2, d1) for k in np.unique(counts)}
    return np.array([max(table[k] for k in row) for row in counts], dtype=np.int64)


def _shipped_stage_two() -> dict:
    try:
        from virtspec_mi.budgets.tables import STAGE_TWO
    except ImportError:  # while tools/budget_tables.py regenerates the tables
        return {}
    return STAGE_TWO


@functools.lru_cache(maxsize=65536)
def _rays_for_count(k: int, n1: int, mu: float, delta2: float, delta1: float) -> int:
    """N₂ for a pilot count k of n₁: the exact rule at δ₂ over the Clopper–Pearson interval at δ₁."""

    lower, upper = clopper_pearson.unchecked(k, n1, delta1)
    return exact_rays.unchecked(mu, delta2, float(lower), float(upper))


@dataclass(frozen=True)
class TwoStageLaw:
    """Exact behaviour of the two-stage rule for a quantity of true value ρ."""

    rho: float
    expected_rays: float
    """E[n₁ + N₂]: all rays traced per reading, pilot included."""
    expected_second_rays: float
    """E[N₂]: rays behind the estimate."""
    miss_probability: float
    """P(|m/N₂ − ρ| ≥ μ), the exact mixture over the pilot count."""


@validated(mu=check_mu, delta=check_delta, pilot_rays=lambda value: check_rays(value, name="pilot_rays"),
           pilot_delta=lambda value: check_delta(value, name="pilot_delta"))
def two_stage_law(
    rho: float,
    mu: float,
    delta: float,
    pilot_rays: int | None = None,
    pilot_delta: float | None = None,
    joint: bool = False,
    other: str = "transmitted",
    tail: float = 1e-12,
) -> TwoStageLaw:
    """
    Exact expected rays and miss probability of the two-stage rule for a specimen whose
    rays are reflected with probability ρ and otherwise ``other`` (``"transmitted"``,
    e.g. diamond, or ``"absorbed"``, e.g. an opaque diffuse), the third fate never occurring.

    ``E[N] = Σ_k Bin(k; n₁, ρ) (n₁ + N₂(k))`` and
    ``P(miss) = Σ_k Bin(k; n₁, ρ) P(|m/N₂(k) − ρ| ≥ μ)``, with N₂(k) the sizing
    :func:`stage_two_rays` makes from the pilot counts (reflected, transmitted,
    absorbed) = (k, n₁ − k, 0) or (k, 0, n₁ − k) (without the absorbed column with
    ``joint``). Pilot counts of probability below ``tail`` are left out; their
    total mass is added to ``miss_probability`` (an upper bound, not an estimate).

    The two-stage design and these two sums are those of Clopper & Pearson's interval
    followed by the exact rule; ``tests/budgets/test_twostage.py`` checks them against the
    expected rays 19,393 / 50,524 / 70,401 at ρ = 0.05 / 0.2 / 0.5 (μ = 0.005, δ = 0.01).
    """

    from scipy import stats

    n1 = default_pilot_rays(mu) if pilot_rays is None else pilot_rays
    d1 = default_pilot_delta(delta) if pilot_delta is None else pilot_delta
    if not d1 < delta:
        raise ValueError(f"pilot_delta must satisfy 0 < pilot_delta < delta = {delta:g} (got {d1:g})")
    k = np.arange(n1 + 1)
    weights = stats.binom.pmf(k, n1, rho)
    keep = weights >= tail
    k, weights, left_out = k[keep], weights[keep], float(weights[~keep].sum())
    if other not in ("transmitted", "absorbed"):
        raise ValueError(f"other must be 'transmitted' or 'absorbed' (got {other!r})")
    zeros = np.zeros_like(k)
    columns = [k, n1 - k, zeros] if other == "transmitted" else [k, zeros, n1 - k]
    counts = np.stack(columns[:2] if joint else columns, axis=1)
    n2 = _sizing(counts, n1, mu, delta, d1, bool(joint))
    miss = np.array([miss_probability.unchecked(int(n), rho, mu) for n in n2])
    total = weights.sum()
    return TwoStageLaw(
        rho=float(rho),
        expected_rays=float(n1 + (weights * n2).sum() / total),
        expected_second_rays=float((weights * n2).sum() / total),
        miss_probability=float((weights * miss).sum() + left_out),
    )
