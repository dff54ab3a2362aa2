"""
The stratified betting confidence sequence (budgets/betting.py): coverage over many seeds
at every batch (a peeking stopping rule and a deliberately adaptive allocation included),
exactness against brute force, the reduction to one stratum, signed weights, and its width
against Hoeffding's at equal rays.

Tolerances are derived, not tuned: a sequence at δ misses (at any batch, hence at any
stopping time) in at most a share δ of independent trials, so with T trials the misses
are stochastically below Binomial(T, δ); the tests allow up to the binomial quantile
:func:`most_misses` (T, δ) at 1 − 10⁻³ — a correct sequence fails it at most once in a
thousand seed sets, and a fixed-sample interval used sequentially (the planted fault) fails.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import binom, norm

from virtspec_mi.budgets.betting import (BettingSequence, lower_bound, neyman_rays, prior_variances, stakes,
                                         stratified_interval)

DELTA = 0.2
MEANS = np.array([0.05, 0.12, 0.5, 0.9])
WEIGHTS = np.array([3.0, -1.0, 0.5, 2.0])  # signed


def most_misses(trials: int, delta: float, risk: float = 1e-3) -> int:
    """The largest miss count a correct sequence reaches with probability ≥ ``risk`` (Binomial(trials, δ) quantile)."""

    return int(binom.ppf(1 - risk, trials, delta))


def _run(seed: int, interval_of, adaptive: bool, batches: int = 6, tolerance: float = 0.15) -> tuple[bool, bool]:
    """
    One trial: batches of rays, each after the last; returns (missed at some batch, missed
    at the stopping time of 'stop once the half-width is at most the tolerance').
    ``adaptive``: the next batch goes to the stratum whose estimate lies farthest above its
    mean so far (a deliberately data-dependent allocation), else Neyman-like.
    """

    rng = np.random.default_rng(seed)
    truth = float(WEIGHTS @ MEANS)
    state = interval_of()
    batch = np.full(len(MEANS), 40)
    ever = stopped = False
    for b in range(batches):
        state.stake(batch)
        hits = rng.binomial(batch, MEANS)
        state.record(batch, hits)
        low, high = state.interval()
        missed = not low <= truth <= high
        ever |= missed
        if max(state.estimate - low, high - state.estimate) <= tolerance:
            stopped = missed
            break
        rays, seen = state.seen
        if adaptive:
            batch = np.full(len(MEANS), 5)
            batch[int(np.argmax(seen / rays))] += 150 * (b + 1)
        else:
            batch = np.maximum(neyman_rays(WEIGHTS, [40.0 * 2 ** b], prior_variances(rays, seen)[1]), 5)
    else:
        stopped = ever and missed
    return ever, stopped


class _Wald:
    """The planted fault: a fixed-sample normal interval at δ, recomputed after every batch (peeking)."""

    def __init__(self) -> None:
        self.rays, self.hits, self.pending = [], [], None

    def stake(self, batch):
        self.pending = batch

    def record(self, batch, hits):
        self.rays.append(batch)
        self.hits.append(hits)

    @property
    def seen(self):
        return np.sum(self.rays, axis=0).astype(float), np.sum(self.hits, axis=0).astype(float)

    @property
    def estimate(self):
        rays, hits = self.seen
        return float(WEIGHTS @ (hits / rays))

    def interval(self):
        rays, hits = self.seen
        p = hits / rays
        half = norm.ppf(1 - DELTA / 2) * math.sqrt(float(np.sum(WEIGHTS ** 2 * p * (1 - p) / rays)))
        return self.estimate - half, self.estimate + half


@pytest.mark.parametrize("adaptive", [False, True])
def test_the_sequence_covers_at_every_batch_under_adaptive_allocation(adaptive):
    trials = 60
    results = [_run(seed, lambda: BettingSequence(WEIGHTS, 0.15, DELTA), adaptive) for seed in range(trials)]
    ever = sum(r[0] for r in results)
    assert ever <= most_misses(trials, DELTA), ever


def test_a_fixed_sample_interval_used_sequentially_is_caught():
    trials = 60
    results = [_run(seed, _Wald, False, batches=12, tolerance=1e-9) for seed in range(trials)]
    ever = sum(r[0] for r in results)
    assert ever > most_misses(trials, DELTA), ever


@pytest.mark.slow
def test_coverage_over_400_seeds_with_a_stopping_rule():
    trials = 400
    results = [_run(seed, lambda: BettingSequence(WEIGHTS, 0.1, DELTA), True, batches=10, tolerance=0.1)
               for seed in range(trials)]
    assert sum(r[0] for r in results) <= most_misses(trials, DELTA)
    assert sum(r[1] for r in results) <= most_misses(trials, DELTA)


def _log_capital(rays, hits, side, m):
    """Brute force of eq. (1) for one stratum at null means m (all of the side's ranges)."""

    bets, floors, caps = side
    m = np.asarray(m)[:, None]
    active = (floors[None, :] <= m) & (m < caps[None, :]) & (bets[None, :] > 0)
    terms = hits * np.log1p(bets * (1 - m)) + (rays - hits) * np.log1p(-bets * m)
    return np.where(active, terms, 0.0).sum(axis=1)


def test_one_stratum_is_solved_exactly_and_never_above_the_truth_of_eq_2():
    rng = np.random.default_rng(4)
    p, n = 0.05, 20_000
    sequence = BettingSequence(np.array([1.0]), 0.003, 0.05, prior_rays=np.array([5000.0]),
                               prior_hits=np.array([250.0]))
    for _ in range(2):
        sequence.stake(np.array([n]))
        sequence.record(np.array([n]), rng.binomial([n], [p]))
    low, _ = sequence.interval()
    grid = np.linspace(0, 0.2, 200_001)
    total = np.zeros(len(grid))
    for rays, hits, sides in zip(sequence.rays, sequence.hits, sequence.sides):
        total += _log_capital(rays[0], hits[0], tuple(x[:, 0] for x in sides[0]), grid)
    excluded = np.minimum.accumulate(total) >= math.log(2 / 0.05)  # every m' <= m excluded
    brute = grid[np.flatnonzero(excluded)[-1]]
    assert low <= brute + 1e-6 and low >= brute - 2e-6


def test_two_strata_the_lagrangian_bound_is_conservative_and_close():
    rng = np.random.default_rng(5)
    weights, means, rays = np.array([1.0, 2.0]), np.array([0.08, 0.15]), np.array([30_000, 50_000])
    hits = rng.binomial(rays, means)
    lower, _ = stakes(weights, rays, 0.01, np.array([4000.0, 4000.0]), np.round(means * 4000))
    bets, floors, caps = lower
    alpha = 0.025
    value = lower_bound(weights, np.repeat(rays[None], len(bets), 0), np.repeat(hits[None], len(bets), 0), bets,
                        floors, caps, alpha)
    # brute force of eq. (2): min over m1 of log K1(m1) + log K2((s − m1)/2), s on a grid
    m1 = np.linspace(0, 1, 20_001)

    def minimum(s):
        m2 = (s - m1) / 2
        ok = (m2 >= 0) & (m2 <= 1)
        f = (_log_capital(rays[0], hits[0], tuple(x[:, 0] for x in lower), m1[ok])
             + _log_capital(rays[1], hits[1], tuple(x[:, 1] for x in lower), m2[ok]))
        return f.min()

    s_hat = float(weights @ (hits / rays))
    assert minimum(value) >= math.log(1 / alpha) - 0.05  # every s <= value is excluded (up to the brute grid)
    assert minimum(value + 0.1 * (s_hat - value)) < math.log(1 / alpha) + 1.0  # and the bound is not far below
    assert value < s_hat


def test_signed_weights_turn_the_interval_round():
    rng = np.random.default_rng(6)
    rays = np.array([[4000, 9000, 3000]])
    hits = rng.binomial(rays, [0.1, 0.6, 0.95])
    weights = np.array([2.0, -1.0, 0.5])
    forward, backward = (BettingSequence(w, 0.05, 0.1) for w in (weights, -weights))
    for s in (forward, backward):
        s.stake(rays[0])
        s.record(rays[0], hits[0])
    low, high = forward.interval()
    assert backward.interval() == pytest.approx((-high, -low), abs=1e-12)
    assert low < forward.estimate < high


def test_narrower_than_hoeffding_at_equal_rays_for_small_proportions():
    rng = np.random.default_rng(7)
    delta, n = 0.05, 100_000
    sequence = BettingSequence(np.array([1.0]), 0.002, delta, prior_rays=np.array([20_000.0]),
                               prior_hits=np.array([1000.0]))
    sequence.stake(np.array([n]))
    sequence.record(np.array([n]), rng.binomial([n], [0.05]))
    low, high = sequence.interval()
    hoeffding = math.sqrt(math.log(2 / delta) / (2 * n))
    assert max(sequence.estimate - low, high - sequence.estimate) < 0.5 * hoeffding
    assert low <= 0.05 <= high


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="delta must lie in"):
        BettingSequence(np.array([1.0]), 0.1, 1.5)
    sequence = BettingSequence(np.array([1.0]), 0.1, 0.1)
    with pytest.raises(ValueError, match="stake a batch before recording"):
        sequence.record(np.array([10]), np.array([1]))
    sequence.stake(np.array([10]))
    with pytest.raises(ValueError, match="set already"):
        sequence.stake(np.array([10]))
    with pytest.raises(ValueError, match="hits must lie in"):
        stratified_interval(np.array([1.0]), np.array([[10]]), np.array([[11]]),
                            *[tuple(x[None] for x in side) for side in stakes(np.array([1.0]), np.array([10]), 0.1,
                                                                               np.zeros(1), np.zeros(1))], 0.1)
