"""
Measuring a target: the rays a derived quantity needs, where it needs them
==========================================================================

:func:`take_target` certifies a :class:`~.targets.Target` on a bench (``vm.measure(scene,
target=...)`` calls it):

1. the target's functionals (:mod:`.functionals`) on one wavelength grid, checked against
   the specimen's data (a band outside it, a colour of too little of the visible: refused
   with the reason);
2. for a nonlinear target, a pilot of about 80,000 rays per functional (Nₖ ∝ |wₖ|, its own
   seed) gives the point at which the target picks each functional's tolerance; when
   that asks for more than :data:`REFINE_ABOVE` times the pilot's rays, a second pilot
   of :data:`REFINE_SHARE` of them (its own seed) refines the point, and the tolerances
   are picked again with less in reserve (:data:`REFINED_MARGIN`);
3. each functional j at δ/m (m functionals, union bound) holds to its tolerance with the
   fewest rays in all: Nₖ = ⌈cⱼ|wⱼₖ|⌉ for one functional (:func:`~.functionals.allocate`),
   the joint optimum for several sharing wavelengths
   (:func:`~.functionals.allocate_jointly`); wavelengths of zero weight are not traced;
4. the spectrophotometer traces them through the instrument seam
   (:data:`virtspec_mi.instruments.ALLOCATING`: its ``init`` plans
   the allocation, its ``process`` is one batched kernel call at the seed
   :func:`~virtspec_mi.budgets.twostage.stage_two_seed` of the settings' seed, rays fresh of
   the pilot's, its ``postprocess`` the readings result), each reading with rays of its own
   (the pilots too, at their own seeds);
5. the certificate comes from the rays spent: each functional's Hoeffding tolerance
   (eq. 1 of :mod:`.functionals`) plus its rounding bias, then the target's map (exact
   intervals, or the ΔE₀₀ bound of :mod:`.delta_e`): a :class:`~.result.DerivedResult`.

The per-wavelength readings are returned too (``result.readings``, a hemispherical
:class:`~virtspec_mi.results.readings.Result`): they are the rays spent, and carry
no joint per-wavelength certificate — each alone has the Hoeffding tolerance of its own
N, which for most of them is wide.

References
----------
Hoeffding (1963), Theorem 2; Baranoski et al. (2001), eq. (2).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np

from virtspec_mi.budgets.functionals import (Functional, allocate, allocate_jointly, certified_tolerance,
                                                          union_delta)
from virtspec_mi.applications.targets.result import DerivedResult
from virtspec_mi.applications.targets.resume import REPLAY, trace_key
from virtspec_mi.applications.targets.targets import TARGETS, ColourTarget, Target, Value, colour_of
from virtspec_mi.base.surface import spoken
from virtspec_mi.budgets.twostage import stage_two_seed
from virtspec_mi.engine.progress import expect, finished
from virtspec_mi.engine.tally import Tally
from virtspec_mi.instruments import ALLOCATING, Allocation
from virtspec_mi.kernel.counts import Counts
from virtspec_mi.plugins.specimen import specimen_of
from virtspec_mi.runtime.reading import scene_options
from virtspec_mi.runtime.scene import LoadedScene
from virtspec_mi.settings import Settings, resolve

__all__ = ["measure_target", "take_target", "plan_target", "prepared", "check_certified", "spent_readings", "TargetPlan", "PILOT_TOLERANCE", "PILOT_DELTA", "REFUSED_SETTINGS"]

PILOT_TOLERANCE: float = 0.003
"""A pilot's tolerance on each functional, as a share of its Σ|w| (about 80,000 rays per functional at PILOT_DELTA)."""

PILOT_DELTA: float = 0.5
"""δ a pilot is sized at (it decides rays only; nothing it measures is claimed)."""

REFINE_ABOVE: float = 50.0
"""A nonlinear target whose rays exceed this many times the pilot's gets a second pilot (see :func:`plan_target`)."""

REFINE_SHARE: float = 0.02
"""The second pilot's rays, as a share of the rays first planned (laid out as they are)."""

REFINED_MARGIN: float = 0.95
"""The share of the tolerance sized for after the second pilot (:data:`~.targets.MARGIN` after the first)."""

REFINE_SEED_MASK: int = 0x2C1B3C6D
"""The second pilot's seed is the settings' seed XOR this (distinct from the first pilot's and the estimates')."""

REFUSED_SETTINGS: tuple[str, ...] = ("wavelengths", "mu", "rays", "pilot_rays", "pilot_delta", "joint")
"""Settings a target decides itself: giving one with a target is an error (``bound``: :data:`.sequential.BOUNDS`)."""


def _fates(tally_counts: Any, quantity: str) -> np.ndarray:
    return np.asarray(getattr(tally_counts, {"reflectance": "reflected", "transmittance": "transmitted",
                                             "absorptance": "absorbed"}[quantity]), dtype=np.float64)


def _specimen_fit(target: Target, bench: Any) -> Target:
    """The target within the specimen's data (a colour's grid clipped to it), or ``ValueError`` saying why not."""

    from virtspec_mi.kernel.spectra import data_ranges  # Mitsuba is set up: the bench is loaded

    spans = [(float(r.low), float(r.high)) for r in data_ranges(bench.bsdf)]
    own = specimen_of(bench.bsdf).wavelength_range
    spans += [] if own is None else [(float(own[0]), float(own[1]))]
    if not spans:
        return target
    low, high = max(s[0] for s in spans), min(s[1] for s in spans)
    if isinstance(target, ColourTarget):
        return replace(target, low=max(low, target.low or low), high=min(high, target.high or high))
    for f in target.functionals():
        used = f.wavelengths[f.weights != 0]
        if used.min() < low or used.max() > high:
            raise ValueError(f"target {target.describe()}: {f.name} needs {used.min():g}-{used.max():g} nm, outside "
                             f"the specimen's data ({low:g}-{high:g} nm): the instrument cannot certify it")
    return target


def _grid(functionals: list[Functional]) -> tuple[np.ndarray, np.ndarray]:
    """The union of the functionals' wavelengths and their weights on it, shape (m, n)."""

    grid = np.unique(np.concatenate([f.wavelengths for f in functionals]))
    return grid, np.stack([f.at(grid) for f in functionals])


def _trace(bench: Any, settings: Settings, grid: np.ndarray, rays: np.ndarray, seed: int, scene: str = "",
           source: dict | None = None, offsets: np.ndarray | None = None) -> tuple[Any, Any]:
    """
    The spectrophotometer's allocated reading (:data:`virtspec_mi.instruments.ALLOCATING`:
    its init plans the traced wavelengths, rays > 0, each from its own key k·stride, or from
    ``offsets`` where given; its process traces them at ``seed``): the instrument (its
    ``used`` wavelengths, its ``postprocess``) and the tally.
    """

    instrument = ALLOCATING(scene, source)
    plan = instrument.init(bench, settings, Allocation(grid, rays, seed, offsets), np.array([float(settings.theta_i)]),
                           None)
    checkpoint = REPLAY.get()  # a run with a checkpoint (.resume): a trace it holds is read back, not traced again
    expect(int(np.sum(rays)))  # the target's bar, when one is open, moves by these rays as they are traced
    if checkpoint is None:
        tally = instrument.process(plan)
    else:
        traced = np.asarray(rays)[np.asarray(rays) > 0]
        tally = checkpoint.trace(trace_key(grid, rays, seed, offsets), traced, lambda: instrument.process(plan))
    finished(int(np.sum(rays)))
    return instrument, tally


@dataclass(frozen=True, eq=False)
class TargetPlan:
    """
    What :func:`plan_target` decided: the target (fitted to the specimen's data), its
    functionals, their wavelength ``grid`` and ``weights`` (m × n), the tolerance each is
    sized for, δ of each (``each``), the rays per wavelength and the pilot's rays.
    """

    target: Target
    functionals: list[Functional]
    grid: np.ndarray
    weights: np.ndarray
    tolerances: np.ndarray
    each: float
    rays: np.ndarray
    pilot_rays: int
    pilot_counts: tuple[np.ndarray, np.ndarray] | None = None  # (rays, counts) per grid wavelength: sizing only


def prepared(bench: Any, settings: Settings, target: Target
             ) -> tuple[Target, list[Functional], np.ndarray, np.ndarray, float]:
    """
    Step 1 of the module docstring: the target fitted to the specimen's data, its
    functionals, their wavelength grid and weights (m × n), and δ of each (δ/m); a
    ``target`` that is not one: ``ValueError`` naming the constructors.
    """

    if not isinstance(target, Target):
        made = [f"vm.{name}" for name in TARGETS]
        raise ValueError(f"target must be made by {', '.join(made[:-1])} or {made[-1]} (the rows of TARGETS; a "
                         f"text such as 'colour,dE00=0.5' is read by parse_target) (got {target!r})")
    target = _specimen_fit(target, bench)
    functionals = target.functionals()
    grid, weights = _grid(functionals)
    return target, functionals, grid, weights, union_delta(float(settings.delta), len(functionals))


def check_certified(target: Target, counts: Counts) -> None:
    """``ValueError`` when some of ``counts``' readings escaped their certificate: nothing to certify."""

    if np.any(counts.weight_violations) or np.any(counts.capped) or np.any(counts.invalid_directions):
        raise ValueError(f"target {target.describe()}: some readings escaped their certificate (weight violations, "
                         "capped walks or invalid directions): no certified value")


def spent_readings(bench: Any, settings: Settings, grid: np.ndarray, used: np.ndarray, total: Counts,
                   seconds: float, scene: str = "", source: dict | None = None) -> Any:
    """
    The readings of the rays a route spent in several traces: ``total``, the counts of the
    wavelengths ``grid[used]`` summed over the traces, as the allocated reading's result
    (``theta_i`` squeezed), ``seconds`` its tracing time.
    """

    final = ALLOCATING(scene, source)
    rays = np.zeros(len(grid), dtype=np.int64)
    rays[used] = 1
    final.init(bench, settings, Allocation(grid, rays, int(settings.seed)), np.array([float(settings.theta_i)]), None)
    return final.postprocess(Tally(total).with_seconds(seconds)).squeeze("theta_i")


def plan_target(bench: Any, settings: Settings, target: Target, refine: bool = True) -> TargetPlan:
    """
    Steps 1–3 of the module docstring (the pilot traced when the target needs one): the rays, not yet traced
    (``refine``: a second pilot for a costly nonlinear target).
    """

    target, functionals, grid, weights, each = prepared(bench, settings, target)
    quantity = functionals[0].quantity
    pilot_rays = 0
    estimates = None
    counts = np.zeros(len(grid))
    if target.needs_pilot:
        first = np.max([allocate(w, PILOT_TOLERANCE * np.abs(w).sum(), PILOT_DELTA) for w in weights], axis=0)
        pilot, tally = _trace(bench, settings, grid, first, settings.seed)
        counts[pilot.used] = _fates(tally.counts, quantity)
        estimates = weights @ (counts / np.maximum(first, 1))
        pilot_rays = int(first.sum())
    tolerances = np.asarray(target.tolerances(estimates, float(settings.delta)), dtype=np.float64)
    rays = allocate_jointly(weights, tolerances, each)
    pilot_counts = None if estimates is None else (np.asarray(first, dtype=np.float64), counts.copy())
    if refine and target.needs_pilot and rays.sum() > REFINE_ABOVE * pilot_rays:
        # a costly target: a second pilot of REFINE_SHARE of those rays pins the point down, so the sizing can
        # keep less in reserve (REFINED_MARGIN): its rays (counted) are few beside those it saves
        second = np.where(rays > 0, np.maximum(1, np.ceil(REFINE_SHARE * rays)), 0).astype(np.int64)
        pilot, tally = _trace(bench, settings, grid, second, settings.seed ^ REFINE_SEED_MASK)
        counts[pilot.used] += _fates(tally.counts, quantity)
        pooled = counts / np.maximum(first + second, 1)  # both pilots' rays (sizing only)
        pilot_rays += int(second.sum())
        tolerances = np.asarray(target.tolerances(weights @ pooled, float(settings.delta), REFINED_MARGIN),
                                dtype=np.float64)
        rays = allocate_jointly(weights, tolerances, each)
        pilot_counts = (np.asarray(first + second, dtype=np.float64), counts.copy())
    return TargetPlan(target, functionals, grid, weights, tolerances, each, rays, pilot_rays, pilot_counts)


def measure_target(scene: LoadedScene, parameters: Any, target: Target, settings: dict[str, Any],
                   take: Callable[..., DerivedResult] | None = None) -> DerivedResult:
    """
    ``vm.measure(scene, target=...)``: the keywords of the call checked — a target picks its
    own wavelengths and rays (:data:`REFUSED_SETTINGS` given: ``ValueError``), and reads the
    scene's own specimen parameters — the settings resolved over the scene's integrator, then
    ``take`` (default :func:`take_target`, the one-batch route; the sequential route:
    :func:`virtspec_mi.applications.targets.sequential.measure_target`).
    """

    given = sorted(name for name in REFUSED_SETTINGS if settings.get(name) is not None)
    if given:
        example = spoken("vm.band('B04', tolerance=0.002)", "--target band:B04,tolerance=0.002")
        raise ValueError(f"{', '.join(given)}: a target picks its own wavelengths and rays (give its tolerance to the "
                         f"target, e.g. {example}); leave them out")
    if parameters:
        raise ValueError("parameters: a target is measured at the scene's own specimen parameters (set them in the "
                         "scene or with defines)")
    resolved, = resolve("measure", settings, scene_options(scene.bench, Settings))
    return (take or take_target)(scene.bench, resolved, target, scene=scene.fingerprint, source=scene.source)


def take_target(bench: Any, settings: Settings, target: Target, *, scene: str = "", source: dict | None = None
                ) -> DerivedResult:
    """
    Certify ``target`` on ``bench`` with ``settings`` (δ, θi, φi, beam, sampling, seed) by
    the one-batch Hoeffding route of the module docstring (``bound="hoeffding"``; the
    default, a betting confidence sequence over batches, is :mod:`.sequential`).
    """

    start = time.perf_counter()
    planned = plan_target(bench, settings, target)
    target, functionals, grid, weights = planned.target, planned.functionals, planned.grid, planned.weights
    rays, each, pilot_rays, delta = planned.rays, planned.each, planned.pilot_rays, float(settings.delta)
    quantity = functionals[0].quantity
    instrument, tally = _trace(bench, settings, grid, rays, stage_two_seed(settings.seed), scene, source)
    used = instrument.used
    readings = instrument.postprocess(tally).squeeze("theta_i")
    spent = rays[used]
    values = _fates(tally.counts, quantity) / spent
    check_certified(target, tally.counts)
    rounding = np.asarray(readings.rounding_bias, dtype=np.float64)
    estimates = weights[:, used] @ values
    certified = np.array([certified_tolerance(Functional(f.name, grid[used], w[used], f.quantity), spent, each,
                                              rounding) for f, w in zip(functionals, weights)])
    colour = None
    if isinstance(target, ColourTarget):
        colour = _certified_colour(target, functionals, estimates, certified, delta, int(spent.sum()))
        reported = _colour_values(colour)
    else:
        reported = target.values(estimates, certified)
    return DerivedResult(target=target, values=tuple(reported), readings=readings, rays=int(spent.sum()),
                         pilot_rays=pilot_rays, delta=delta, statements=len(functionals),
                         functional_tolerances=tuple(float(t) for t in certified), colour=colour,
                         met=target.met(reported), seconds=time.perf_counter() - start)


def _certified_colour(target: ColourTarget, functionals: list[Functional], estimates: np.ndarray,
                      tolerances: np.ndarray, delta: float, rays: int) -> Any:
    from virtspec_mi.colorimetry.certified import certify_colour

    return certify_colour(colour_of(estimates, functionals, target), functionals, tolerances, delta, rays)


def _colour_values(colour: Any) -> list[Value]:
    out = []
    for space, names, units, interval, values in (
            ("CIE XYZ", "XYZ", "1", colour.XYZ_interval, colour.XYZ),
            ("CIE L*a*b*", ("L", "a", "b"), "1", colour.Lab_interval, colour.Lab),
            ("sRGB (encoded, before clipping)", ("sRGB_R", "sRGB_G", "sRGB_B"), "1", colour.sRGB_interval,
             colour.sRGB)):
        for name, (low, high), value in zip(names, interval, values):
            out.append(Value(name, float(value), float(low), float(high), units, f"{space} {name}"))
    out.append(Value("dE00_radius", colour.dE00_radius, 0.0, colour.dE00_radius, "1",
                     "largest CIEDE2000 difference between the estimate and a colour of the certified box"))
    out.append(Value("dEab_radius", colour.dEab_radius, 0.0, colour.dEab_radius, "1",
                     "largest CIE 1976 difference between the estimate and a colour of the certified box"))
    return out
