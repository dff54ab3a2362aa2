"""
Betting confidence sequences for weighted sums of proportions
=============================================================

A derived quantity L = Σₖ wₖ pₖ (weights of any sign) of per-wavelength proportions pₖ
(each the probability that a ray of stratum k ends in one fate) is certified here by a
*stratified betting confidence sequence*: an interval that holds, with probability
≥ 1 − δ, at every batch at once — so sampling may stop at the first batch at which it
is narrow enough, and rays may go to the strata where they help most, chosen from what
the earlier batches showed (Spertus, Sridhar & Stark 2024; one stratum: Waudby-Smith &
Ramdas 2023).

**Orientation.** Write μₖ = pₖ where wₖ > 0 and μₖ = 1 − pₖ (the complementary fate,
counts nₖ − kₖ) where wₖ < 0, aₖ = |wₖ|: L = Σ_{wₖ<0} wₖ + Σₖ aₖ μₖ. A lower bound on
S = Σₖ aₖ μₖ gives a lower bound on L; the upper bound on L is the lower bound of −L
(weights −w) turned round. Each side is stated at δ/2.

**The capital.** In batch b stratum k draws nₖᵦ rays (a number fixed before the batch
is drawn), of which kₖᵦ land in the oriented fate. For a null mean m of the stratum the
bettor stakes λₖᵦ ≥ 0 per ray while m < uₖᵦ and nothing for m ≥ uₖᵦ; λ and u are chosen
from earlier batches only (*predictable*) and λ ≤ :data:`MAX_BET` < 1. With the stake
fixed within the batch, the stratum's capital after B batches is a function of its counts:

    Kₖ(m) = Πᵦ [ (1 + λₖᵦ(1 − m))^kₖᵦ · (1 − λₖᵦ m)^(nₖᵦ − kₖᵦ) ]^[m < uₖᵦ]           (1)

**Theorem** (Ville's maximal inequality for non-negative supermartingales, Ville 1939;
used as here by Spertus, Sridhar & Stark 2024 — independent test supermartingales per
stratum multiplied, a union of intersection nulls — and, for one stratum, by
Waudby-Smith & Ramdas 2023 — the betting capital process). With μ* the true oriented
means, P(∃B: Πₖ Kₖ(μ*ₖ) ≥ 1/α) ≤ α. Hence the set

    C_B = { s : min_{m ∈ [0,1]ᴷ, Σₖ aₖ mₖ ≤ s} Σₖ log Kₖ(mₖ) < log(1/α) }              (2)

contains S = Σₖ aₖ μ*ₖ at every B at once with probability ≥ 1 − α, and C_B = [s_B, ∞).

*Proof sketch.* Fix the true μ*. Order the rays of a batch in any fixed way; ray i of
stratum k multiplies Kₖ(μ*ₖ) by 1 + λ(yᵢ − μ*ₖ) (or by 1 when μ*ₖ ≥ u), a non-negative
factor (λ ≤ MAX_BET < 1) whose conditional mean given everything before it is 1: the ray
is a fresh Bernoulli(μ*ₖ) draw, independent of the past, and λ, u and the decision to
draw it were fixed before it (allocation and bets use earlier batches only). So
M = Πₖ Kₖ(μ*ₖ) is a non-negative martingale with M₀ = 1 in the filtration of the rays,
whatever the allocation rule, and Ville's inequality gives P(supₜ Mₜ ≥ 1/α) ≤ α; the
bound holds at every time, hence at any stopping time (a rule that stops once the
interval is narrow enough). If S ≤ s, μ* is one of the m in (2), so s is excluded only
when M ≥ 1/α. ∎

**Exact and conservative computation.** Between consecutive thresholds uₖᵦ the set of
active batches is fixed and every term of log Kₖ is the logarithm of a positive affine
function of m: concave. For any ν ≥ 0 (weak Lagrangian duality),

    min_{Σ aₖmₖ ≤ s} Σₖ log Kₖ(mₖ) ≥ Σₖ hₖ(ν) − ν s,   hₖ(ν) = min_{m∈[0,1]} log Kₖ(m) + ν aₖ m,

and hₖ is found *exactly*: on each piece log Kₖ(m) + ν aₖ m is concave, so its infimum is
at an end of the piece (the right end as a limit from the left). Every s ≤ s(ν) =
(Σₖ hₖ(ν) − log(1/α))/ν is therefore excluded, for every ν > 0: the bound reported is
the largest s(ν) found over a search of ν. A poor ν, a search that stops short, or the
duality gap (the relaxation replaces each log Kₖ by its convex envelope) can only lower
s(ν), i.e. widen the interval, never narrow it; each logarithm is lowered by a
relative 10⁻¹² before use so that floating-point rounding cannot narrow it either.
With one stratum no relaxation is needed: (2) is solved directly (log K₁ is
non-increasing in m on [0, u) and the bound is found by bisection, kept on the side
that is certainly excluded).

**The stakes** (:func:`stakes`). For a planned tolerance t of L and prior variances
v̂ₖ = p̃ₖ(1 − p̃ₖ) (from earlier batches, or a pilot), batch b stakes
λₖᵦ = t·Iᵦ·aₖ/nₖᵦ with Iᵦ = 1/Σₖ aₖ² v̂ₖ/nₖᵦ. To second order the batch then adds
t·Iᵦ·(Ŝᵦ − s) − t²Iᵦ/2 to (2) for every m with Σ aₖmₖ = s: a test of the weighted sum
with information Iᵦ, and the certified half-width after batches of total information I
is about t/2 + log(1/α)/(t·I), which reaches t at I = 2 log(1/α)/t² — the Gaussian
optimum (Hoeffding needs (Σₖ aₖ)²/(4 (Σₖ aₖ √vₖ)²) times as many rays). The threshold
uₖᵦ = p̃ₖ + 5 σ̃ₖ keeps the relaxation close: the stake is nothing above it, so a null
mean far above the data buys the adversary nothing. σ̃ₖ is the standard error of the
batch's mean about p̃ₖ, at the largest variance p(1 − p) within 3 standard errors of
p̃ₖ (a small count understates the variance).
Validity never depends on these choices; only the width does.

References
----------
Spertus, J. V., Sridhar, M. & Stark, P. B. (2024). Sequential stratified inference for
the mean. arXiv:2409.06680 (intersection–union test supermartingales combined across
strata by multiplication; bets and stratum selection that may depend on the null and
on the sample so far).
Waudby-Smith, I. & Ramdas, A. (2023). Estimating means of bounded random variables by
betting. *J. R. Stat. Soc. B* 86(1), 1–27 (the capital process of a bounded mean and
its confidence sequence).
Ville, J. (1939). *Étude critique de la notion de collectif*. Gauthier-Villars (the
maximal inequality for non-negative supermartingales).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["CERTIFICATES", "MAX_BET", "THRESHOLD_SIGMAS", "LADDER", "Side", "lower_bound", "stratified_interval", "stakes",
           "prior_variances", "neyman_rays", "BettingSequence"]

CERTIFICATES: dict[str, str] = {
    "auto": "a target's default: two-stage (pooled) for a linear target of one-signed weights, betting for any other",
    "betting": "a target: batches until a stratified betting confidence sequence certifies it",
}
"""
The certificates a *target* takes as ``bound`` besides ``two-stage`` and ``hoeffding``
(a spectrum's rules, ``budgets.rules``, which a target's pooled readings follow too).
"""

MAX_BET: float = 0.5
"""The largest stake per ray: every factor of eq. (1) stays ≥ 1 − MAX_BET > 0."""

THRESHOLD_SIGMAS: float = 5.0
"""uₖᵦ = p̃ₖ + THRESHOLD_SIGMAS · (standard error of p̃ₖ): no stake on null means above it."""

_ROUNDING: float = 1e-12
"""Relative amount each log-capital is lowered by before use (floating-point rounding only widens)."""


def _check(a: np.ndarray, rays: np.ndarray, hits: np.ndarray, bets: np.ndarray, floors: np.ndarray,
           caps: np.ndarray, alpha: float) -> None:
    if not 0 < alpha < 1:
        raise ValueError(f"alpha must lie in (0, 1) (got {alpha!r})")
    if np.any(a < 0) or not np.all(np.isfinite(a)):
        raise ValueError("weights of the oriented sum must be finite and >= 0")
    shape = rays.shape
    if rays.ndim != 2 or shape[1] != len(a) or any(x.shape != shape for x in (hits, bets, floors, caps)):
        raise ValueError(f"rays, hits, bets, floors and caps must be (batches, {len(a)}) arrays of one shape")
    if np.any(hits < 0) or np.any(hits > rays):
        raise ValueError("hits must lie in [0, rays] in every batch and stratum")
    if np.any(bets < 0) or np.any(bets > MAX_BET) or not np.all(np.isfinite(bets)):
        raise ValueError(f"bets must lie in [0, {MAX_BET}]")


def _log_capital(rays: np.ndarray, hits: np.ndarray, bets: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Σᵦ of eq. (1)'s logarithm at null means ``m`` (shape (P,)) over the batches given (1-d, all staking), lowered."""

    m = np.asarray(m, dtype=np.float64)[:, None]
    up = hits[None, :] * np.log1p(bets[None, :] * (1.0 - m))
    down = (rays - hits)[None, :] * np.log1p(-bets[None, :] * m)
    total = (up + down).sum(axis=1)
    return total - _ROUNDING * (np.abs(up) + np.abs(down)).sum(axis=1) - 1e-300


def _at(rays: np.ndarray, hits: np.ndarray, bets: np.ndarray, floors: np.ndarray, caps: np.ndarray, start: float,
        m: np.ndarray) -> np.ndarray:
    """log K at ``m`` with the stakes active on the piece that starts at ``start`` (floor ≤ start < cap)."""

    active = (floors <= start) & (caps > start)
    if not active.any():
        return np.zeros(len(m))
    return _log_capital(rays[active], hits[active], bets[active], m)


def _staking(rays: np.ndarray, bets: np.ndarray, floors: np.ndarray, caps: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    """Each stake's range [floor, cap) within [0, 1]; empty (2, 0) for a stake of nothing."""

    staked = (bets > 0) & (rays > 0)
    return np.where(staked, np.clip(floors, 0.0, 1.0), 2.0), np.where(staked, np.clip(caps, 0.0, 1.0), 0.0)


def _edges(floors: np.ndarray, caps: np.ndarray, high: float) -> np.ndarray:
    inner = np.concatenate([floors, caps])
    return np.unique(np.concatenate([[0.0, high], inner[(inner > 0) & (inner < high)]]))


def _distinct_pieces(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Each stratum's pieces [lo, hi) (sorted, shape (strata, P)) without repeats, padded
    with a repeat of its first: a repeated piece gives the same candidates, value for value.
    """

    fresh = np.ones(lo.shape, dtype=bool)
    fresh[:, 1:] = (lo[:, 1:] != lo[:, :-1]) | (hi[:, 1:] != hi[:, :-1])
    return _kept(fresh, lo, hi)


def _kept(kept: np.ndarray, *arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    """Each row's entries where ``kept`` (its first always is), in order, padded with the row's first."""

    counts = kept.sum(axis=1)
    order = np.argsort(~kept, axis=1, kind="stable")[:, :int(counts.max())]
    order = np.where(np.arange(order.shape[1])[None, :] >= counts[:, None], 0, order)
    return tuple(np.take_along_axis(a, order, axis=1) for a in arrays)


def _candidates(rays: np.ndarray, hits: np.ndarray, bets: np.ndarray, floors: np.ndarray, caps: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """
    Every stratum's candidate points and log-capitals, shape (strata, C): for every piece
    [eᵢ, eᵢ₊₁) of [0, 1] between the ends of the stakes' ranges, its two ends (the right
    one as the limit from the left) with the stakes active on it, and the point m = 1,
    where log K = 0 (arrays (stakes, strata) in; unused ends are padded with 1). The
    minimum over m ∈ [0, 1] of log K(m) + c·m for any c ≥ 0 is the least of a stratum's
    candidates (log K is concave on each piece).
    """

    floors, caps = _staking(rays, bets, floors, caps)
    inner = np.concatenate([floors, caps]).T  # (strata, 2·stakes)
    inner = np.where((inner > 0) & (inner < 1), inner, 1.0)
    edges = np.sort(np.concatenate([np.zeros((len(inner), 1)), inner, np.ones((len(inner), 1))], axis=1), axis=1)
    lo, hi = _distinct_pieces(edges[:, :-1], edges[:, 1:])  # (strata, P) pieces (empty ones where lo == hi: harmless)
    active = (floors.T[:, :, None] <= lo[:, None, :]) & (caps.T[:, :, None] > lo[:, None, :])  # (strata, stakes, P)

    def log_capital(m: np.ndarray) -> np.ndarray:
        b, n, k = bets.T[:, :, None], rays.T[:, :, None], hits.T[:, :, None]
        up = np.where(active, k * np.log1p(b * (1.0 - m[:, None, :])), 0.0)
        down = np.where(active, (n - k) * np.log1p(-b * m[:, None, :]), 0.0)
        return (up + down).sum(axis=1) - _ROUNDING * (np.abs(up) + np.abs(down)).sum(axis=1) - 1e-300

    points = np.concatenate([lo, hi, np.ones((len(lo), 1))], axis=1)
    values = np.concatenate([log_capital(lo), log_capital(hi), np.zeros((len(lo), 1))], axis=1)
    return points, values


def _undominated(slopes: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Each stratum's candidate lines ν ↦ value + ν·slope (shape (strata, C)) that no other
    one of its own undercuts at every ν ≥ 0 (another with slope and value both no larger),
    padded with a repeat of one of them. The minimum over ν ≥ 0 is the same, bit for bit:
    rounding is monotone, so a line undercut in exact arithmetic is undercut as computed.
    A stratum's log-capital falls to its least value and rises after it, so few survive.
    """

    order = np.lexsort((values, slopes), axis=-1)  # by slope, then by value
    slopes, values = np.take_along_axis(slopes, order, axis=1), np.take_along_axis(values, order, axis=1)
    lowest = np.minimum.accumulate(values, axis=1)
    kept = np.ones(values.shape, dtype=bool)  # the first line (least slope, then value) is always kept
    kept[:, 1:] = values[:, 1:] < lowest[:, :-1]
    return _kept(kept, slopes, values)


def _one_stratum(a: float, rays: np.ndarray, hits: np.ndarray, bets: np.ndarray, floors: np.ndarray,
                 caps: np.ndarray, level: float) -> float:
    """Eq. (2) for one stratum, solved directly: a·m for the largest m with every m' ≤ m excluded (bisection)."""

    floors, caps = _staking(rays, bets, floors, caps)

    def excluded_up_to(m: float) -> bool:  # min over m' in [0, m] of log K(m') >= level
        if _at(rays, hits, bets, floors, caps, m, np.array([m]))[0] < level:  # the point m itself
            return False
        edges = _edges(floors, caps, m) if m > 0 else np.array([0.0])
        for lo, hi in zip(edges[:-1], edges[1:]):  # each piece [lo, hi): concave, its infimum at an end
            if _at(rays, hits, bets, floors, caps, lo, np.array([lo, hi])).min() < level:
                return False
        return True

    if not excluded_up_to(0.0):
        return 0.0
    if excluded_up_to(1.0):
        return a
    low, high = 0.0, 1.0
    for _ in range(60):  # low is always certainly excluded
        middle = 0.5 * (low + high)
        if excluded_up_to(middle):
            low = middle
        else:
            high = middle
    return a * low


def lower_bound(weights: np.ndarray, rays: np.ndarray, hits: np.ndarray, bets: np.ndarray, floors: np.ndarray,
                caps: np.ndarray, alpha: float, search: int = 240) -> float:
    """
    A lower confidence bound s_B of S = Σₖ aₖ μₖ (``weights`` aₖ ≥ 0) at level ``alpha``:
    eq. (2) by the exact Lagrangian bound of the module docstring (one stratum: directly).
    ``rays``, ``hits`` (in the oriented fate), ``bets``, ``floors`` and ``caps`` have shape
    (stakes, strata): row r stakes ``bets[r]`` per ray of its batch's ``rays[r]`` on null
    means m in [``floors[r]``, ``caps[r]``) (a batch staking differently on several ranges
    of m has one row per range, its counts repeated). Always in [0, Σₖ aₖ].
    """

    a = np.asarray(weights, dtype=np.float64)
    rays, hits, bets, floors, caps = (np.asarray(x, dtype=np.float64) for x in (rays, hits, bets, floors, caps))
    _check(a, rays, hits, bets, floors, caps, alpha)
    used = a > 0
    a, rays, hits, bets, floors, caps = a[used], rays[:, used], hits[:, used], bets[:, used], floors[:, used], \
        caps[:, used]
    level = math.log(1.0 / alpha)
    if len(a) == 0:
        return 0.0
    if len(a) == 1:
        return _one_stratum(float(a[0]), rays[:, 0], hits[:, 0], bets[:, 0], floors[:, 0], caps[:, 0], level)
    points, values = _candidates(rays, hits, bets, floors, caps)
    total = float(a.sum())
    slopes, values = _undominated(a[:, None] * points, values)

    def bound(nu: np.ndarray) -> np.ndarray:  # s(ν) = (Σₖ hₖ(ν) − level)/ν for every ν given
        h = np.zeros(len(nu))
        for part in np.array_split(np.arange(len(nu)), max(1, len(nu) * values.size // 2_000_000)):
            h[part] = np.min(values[None] + nu[part, None, None] * slopes[None], axis=2).sum(axis=1)
        return (h - level) / nu

    nu = level / total * np.logspace(-3, 12, search)
    s = bound(nu)
    best, found = int(np.argmax(s)), [s]
    for _ in range(3):  # refine around the best ν (any ν is valid: this only tightens)
        nu = np.geomspace(nu[max(best - 1, 0)], nu[min(best + 1, len(nu) - 1)], 48)
        s = bound(nu)
        best = int(np.argmax(s))
        found.append(s)
    value = float(np.max(np.concatenate(found)))
    value -= 1e-12 * total  # the division's rounding: only ever lower
    return min(max(value, 0.0), total)


Side = tuple[np.ndarray, np.ndarray, np.ndarray]
"""One side's stakes of one batch: (bets, floors, caps), each of shape (ranges, strata)."""


def stratified_interval(weights: np.ndarray, rays: np.ndarray, hits: np.ndarray, lower: Side, upper: Side,
                        delta: float) -> tuple[float, float]:
    """
    The interval [low, high] for L = Σₖ wₖ pₖ (``weights`` any sign; ``rays`` and ``hits``
    — rays in the fate of pₖ — of shape (batches, strata)) from each side's stakes
    (``lower``, ``upper``: (bets, floors, caps) of shape (batches, ranges, strata), each in
    its own orientation, as :func:`stakes` makes them), each side at δ/2: holds at every
    batch at once with probability ≥ 1 − ``delta`` (the module docstring).
    """

    w = np.asarray(weights, dtype=np.float64)
    rays, hits = np.asarray(rays, dtype=np.float64), np.asarray(hits, dtype=np.float64)
    if not 0 < delta < 1:
        raise ValueError(f"delta must lie in (0, 1) (got {delta!r})")
    a = np.abs(w)
    floor, ceiling = float(w[w < 0].sum()), float(w[w > 0].sum())
    bounds = []
    for side, oriented in ((lower, np.where(w > 0, hits, rays - hits)), (upper, np.where(w < 0, hits, rays - hits))):
        bets, floors, caps = (np.asarray(x, dtype=np.float64) for x in side)
        ranges = bets.shape[1]
        flat = lambda x: np.repeat(x, ranges, axis=0)  # each batch's counts once per range of its stakes
        bounds.append(lower_bound(a, flat(rays), flat(oriented), bets.reshape(-1, len(w)),
                                  floors.reshape(-1, len(w)), caps.reshape(-1, len(w)), delta / 2))
    return floor + bounds[0], ceiling - bounds[1]


def prior_variances(rays: np.ndarray, hits: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    p̃ₖ = (hitsₖ + ½)/(raysₖ + 1) (Krichevsky–Trofimov) and v̂ₖ = p̃ₖ(1 − p̃ₖ) from counts
    so far (¼ where there are none): the predictable estimates the stakes use.
    """

    rays, hits = np.asarray(rays, dtype=np.float64), np.asarray(hits, dtype=np.float64)
    p = (hits + 0.5) / (rays + 1.0)
    return p, p * (1 - p)


LADDER: int = 6
"""Ranges of null means below the data on which a batch stakes more (each twice as far as the last)."""


def _side(mean: np.ndarray, spread: np.ndarray, seen: np.ndarray, bet: np.ndarray) -> Side:
    """
    One side's stakes (oriented prior ``mean``): ``bet`` on [m₁, u) with u = mean + 5·spread
    (none above), and on the ranges [mⱼ₊₁, mⱼ) below, mⱼ = mean − 5·2ʲ⁻¹·spread, the larger
    of ``bet`` and half the Kelly stake D/(mⱼ(1 − mⱼ)) against a null at the range's top
    (D = mean − mⱼ; half, so that it still wins when the data lie a few spreads from the
    prior): a null far from the data costs the adversary more.
    Without a prior (``seen`` = 0): ``bet`` on all of [0, 1).
    """

    K = len(mean)
    known = seen > 0
    width = THRESHOLD_SIGMAS * spread
    bets, floors, caps = np.zeros((LADDER + 1, K)), np.zeros((LADDER + 1, K)), np.zeros((LADDER + 1, K))
    top = np.where(known, np.minimum(mean + width + 1.0 / np.maximum(seen, 1.0), 1.0), 1.0)
    first = np.where(known, np.maximum(mean - width, 0.0), 0.0)
    bets[0], floors[0], caps[0] = bet, first, top
    upper = first
    for j in range(1, LADDER + 1):
        lower = np.where(known, np.maximum(mean - width * 2.0 ** j, 0.0), 0.0)
        if j == LADDER:
            lower = np.zeros(K)
        distance = mean - upper
        kelly = np.where(distance > 0, 0.5 * distance / np.maximum(upper * (1 - upper), 1e-12), 0.0)
        bets[j] = np.where(upper > lower, np.minimum(np.maximum(bet, kelly), MAX_BET), 0.0) * (bet > 0)
        floors[j], caps[j] = lower, upper
        upper = lower
    return bets, floors, caps


def stakes(weights: np.ndarray, batch: np.ndarray, tolerance: float, prior_rays: np.ndarray, prior_hits: np.ndarray
           ) -> tuple[Side, Side]:
    """
    The stakes of one batch (``batch`` rays per stratum, fixed before it is drawn) for
    L = Σₖ wₖ pₖ planned to ``tolerance``, from the counts before it (``prior_rays``,
    ``prior_hits``): (lower side, upper side), each (bets, floors, caps) of shape
    (ranges, strata) in its own orientation (module docstring).
    """

    w = np.asarray(weights, dtype=np.float64)
    batch = np.asarray(batch, dtype=np.float64)
    if not tolerance > 0:
        raise ValueError(f"tolerance must be positive (got {tolerance!r})")
    p, v = prior_variances(prior_rays, prior_hits)
    a = np.abs(w)
    used = (a > 0) & (batch > 0)
    spread = float(np.sum(a[used] ** 2 * v[used] / batch[used]))
    information = 1.0 / spread if spread > 0 else 0.0
    bet = np.zeros(len(w))
    bet[used] = np.minimum(tolerance * information * a[used] / batch[used], MAX_BET)
    seen = np.asarray(prior_rays, dtype=np.float64)
    n = np.maximum(seen, 1.0)
    reach = 3.0 * np.sqrt(v / n) + 1.0 / n  # p̃ may be this far off: the error uses the largest variance within it
    nearest = np.clip(0.5, p - reach, p + reach)
    v_high = nearest * (1.0 - nearest)
    error = np.sqrt(v_high / n + v_high / np.maximum(batch, 1.0)) + 1.0 / n
    lower_mean = np.where(w > 0, p, 1 - p)  # each side's oriented prior mean
    return _side(lower_mean, error, seen, bet), _side(1 - lower_mean, error, seen, bet)


def neyman_rays(weights: np.ndarray, information: np.ndarray, variances: np.ndarray) -> np.ndarray:
    """
    Rays per stratum that give each functional j (``weights`` shape (m, K)) the
    ``information[j]`` = 1/Σₖ wⱼₖ² vₖ/nₖ it asks for with the fewest rays for it alone
    (nₖ ∝ |wⱼₖ| √vₖ: Neyman allocation), the most any of them asks for per stratum.
    """

    w = np.abs(np.atleast_2d(np.asarray(weights, dtype=np.float64)))
    sigma = np.sqrt(np.asarray(variances, dtype=np.float64))
    rays = np.zeros(w.shape[1])
    for row, need in zip(w, np.atleast_1d(np.asarray(information, dtype=np.float64))):
        rays = np.maximum(rays, need * row * sigma * float(np.sum(row * sigma)))
    return np.where(rays > 0, np.ceil(rays), 0).astype(np.int64)


@dataclass
class BettingSequence:
    """
    The running confidence sequence of one functional L = Σₖ wₖ pₖ: each batch's rays,
    hits and stakes (set by :meth:`stake` before the batch, from the counts before it),
    and :meth:`interval` — valid at every batch at once (module docstring).

    Attributes
    ----------
    weights : ndarray
        wₖ (any sign).
    tolerance : float
        The half-width the stakes are planned for (t of :func:`stakes`).
    delta : float
        δ of the two-sided statement.
    prior_rays, prior_hits : ndarray
        Counts of rays not in the sequence (a pilot's): used for the stakes only.
    """

    weights: np.ndarray
    tolerance: float
    delta: float
    prior_rays: np.ndarray | None = None
    prior_hits: np.ndarray | None = None
    rays: list[np.ndarray] = field(default_factory=list)
    hits: list[np.ndarray] = field(default_factory=list)
    sides: list[tuple[Side, Side]] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.weights = np.asarray(self.weights, dtype=np.float64)
        zero = np.zeros(len(self.weights))
        self.prior_rays = zero.copy() if self.prior_rays is None else np.asarray(self.prior_rays, dtype=np.float64)
        self.prior_hits = zero.copy() if self.prior_hits is None else np.asarray(self.prior_hits, dtype=np.float64)
        if not 0 < self.delta < 1:
            raise ValueError(f"delta must lie in (0, 1) (got {self.delta!r})")

    @property
    def seen(self) -> tuple[np.ndarray, np.ndarray]:
        """Rays and hits per stratum so far: the prior's and the sequence's."""

        rays = self.prior_rays + (np.sum(self.rays, axis=0) if self.rays else 0.0)
        hits = self.prior_hits + (np.sum(self.hits, axis=0) if self.hits else 0.0)
        return rays, hits

    def stake(self, batch: np.ndarray) -> None:
        """Fix the stakes of the next batch of ``batch`` rays per stratum (before it is drawn)."""

        if len(self.sides) > len(self.rays):
            raise ValueError("the stakes of the next batch are set already: record its counts first")
        self.sides.append(stakes(self.weights, batch, self.tolerance, *self.seen))

    def record(self, batch: np.ndarray, hits: np.ndarray) -> None:
        """The counts of the batch just drawn (``batch`` rays, ``hits`` in the fate of pₖ)."""

        batch, hits = np.asarray(batch, dtype=np.float64), np.asarray(hits, dtype=np.float64)
        if len(self.sides) != len(self.rays) + 1:
            raise ValueError("stake a batch before recording it (the stakes must be predictable)")
        self.rays.append(batch)
        self.hits.append(hits)

    @property
    def estimate(self) -> float:
        """L̂ = Σₖ wₖ (hits/rays) over the sequence's batches (a stratum without rays counts 0)."""

        rays, hits = np.sum(self.rays, axis=0), np.sum(self.hits, axis=0)
        return float(np.dot(self.weights, np.where(rays > 0, hits / np.maximum(rays, 1), 0.0)))

    def interval(self) -> tuple[float, float]:
        """The certified [lower, upper] after the batches recorded (eq. (2), each side at δ/2)."""

        w = self.weights
        if not self.rays:
            return float(w[w < 0].sum()), float(w[w > 0].sum())
        done = self.sides[:len(self.rays)]
        side = lambda i: tuple(np.stack([s[i][j] for s in done]) for j in range(3))
        return stratified_interval(w, np.stack(self.rays), np.stack(self.hits), side(0), side(1), self.delta)

    def information(self, variances: np.ndarray) -> float:
        """Σᵦ 1/Σₖ wₖ² vₖ/nₖᵦ: the information the batches so far carry about L at ``variances``."""

        a2 = self.weights ** 2
        total = 0.0
        for batch in self.rays:
            used = (a2 > 0) & (batch > 0)
            spread = float(np.sum(a2[used] * variances[used] / batch[used]))
            total += 0.0 if spread == 0 or np.any((a2 > 0) & (batch == 0)) else 1.0 / spread
        return total
