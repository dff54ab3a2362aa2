"""
Coverage of the certified derived quantities (issue 30): over many seeds, the exact value
of an analytic specimen lies inside the certified interval at least 1 − δ of the time.

The specimen is a Lambertian reflector (Mitsuba ``diffuse``) whose albedo is a regular
spectrum: every ray is reflected with probability ρ(λ) — its hemispherical reflectance
— and absorbed otherwise, so ρ(λ) (linear interpolation of the spectrum's values),
τ = 0 and α = 1 − ρ are exact, and so is every functional of them (a band, fAPAR, the
colour through the same ASTM E308 weights) and every index.

δ = 0.2, so that the test has power. Each trial is one ``vm.measure(scene, target=...,
seed=s)``; a target's statement is joint (all its intervals at once), and a trial
*covers* when every one of them holds. With n trials and a true coverage p ≥ 1 − δ, the
hits are Binomial(n, p): the test asks for at least :func:`least_hits` (n, 0.8), the
number below which a correct certificate falls with probability ≤ 10⁻³ (one-sided
binomial quantile) — so a correct implementation fails it at most once in a thousand
seed sets, and the planted error below (coverage far below 0.8) fails it.

The planted error: rays allocated inversely to the weights while the certificate assumes
Nₖ ∝ |wₖ| (it states (Σ|w|)²/N for Σ w²/Nₖ): the same coverage check catches it. With
``bound="two-stage"`` (pooled readings of a linear target) the planted error is a draw
of the wavelengths that ignores the weights: caught too.

With ``bound="betting"`` a trial looks at the certificate after every batch and stops at
the first that meets the target; it covers only when every certificate it looked at held
the exact values (anytime validity). A colour's is its joint region: XYZ, L*a*b* and
ΔE₀₀ to the estimate, all at once. The second planted fault: a fixed-sample normal
interval in place of the sequence, looked at after about 30 batches, is caught by the
same check (its power is argued in its test).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.stats import binom, norm

import virtspec_mi as vm
from virtspec_mi.budgets import functionals as functionals_module
from virtspec_mi.applications.targets import measure as measure_module
from virtspec_mi.applications.targets import sequential
from virtspec_mi.budgets.betting import BettingSequence

DELTA = 0.2
TRIALS = 40
VALUES = np.array([0.1, 0.3, 0.7, 0.4, 0.2, 0.6, 0.8, 0.5])
SPAN = (300.0, 1000.0)


def least_hits(trials: int, coverage: float, risk: float = 1e-3) -> int:
    """The least k with P(Binomial(trials, coverage) < k) ≤ risk."""

    return int(binom.ppf(risk, trials, coverage))


def rho(wavelengths: np.ndarray) -> np.ndarray:
    """The exact hemispherical reflectance of the specimen."""

    return np.interp(wavelengths, np.linspace(*SPAN, len(VALUES)), VALUES)


@pytest.fixture(scope="module")
def scene(mi):
    return vm.instrument_scene({"type": "diffuse", "reflectance": {
        "type": "regular", "wavelength_min": SPAN[0], "wavelength_max": SPAN[1],
        "values": ", ".join(f"{v:g}" for v in VALUES)}})


def _truth(target, functional) -> float:
    exact = rho(functional.wavelengths)
    exact = 1 - exact if functional.quantity == "absorptance" else exact
    return functional.value(exact)


def _covers(result) -> bool:
    """Every interval of the result holds the exact value (the joint statement)."""

    target = result.target
    truths = {f.name: _truth(target, f) for f in target.functionals()}
    if result.colour is not None:
        import colour

        from virtspec_mi.applications.targets.targets import colour_of

        XYZ = np.array([truths[n] for n in "XYZ"])
        box = result.colour.XYZ_interval
        inside = bool(np.all((box[:, 0] <= XYZ) & (XYZ <= box[:, 1])))
        exact = colour_of(XYZ, target.functionals(), target)
        lab = result.colour.Lab_interval
        in_lab = bool(np.all((lab[:, 0] <= exact.Lab) & (exact.Lab <= lab[:, 1])))
        de00 = float(colour.delta_E(exact.Lab, result.colour.Lab, method="CIE 2000"))
        if getattr(result, "bound", "hoeffding") == "betting":  # one joint region: every statement at once
            return inside and in_lab and de00 <= result.colour.dE00_radius
        if inside:  # then the propagated statements must hold too (they are images of the box)
            assert np.all((lab[:, 0] - 1e-9 <= exact.Lab) & (exact.Lab <= lab[:, 1] + 1e-9))
            assert de00 <= result.colour.dE00_radius + 1e-9
        return inside
    if target.kind == "index":
        a, b = truths[result.values[1].name], truths[result.values[2].name]
        truths[result.values[0].name] = target.index.value(a, b)
    return all(v.lower <= truths[v.name] <= v.upper for v in result.values)


def coverage(scene, target, trials: int = TRIALS, bound: str = "betting") -> int:
    """
    Trials (seeds 0 … trials − 1) whose certified intervals hold the exact values. With
    ``bound="betting"`` each trial looks after every batch and stops at the first at which
    the target is met (the adaptive stopping the sequence must survive), and a trial
    covers only when the certificate of **every** batch it looked at held the exact values
    (anytime validity), the one it stopped at included.
    """

    looks: list[bool] = []
    original = sequential._certificate

    def looking(target, functionals, sequences, total, spent, delta, region=None):
        outcome = original(target, functionals, sequences, total, spent, delta, region=region)
        looks.append(_covers(SimpleNamespace(target=target, colour=outcome[3], values=outcome[2], bound="betting")))
        return outcome

    hits = 0
    sequential._certificate = looking
    try:
        for seed in range(trials):
            looks.clear()
            result = vm.measure(scene, target=target, delta=DELTA, seed=seed, theta_i=8, beam="collimated",
                                bound=bound)
            hits += _covers(result) and all(looks)
    finally:
        sequential._certificate = original
    return hits


TARGETS = {
    "band": lambda: vm.band((450, 520), {600: 1.0, 650: 2.0, 700: 1.0}, tolerance=0.02),
    "fapar": lambda: vm.fapar(tolerance=0.02),
    "index": lambda: vm.index("NDVI", tolerance=0.05),
    "colour": lambda: vm.colour(tolerance_dE00=4.0),
    "albedo": lambda: vm.albedo(tolerance=0.02, low=350, high=780),
}


PILOTED = {
    "band": lambda: vm.band((450, 520), {600: 1.0, 650: 2.0, 700: 1.0}, tolerance=0.005),
    "fapar": lambda: vm.fapar(tolerance=0.005),
    "albedo": lambda: vm.albedo(tolerance=0.005, low=350, high=780),
}
"""
The linear kinds that pooled two-stage readings take (bound="two-stage"), at a tolerance
where each functional takes its pilot; at TARGETS' 0.02 and δ = 0.2 the pilot would not
pay (``pooled.pilot_pays``) and N is the exact rule's over every p̄: both paths are covered.
"""

ROUTES = [(kind, bound) for kind in sorted(TARGETS) for bound in ("betting", "two-stage", "hoeffding")
          if bound != "two-stage" or kind in PILOTED] + [(f"{kind}, piloted", "two-stage") for kind in sorted(PILOTED)]


def _made(kind: str):
    return PILOTED[kind.split(",")[0]]() if kind.endswith("piloted") else TARGETS[kind]()


@pytest.mark.parametrize(("kind", "bound"), ROUTES)
def test_the_exact_value_lies_inside_the_certified_interval_at_least_1_minus_delta_of_the_time(scene, kind, bound):
    hits = coverage(scene, _made(kind), bound=bound)
    assert hits >= least_hits(TRIALS, 1 - DELTA), (kind, bound, hits)
    if kind.endswith("piloted"):  # the path this row is for
        assert vm.measure(scene, target=_made(kind), delta=DELTA, seed=0, theta_i=8, beam="collimated",
                          bound=bound).pilot_rays > 0


@pytest.mark.slow
@pytest.mark.parametrize(("kind", "bound"), [(kind, "betting") for kind in sorted(TARGETS)]
                         + [(kind, "two-stage") for kind in sorted(PILOTED)]
                         + [(f"{kind}, piloted", "two-stage") for kind in sorted(PILOTED)])
def test_coverage_over_400_seeds(scene, kind, bound):
    trials = 400
    assert coverage(scene, _made(kind), trials, bound=bound) >= least_hits(trials, 1 - DELTA)


def test_a_planted_draw_that_ignores_the_weights_is_caught(scene, monkeypatch):
    """
    Pooled readings whose wavelengths are drawn uniformly while the estimate takes them as
    drawn by the weights: the count is then a proportion of the unweighted mean, 0.55
    here against the band's 0.68, far beyond its tolerance — caught by the same check,
    which the right draw passes.
    """

    from virtspec_mi.applications.targets import pooled

    target = vm.band({500: 1.0, **{510 + 10 * i: 0.02 for i in range(10)}}, tolerance=0.02)
    assert coverage(scene, target, bound="two-stage") >= least_hits(TRIALS, 1 - DELTA)
    right = pooled.pooled_rays
    monkeypatch.setattr(pooled, "pooled_rays", lambda weights, rays, seed, stage, functional: right(
        np.asarray(weights) != 0, rays, seed, stage, functional))
    assert coverage(scene, target, bound="two-stage") < least_hits(TRIALS, 1 - DELTA)


def test_a_planted_wrong_allocation_is_caught_by_the_coverage_check(scene, monkeypatch):
    """
    Rays inversely proportional to the weights (the heavy wavelength starved) while the
    certificate states the proportional allocation's (Σ|w|)²/N: the coverage collapses
    and the same check as above fails — and with the right allocation it passes.
    """

    target = vm.band({500: 1.0, **{510 + 10 * i: 0.02 for i in range(10)}}, tolerance=0.02)
    assert coverage(scene, target, bound="hoeffding") >= least_hits(TRIALS, 1 - DELTA)

    def inverse(weights, tolerances, delta):
        right = functionals_module.allocate_jointly(weights, tolerances, delta)
        w = np.abs(np.atleast_2d(np.asarray(weights, dtype=np.float64))).max(axis=0)
        share = np.where(w > 0, 1 / np.where(w > 0, w, 1), 0)
        return np.maximum(np.where(w > 0, 1, 0), np.round(right.sum() * share / share.sum())).astype(np.int64)

    def assumes_proportional(weights, rays, delta, shared=False):
        weights, rays = np.asarray(weights, dtype=np.float64), np.asarray(rays, dtype=np.float64)
        return float(np.sqrt(np.abs(weights).sum() ** 2 / rays[weights != 0].sum() * np.log(2 / delta) / 2))

    monkeypatch.setattr(measure_module, "allocate_jointly", inverse)
    monkeypatch.setattr(functionals_module, "hoeffding_tolerance", assumes_proportional)
    hits = coverage(scene, target, bound="hoeffding")
    assert hits < least_hits(TRIALS, 1 - DELTA), hits


class _Wald:
    """The planted fault's interval: a fixed-sample normal interval at the sequence's δ, recomputed after every batch."""

    def interval(self):
        rays, hits = (np.sum(getattr(self, name), axis=0).astype(float) for name in ("rays", "hits"))
        p = hits / np.maximum(rays, 1)
        half = norm.ppf(1 - self.delta / 2) * float(np.sqrt(np.sum(self.weights ** 2 * p * (1 - p) / rays)))
        return self.estimate - half, self.estimate + half


def _many_looks(monkeypatch) -> None:
    """About 30 looks before a target is met: a first batch of 2 % of the information, each later one 10 % more."""

    monkeypatch.setattr(sequential, "FIRST_SHARE", 0.02)
    monkeypatch.setattr(sequential, "MOST_BATCHES", 60)
    monkeypatch.setattr(sequential, "_next_information",
                        lambda have, widths, tolerances: np.where(widths <= tolerances, 0.0, 1.1 * have))


PEEKED = lambda: vm.band((500, 520), step=10.0, tolerance=0.02)  # noqa: E731 - three wavelengths: cheap looks


def test_a_fixed_sample_bound_used_sequentially_is_caught(scene, monkeypatch):
    """
    The planted fault: the betting sequence's interval replaced by a fixed-sample normal
    interval at δ (valid at one sample size fixed in advance, not at a data-dependent
    one), looked at after every batch until the target is met: about 30 looks (the first
    batch 2 % of the information, each later one 10 % more). Its power: for a Brownian
    mean with looks at n₀·1.1ʲ, j = 0 … 30, a two-sided 80 % normal interval misses at some
    look with probability ≈ 0.73 (20,000 simulated paths; 0.43 with 10 looks), so its hits
    are about Binomial(40, 0.27): below :func:`least_hits` (40, 0.8) = 24 with probability
    ≈ 1 − 10⁻⁶. The same looks with the betting sequence (the slow test below) cover.
    """

    _many_looks(monkeypatch)
    monkeypatch.setattr(BettingSequence, "interval", _Wald.interval)
    hits = coverage(scene, PEEKED(), bound="betting")
    assert hits < least_hits(TRIALS, 1 - DELTA), hits


@pytest.mark.slow
def test_the_betting_sequence_covers_with_the_planted_faults_30_looks(scene, monkeypatch):
    _many_looks(monkeypatch)
    hits = coverage(scene, PEEKED(), bound="betting")
    assert hits >= least_hits(TRIALS, 1 - DELTA), hits
