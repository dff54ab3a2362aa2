"""
Measuring a target sequentially: batches of rays until the certificate holds
============================================================================

:func:`take_sequential` certifies a :class:`~.targets.Target` with a betting confidence
sequence (:mod:`virtspec_mi.budgets.betting`) — ``vm.measure(scene, target=...)``'s
default, ``bound="betting"``:

1. the target's functionals on one wavelength grid, fitted to the specimen's data, and
   for a nonlinear target the pilot and the tolerance tⱼ each functional is planned for
   (:func:`~virtspec_mi.applications.targets.measure.plan_target`, without its second pilot; tⱼ for
   :data:`PLANNED_MARGIN` of the target's tolerance at the pilot's point); a linear
   target's tⱼ is its tolerance, and its pilot :data:`BLIND_SHARE` of Hoeffding's rays
   (Nₖ ∝ |wₖ|, the settings' seed). The pilot's counts (its own seed) only size rays and stakes;
2. each functional j gets a :class:`~virtspec_mi.budgets.betting.BettingSequence` at
   δ/m (m functionals, union bound), its stakes planned for tⱼ. A colour's functionals
   are not X, Y and Z but the CIELAB facets L*, a*, b* linearised at the pilot's point,
   and its certificate is their one joint region of XYZ (:mod:`.joint`);
3. batch after batch: the rays of the batch go to the wavelengths by Neyman allocation
   (Nₖ ∝ |wⱼₖ|·σ̂ₖ for each j, σ̂ from the rays before the batch; the most any functional
   asks for), sized for the information each functional still lacks (the first batch:
   :data:`FIRST_SHARE` of what it needs at the pilot's variances); the stakes are fixed
   *before* the batch is traced, from the rays before it (predictable);
4. the batch is traced (the spectrophotometer's allocated reading, :data:`virtspec_mi.instruments.ALLOCATING`, seed
   :func:`~virtspec_mi.budgets.twostage.stage_two_seed` of the settings' seed). Reading k
   continues its own stream of rays: global indices k·S + (rays it traced before), S
   more than any reading can trace (:data:`MOST_RAYS_FACTOR` times Hoeffding's rays in
   all, plus the first batch), so no ray is traced twice and batch b's rays are
   independent of every earlier batch's; the result is a function of the seed alone;
5. after each batch the certificate of the rays so far — each functional's interval
   (the symmetric half-width enclosing it, plus its rounding bias), then the target's map
   — decides: sampling **stops at the first batch at which the target is met**; no batch
   is traced after that. The sequence is valid at every batch at once, so this stopping
   rule keeps the stated δ. A target not met after :data:`MOST_RAYS_FACTOR` times
   Hoeffding's rays or :data:`MOST_BATCHES` batches stops and says "NOT MET", with the
   interval its rays certify.

:func:`certify_target` picks the route: ``bound="betting"`` this one, ``bound="two-stage"``
pooled two-stage readings (:mod:`.pooled`), ``bound="hoeffding"`` the one-batch route of
:mod:`~virtspec_mi.applications.targets.measure`, ``bound="auto"`` (the default,
:func:`take_auto`) the pooled readings for a linear target whose weights have one sign
(every band, fAPAR, albedo: they need fewer rays, ``benchmarks/betting.py``), this one
for any other (an index, a colour).

With ``checkpoint=`` every trace is kept on disk and an interrupted run resumes to the
same result (:mod:`.resume`). The batch granularity: a batch asks for at most as much again as all the batches before
it (and at least :data:`LEAST_GROWTH` of it), so the rays spent exceed the fewest that
would have met the target by at most that step.

References
----------
Spertus, Sridhar & Stark (2024), arXiv:2409.06680; Waudby-Smith & Ramdas (2023), JRSS-B;
Neyman (1934), *J. R. Stat. Soc.* 97(4), 558–625 (optimum allocation).
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, replace
from functools import partial
from typing import Any, Callable

import numpy as np

from virtspec_mi.budgets.functionals import allocate_jointly
from virtspec_mi.applications.targets.measure import (_certified_colour, _colour_values, _fates, _trace, check_certified,
                                                      plan_target, spent_readings, take_target)
from virtspec_mi.applications.targets.measure import measure_target as checked_target
from virtspec_mi.runtime.scene import LoadedScene
from virtspec_mi.applications.targets.result import DerivedResult
from virtspec_mi.applications.targets.pooled import poolable, take_pooled
from virtspec_mi.applications.targets.resume import replaying
from virtspec_mi.applications.targets.joint import facet_tolerances, facet_weights, lab_boxes, lab_jacobian, region_colour
from virtspec_mi.applications.targets.targets import ColourTarget, Target, colour_of
from virtspec_mi.budgets.betting import BettingSequence, neyman_rays, prior_variances
from virtspec_mi.budgets.twostage import stage_two_seed
from virtspec_mi.engine.progress import Progress
from virtspec_mi.engine.tally import Tally
from virtspec_mi.kernel.counts import WEIGHT_ROUNDING, Counts
from virtspec_mi.settings import Settings

__all__ = ["measure_target", "measure_targets", "certify_target", "take_sequential", "take_auto", "BOUNDS", "PLANNED_MARGIN", "FIRST_SHARE", "BLIND_SHARE", "LEAST_GROWTH", "MOST_BATCHES", "MOST_RAYS_FACTOR", "JOINT_METHOD"]

FIRST_SHARE: float = 0.9
"""The first batch asks for this share of the information a functional needs (pilot's variances)."""

BLIND_SHARE: float = 1 / 16
"""A linear target's pilot: this share of Hoeffding's rays (Nₖ ∝ |wₖ|, sizing and stakes only)."""

LEAST_GROWTH: float = 0.1
"""A later batch adds at least this share of the information so far (and at most as much again)."""

MOST_BATCHES: int = 40
"""Batches at most before a target not met stops."""

MOST_RAYS_FACTOR: float = 4.0
"""Rays at most, as a multiple of the Hoeffding route's, before a target not met stops."""

PLANNED_MARGIN: float = 0.95
"""The share of a nonlinear target's tolerance its functionals' stakes are planned for (from the pilot's point)."""


def _next_information(have: np.ndarray, widths: np.ndarray, tolerances: np.ndarray) -> np.ndarray:
    """
    The information each functional should have after the next batch: what its width so
    far asks for (a half-width w ≈ t/2 + c/(t·I) reaches t at I·(2w/t − 1)), within
    [1 + LEAST_GROWTH, 2] times what it has; 0 when it holds its tolerance already.
    """

    wanted = have * (2 * widths / tolerances - 1)
    return np.where(widths <= tolerances, 0.0, np.clip(wanted, (1 + LEAST_GROWTH) * have, 2 * have))


def measure_target(scene: LoadedScene, parameters: Any, target: Target, settings: dict[str, Any]) -> DerivedResult:
    """
    ``vm.measure(scene, target=...)``: the call's keywords checked by
    :func:`~virtspec_mi.applications.targets.measure.measure_target`, ``bound`` (``"auto"`` by
    default) taken as the target's certificate, then :func:`certify_target`.
    """

    settings = dict(settings)
    bound = settings.pop("bound", None) or "auto"  # a target's certificate: "auto", "betting" or "hoeffding"
    checkpoint = settings.pop("checkpoint", None)  # the run's traces kept there (.resume)
    with Progress(settings.pop("progress", None), None, desc="target", unit="ray"):  # its length is the batches'
        return checked_target(scene, parameters, target, settings,
                              take=partial(certify_target, bound=bound, checkpoint=checkpoint))


def _angle_on_worker(scene: Any, defines: dict[str, Any] | None, target: Target, settings: dict[str, Any],
                     theta_i: float) -> DerivedResult:
    """One angle of a target's sweep on a Dask worker: the scene loaded there, then :func:`measure_target`."""

    from virtspec_mi.runtime.scaleout import _initialise, _restored
    from virtspec_mi.runtime.scene import loaded

    _initialise()  # libLLVM, the variant and the plugins in the thread this task runs in (idempotent)
    return measure_target(loaded(_restored(scene), defines), None, target, {**settings, "theta_i": theta_i})


def measure_targets(scene: LoadedScene, target: Target, settings: dict[str, Any], angles: tuple[float, ...],
                    checkpoint: Any = None, workers: Any = None) -> tuple[DerivedResult, ...]:
    """
    ``vm.sweep(scene, target=...)``: :func:`measure_target` at each θi of ``angles`` in
    turn, every angle's traces kept in one ``checkpoint`` (:mod:`.resume`; removed once
    the last angle is certified): an interrupted sweep resumes where it stopped, to the
    same results. With ``workers`` (as for ``vm.sweep``: :mod:`virtspec_mi.runtime.scaleout`)
    each angle is one task on a Dask worker, which loads the scene itself: the results are
    those of the run in this process, bit for bit (each angle's batches are a function of
    the seed and its counts). A checkpoint is not kept on workers (refused together).
    """

    if workers is not None:
        if checkpoint is not None:
            raise ValueError("checkpoint and workers: a target's sweep keeps its checkpoint in this process only; "
                             "give one of them")
        from virtspec_mi.runtime.scaleout import connect, portable_scene

        portable = portable_scene(scene.given)
        with connect(workers) as client:
            futures = [client.submit(_angle_on_worker, portable, scene.defines, target, {**settings, "progress": False},
                                     float(t), pure=False)
                       for t in angles]
            return tuple(client.gather(futures))
    if checkpoint is not None and (not isinstance(checkpoint, (str, os.PathLike)) or not str(checkpoint).strip()):
        raise ValueError(f"checkpoint must be a file path (got {checkpoint!r})")
    described = target.as_dict() if isinstance(target, Target) else repr(target)
    identity = {"scene": scene.fingerprint, "settings": {k: settings[k] for k in sorted(settings) if k != "progress"},
                "target": described, "angles": list(angles), "sweep": True}
    with replaying(checkpoint, identity):
        return tuple(measure_target(scene, None, target, {**settings, "theta_i": float(t)}) for t in angles)


def certify_target(bench: Any, settings: Settings, target: Target, *, scene: str = "", source: dict | None = None,
                   bound: str = "auto", checkpoint: Any = None) -> DerivedResult:
    """
    Certify ``target`` by the route :data:`BOUNDS` names ``bound`` (the result's ``bound``
    says which route ``auto`` took), with every trace kept in ``checkpoint`` when given.
    """

    if bound not in BOUNDS:
        raise ValueError(f"bound must be one of {', '.join(BOUNDS)} for a target (got {bound!r})")
    if checkpoint is not None and (not isinstance(checkpoint, (str, os.PathLike)) or not str(checkpoint).strip()):
        raise ValueError(f"checkpoint must be a file path (got {checkpoint!r})")
    described = target.as_dict() if isinstance(target, Target) else repr(target)  # plan_target refuses a non-target
    identity = {} if checkpoint is None else {"scene": scene, "settings": settings.as_dict(), "target": described,
                                              "bound": bound}
    with replaying(checkpoint, identity):
        return BOUNDS[bound](bench, settings, target, scene=scene, source=source)


def take_sequential(bench: Any, settings: Settings, target: Target, *, scene: str = "", source: dict | None = None
                    ) -> DerivedResult:
    """Certify ``target`` on ``bench`` with ``settings`` by batches until it is met (the module docstring)."""

    start = time.perf_counter()
    planned = plan_target(bench, settings, target, refine=False)
    target, functionals, grid, weights = planned.target, planned.functionals, planned.grid, planned.weights
    delta, each, quantity = float(settings.delta), planned.each, functionals[0].quantity
    used = np.flatnonzero(np.any(weights != 0, axis=0))
    w = weights[:, used]
    prior = planned.pilot_counts
    hoeffding = int(allocate_jointly(weights, np.asarray(planned.tolerances, dtype=np.float64), planned.each).sum())
    pilot_rays = planned.pilot_rays
    if prior is None:  # a linear target: a small pilot of its own (seed: the settings'), Nₖ ∝ |wₖ|
        tolerances = np.asarray(planned.tolerances, dtype=np.float64)
        first = neyman_rays(weights[:, used], 2 * math.log(2 / planned.each) / tolerances ** 2 * BLIND_SHARE,
                            np.full(len(used), 0.25))
        tally = _traced(bench, settings, grid, used, np.maximum(first, 1),
                        np.arange(len(used)) * int(max(first.max(), 1)), settings.seed, scene, source)
        prior = (np.zeros(len(grid)), np.zeros(len(grid)))
        prior[0][used], prior[1][used] = np.maximum(first, 1), _fates(tally.counts, quantity)
        pilot_rays += int(np.maximum(first, 1).sum())
    region = None
    prior_rays = np.zeros(len(used)) if prior is None else prior[0][used]
    prior_hits = np.zeros(len(used)) if prior is None else prior[1][used]
    if planned.pilot_counts is not None:  # stopping on the certificate itself: less in reserve than one batch must
        point = weights @ (prior[1] / np.maximum(prior[0], 1))
        if isinstance(target, ColourTarget):  # one joint region: facets along CIELAB at the pilot's point (joint)
            region = _Region.at(point, functionals, w)
            w = region.facets
            tolerances = facet_tolerances(region.Lab, w, prior_variances(prior_rays, prior_hits)[1],
                                          target.tolerance_dE00, PLANNED_MARGIN)
        else:
            tolerances = np.asarray(target.tolerances(point, delta, PLANNED_MARGIN), dtype=np.float64)
    sequences = [BettingSequence(row, float(t), each, prior_rays.copy(), prior_hits.copy())
                 for row, t in zip(w, tolerances)]
    need = 2 * math.log(2 / each) / tolerances ** 2  # information at which a planned stake certifies t
    seed = stage_two_seed(settings.seed)
    total = Counts.zeros(len(used))
    spent = np.zeros(len(used), dtype=np.int64)
    batches: list[int] = []
    batch = neyman_rays(w, FIRST_SHARE * need, prior_variances(prior_rays, prior_hits)[1])
    seconds_traced = 0.0
    stride = int(MOST_RAYS_FACTOR * hoeffding) + int(batch.sum()) + 1  # more than any reading can trace
    while True:
        batch = np.where(batch > 0, batch, 0).astype(np.int64)
        if np.any(spent + batch > stride):
            break  # a reading's stream is full: stop with what the rays so far certify
        for sequence in sequences:
            sequence.stake(batch)  # before the batch is traced: the stakes are predictable
        traced = np.flatnonzero(batch > 0)
        tally = _traced(bench, settings, grid, used[traced], batch[traced],
                        np.arange(len(used))[traced] * stride + spent[traced], seed, scene, source)
        seconds_traced += tally.seconds
        part = np.zeros(len(used))
        part[traced] = _fates(tally.counts, quantity)
        total.add(traced, tally.counts)
        for sequence in sequences:
            sequence.record(batch, part)
        spent += batch
        batches.append(int(batch.sum()))
        outcome = _certificate(target, functionals, sequences, total, spent, delta, region=region)
        if outcome[-1] or len(batches) >= MOST_BATCHES or spent.sum() >= MOST_RAYS_FACTOR * hoeffding:
            break
        widths = outcome[1]
        variances = prior_variances(*sequences[0].seen)[1]
        have = np.array([s.information(variances) for s in sequences])
        if np.all(widths <= tolerances):  # each functional holds its plan but the map is not met: grow all
            wanted = (1 + 2 * LEAST_GROWTH) * have
        else:
            wanted = _next_information(have, widths, tolerances)
        batch = neyman_rays(w, np.maximum(wanted - have, 0.0), variances)
        batch = np.minimum(batch, np.maximum(MOST_RAYS_FACTOR * hoeffding - spent.sum(), 1)).astype(np.int64)
    estimates, certified, reported, colour, met = outcome  # the last batch's certificate
    readings = spent_readings(bench, settings, grid, used, total, seconds_traced, scene, source)
    return DerivedResult(target=target, values=tuple(reported), readings=readings,
                         rays=int(spent.sum()), pilot_rays=pilot_rays, delta=delta,
                         statements=len(functionals), functional_tolerances=tuple(float(t) for t in certified),
                         colour=colour, met=met, seconds=time.perf_counter() - start, bound="betting",
                         batches=tuple(batches))


def take_auto(bench: Any, settings: Settings, target: Target, *, scene: str = "", source: dict | None = None
              ) -> DerivedResult:
    """
    ``bound="auto"``: a linear target whose functionals each weigh with one sign
    (:func:`~.pooled.poolable`) by pooled two-stage readings (:func:`~.pooled.take_pooled`),
    any other by the betting route (:func:`take_sequential`). The choice depends on the
    target alone, before any ray.
    """

    route = take_pooled if isinstance(target, Target) and not poolable(target) else take_sequential
    return route(bench, settings, target, scene=scene, source=source)


BOUNDS: dict[str, Callable[..., DerivedResult]] = {
    "auto": take_auto,
    "betting": take_sequential,
    "two-stage": take_pooled,
    "hoeffding": take_target,
}
"""
A target's certificates by name, each its route: ``auto`` (the default, :func:`take_auto`),
a betting confidence sequence (:func:`take_sequential`), pooled two-stage readings
(:func:`~.pooled.take_pooled`), Hoeffding's (one batch,
:func:`~virtspec_mi.applications.targets.measure.take_target`).
"""


def _traced(bench: Any, settings: Settings, grid: np.ndarray, traced: np.ndarray, rays: np.ndarray,
            offsets: np.ndarray, seed: int, scene: str, source: dict | None) -> Tally:
    """
    One batch through the instrument seam (:func:`~virtspec_mi.applications.targets.measure._trace`):
    the wavelengths ``grid[traced]``, ``rays`` each from global indices ``offsets``, at ``seed``; its tally.
    """

    every, starts = np.zeros(len(grid), dtype=np.int64), np.zeros(len(grid), dtype=np.int64)
    every[traced], starts[traced] = rays, offsets
    return _trace(bench, settings, grid, every, int(seed), scene, source, starts)[1]


@dataclass(frozen=True, eq=False)
class _Region:
    """
    A colour's joint region (:mod:`.joint`): the CIELAB Jacobian ``G`` at the pilot's
    point, the facets' weights G·W on the traced wavelengths, the tristimulus weights
    ``tristimulus`` W there, the white, the estimate's Lab at the pilot's point and what
    a spectrum in [0, 1] can give (``floor``, ``ceiling``).
    """

    G: np.ndarray
    facets: np.ndarray
    tristimulus: np.ndarray
    white: np.ndarray
    Lab: np.ndarray
    floor: np.ndarray
    ceiling: np.ndarray

    @classmethod
    def at(cls, point: np.ndarray, functionals: list, tristimulus: np.ndarray) -> "_Region":
        from virtspec_mi.applications.targets.targets import _white

        white = _white(functionals)
        XYZ = np.maximum(np.asarray(point, dtype=np.float64), 1e-3)
        G = lab_jacobian(XYZ, white)
        Lab = lab_boxes(XYZ[None], XYZ[None], white)[0][0]
        floor = np.array([f.weights[f.weights < 0].sum() for f in functionals])
        ceiling = np.array([f.weights[f.weights > 0].sum() for f in functionals])
        return cls(G, facet_weights(G, tristimulus), np.asarray(tristimulus), np.asarray(white), Lab, floor, ceiling)


def _certificate(target: Target, functionals: list, sequences: list[BettingSequence], total: Counts,
                 spent: np.ndarray, delta: float, region: _Region | None = None) -> tuple:
    """
    What the rays so far certify: (estimates, half-widths, values, colour, met): each
    functional's half-width (the symmetric one enclosing its interval, plus
    Σₖ|wₖ|·rounding biasₖ), the reported values, the colour (or None) and whether the
    target is met. Readings that escaped their certificate are refused (nothing to certify).
    """

    check_certified(target, total)
    rounding = total.rounded_weights * WEIGHT_ROUNDING / np.maximum(spent, 1)
    estimates = np.array([s.estimate for s in sequences])
    widths, intervals = [], []
    for s, e in zip(sequences, estimates):
        low, high = s.interval()
        bias = float(np.sum(np.abs(s.weights) * rounding))
        widths.append(max(e - low, high - e, 0.0) + bias)
        intervals.append((low - bias, high + bias))
    widths = np.array(widths)
    colour = None
    if region is not None:
        rays, hits = (np.sum(getattr(sequences[0], name), axis=0) for name in ("rays", "hits"))
        XYZ = region.tristimulus @ np.where(rays > 0, hits / np.maximum(rays, 1), 0.0)
        low, high = np.array(intervals).T
        colour = region_colour(colour_of(XYZ, functionals, target), region.G, low, high, region.floor,
                               region.ceiling, region.white, delta, int(spent.sum()), JOINT_METHOD)
        reported = _colour_values(colour)
    elif isinstance(target, ColourTarget):
        colour = _certified_colour(target, functionals, estimates, widths, delta, int(spent.sum()))
        colour = _with_method(colour)
        reported = _colour_values(colour)
    else:
        reported = target.values(estimates, widths)
    met = bool(target.met(reported))
    return estimates, widths, reported, colour, met


JOINT_METHOD: str = ("betting confidence sequences (Spertus, Sridhar & Stark 2024) on the CIELAB facets L*, a*, b* "
                     "linearised at the pilot's point, each at delta/3, stopped at the first batch that met the "
                     "target; one joint XYZ region (their intersection) covered by boxes mapped exactly to L*a*b* "
                     "and sRGB; dE00 a rigorous upper bound over the region")
"""The method a colour certified from its joint region states (:mod:`.joint`)."""


def _with_method(colour: Any) -> Any:
    return replace(colour, method="betting confidence sequence (Spertus, Sridhar & Stark 2024) on each tristimulus "
                                  "functional at delta/3, stopped at the first batch that met the target; the XYZ "
                                  "box mapped exactly to L*a*b* and sRGB; dE00 a rigorous upper bound")
