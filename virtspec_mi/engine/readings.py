"""
The engine: one keyed run for every instrument, from a plan to exact tallies
============================================================================

:func:`run` traces every reading of a :class:`~virtspec_mi.engine.plan.Plan` on a bench
and returns one :class:`~virtspec_mi.engine.tally.Tally`: fate counts, the two-stage
pilot's counts, the kernel hook's bins and per-reading sums, and the seconds spent, over
the plan's flat readings k = ((g·n_p + i_p)·n_θ + i_θ)·n_λ + i_λ. Every instrument runs
through it (the hemispherical spectrophotometer, the goniophotometer, the integrating
sphere: each builds its plan, each turns the tally into its result); the engine never
looks at what a hook's bins mean and decides nothing by rule names (it asks the plan and
its budget rule).

Reading k traces the global ray indices [key·stride, key·stride + N_k) (key = k mod
n_p·n_θ·n_λ: groups share rays; stride = :attr:`Plan.stride`), so its counts depend on
(seed, key) only. Readings run in batches of about ``chunk_size`` rays (several readings
per kernel chunk), each traced by :func:`take_keyed_readings` — the one batch function,
here (:func:`in_process_runner`) or on a Dask worker (:mod:`virtspec_mi.runtime.scaleout`) —
recorded in a checkpoint (bins and sums too: :mod:`virtspec_mi.engine.checkpoint`) and
shown by a progress bar (:mod:`virtspec_mi.engine.progress`).

Model only what is needed: a specimen whose BSDF declares ``wavelength_independent =
True`` (e.g. ``simple_dielectric``) is traced once per incidence (θi, φi) and readings
that differ only in wavelength share those rays and tallies — unless a hook depends on
the wavelength (:attr:`~virtspec_mi.kernel.hooks.ExitHook.spectral`: the sphere's wall).

A fixed budget (``hoeffding``, ``chebyshev``, ``exact``, or explicit ``rays``) is one
batched call per batch. A two-stage rule is two: one batched pilot call over the batch's
readings (seed ``settings.seed``), then one batched call with each reading's own N₂ sized
from its pilot's certified columns (:class:`~virtspec_mi.engine.plan.Columns`: the
hemispherical R, T[, A]; the goniophotometer's bin fractions at δ/K; the sphere's detector
fraction per configuration at δ/2), traced with the distinct seed
:func:`virtspec_mi.budgets.twostage.stage_two_seed` so its rays are fresh; only the second
call's tallies form the estimates (the pilot's counts are kept apart). A plan without
columns refuses a two-stage rule with its reason.

The functions marked *transitional* keep the callers of the former per-instrument routes
working over this one path until they build plans themselves.

References
----------
Baranoski et al. (2001), eqs. (2) and (23).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Sequence

import numpy as np

from virtspec_mi.budgets import twostage
from virtspec_mi.base.checks import check_readings, check_rays_needed, check_wavelength_range, shown_value
from virtspec_mi.plugins.specimen import specimen_of
import virtspec_mi.base.interrupts as interrupts
from virtspec_mi.engine.checkpoint import Checkpoint
from virtspec_mi.engine.parameters import apply_point, current_values
from virtspec_mi.engine.plan import Plan, kernel_options
from virtspec_mi.engine.progress import Progress
from virtspec_mi.engine.tally import Tally
from virtspec_mi.settings import Settings

__all__ = ["BatchRunner", "run", "take_keyed_readings", "trace_readings", "trace_allocated", "in_process_runner",
           "shares_wavelengths", "check_specimen"]

BatchRunner = Callable[[list[np.ndarray]], Iterable[tuple[np.ndarray, Tally]]]
"""
What runs the batches of a keyed :func:`run`: given the batches left to do (arrays of
reading indices), yield ``(batch, tally)`` for each as it finishes, in any order, every
tally from :func:`take_keyed_readings` (its ``seconds`` the batch's). The default runs
them here, one after the other (:func:`in_process_runner`); :mod:`virtspec_mi.runtime.scaleout`
runs them on Dask workers.
"""


# -- one plan, one path ---------------------------------------------------------------------


def run(bench: Any, plan: Plan, *, checkpoint: Any = None, progress: bool | None = False,
        runner: BatchRunner | None = None) -> Tally:
    """
    Every reading of ``plan`` on ``bench`` as one :class:`~virtspec_mi.engine.tally.Tally`
    over the flat readings (see the module docstring).

    Keyed on the reading indices: batches of about ``chunk_size`` rays, each recorded in ``checkpoint``
    (a path, or ``None``; a run that resumes from it says so on stderr unless ``progress``
    is ``False``; the checkpoint is left in place when the run completes: the caller
    removes it once the result is safe, :func:`virtspec_mi.engine.checkpoint.remove`, and
    holds it meanwhile, :func:`virtspec_mi.engine.checkpoint.claim`) and shown by
    ``progress``; ``runner`` (a :data:`BatchRunner`) runs the batches left to do elsewhere
    (Dask workers); the default runs them here. The batches, the checkpoint and the
    tallies are the same either way.

    SIGINT and SIGTERM stop the run at its next safe point — after a kernel chunk (each
    lasts about :data:`~virtspec_mi.kernel.tracer.CHUNK_SECONDS` at most) or a batch,
    or while it waits for Dask workers — with the checkpoint saved:
    :class:`~virtspec_mi.base.interrupts.Interrupted` names the signal and the
    checkpoint (:mod:`virtspec_mi.base.interrupts`).
    """

    shared = _shares(bench, plan)
    size = plan.size
    check_readings(size, (size // len(plan.wavelengths) if shared else size) * plan.most_rays_spent)
    with interrupts.deferred():  # SIGINT/SIGTERM stop the run at its next safe point (between kernel chunks)
        return _run_keyed(bench, plan, shared, checkpoint, progress, runner or in_process_runner(bench, plan))


def take_keyed_readings(bench: Any, plan: Plan, batch: Any) -> Tally:
    """
    The tallies of readings ``batch`` of ``plan`` — flat indices, any subset in any order
    — as a :class:`~virtspec_mi.engine.tally.Tally` in the order of ``batch``. Reading k
    traces from global ray index key·stride (:mod:`virtspec_mi.engine.plan`), so its
    tallies depend on (seed, key) only — never on which other readings share the batch.
    The readings of one (group, parameter point) are traced in one
    :func:`trace_readings` call after the point's values are set on the scene
    (:func:`virtspec_mi.engine.parameters.apply_point`); the scene's own values are
    restored before it returns (or raises). The one function that traces a batch of a
    keyed run, here or on a Dask worker (:mod:`virtspec_mi.runtime.scaleout`).
    """

    batch = np.asarray(batch, dtype=np.int64)
    group, point, theta, lam = plan.split(batch)
    offsets = (batch % plan.keys) * plan.stride
    space = plan.parameters
    parts, order = [], []
    original = None if space is None else current_values(bench, space.keys)
    try:
        for p, g in sorted({(int(p), int(g)) for p, g in zip(point, group)}):
            members = np.flatnonzero((point == p) & (group == g))
            if space is not None:
                apply_point(bench, space.keys, space.point(p))
            parts.append(trace_readings(bench, plan, g, _readings(plan, theta[members], lam[members]),
                                        offsets=offsets[members], share=len(members) / len(batch)))
            order.append(members)
    finally:
        if space is not None:
            apply_point(bench, space.keys, original)  # the scene as it was, whatever the driver
    back = np.argsort(np.concatenate(order), kind="stable")
    return Tally.concatenate(parts).take(back).with_seconds(0.0)


def trace_readings(bench: Any, plan: Plan, group: int, readings: Sequence[tuple[float, float, float]],
                   offsets: Sequence[int] | np.ndarray | None = None, progress: bool | None = False,
                   share: float = 1.0) -> Tally:
    """
    Trace every (wavelength nm, θi, φi) of ``readings`` with ``plan``'s settings, budget
    and group ``group``'s hook, each with its own independent rays, and return their
    :class:`~virtspec_mi.engine.tally.Tally` (its pilot ``None`` unless two-stage).

    Each reading gets the budget's N (``settings.rays_per_reading``), or, under a
    two-stage rule, a pilot batch and its own second batch (see the module docstring).
    ``offsets`` (optional) gives each reading's first global ray index, so that a
    reading's random numbers depend only on (seed, offset) and not on the other
    readings of the call (default: consecutive ranges of the traced readings; see
    :func:`~virtspec_mi.kernel.tracer.tally_readings`); both two-stage batches use the
    same offsets, with different seeds.

    Readings of a wavelength-independent specimen with the same (θi, φi) are traced once
    — with the rays (offset) of the first of them in the list — and all report those
    tallies (unless the plan's hooks are spectral). A specimen with a
    ``wavelength_range`` attribute refuses wavelengths outside it, and one with a
    ``check_wavelengths`` method parameters out of range at them (``ValueError``).
    Before anything is traced, the call is held to
    :data:`~virtspec_mi.base.checks.MAX_READINGS` readings and
    :data:`~virtspec_mi.base.checks.MAX_TOTAL_RAYS` rays, and every reading's N (the two-stage
    N₂ included) to :data:`~virtspec_mi.base.checks.MAX_RAYS`. ``progress`` shows the
    readings traced (per chunk; both stages of two-stage) by the rule of
    :mod:`virtspec_mi.engine.progress`; within an enclosing run's bar, the call moves it by
    ``share`` of the step under way there.
    """

    settings = plan.settings
    readings, source, traced = _traced_readings(bench, readings, _shares(bench, plan))
    if offsets is not None and len(offsets) != len(readings):
        raise ValueError(f"offsets must hold one start per reading ({len(readings)}), got {len(offsets)}")
    check_readings(len(readings), len(traced) * plan.most_rays_spent)
    traced_readings = [readings[k] for k in traced]
    traced_offsets = None if offsets is None else np.asarray(offsets)[traced]
    hook = plan.hook(group)
    pilot = None
    bar = Progress(progress, total=len(traced) * (2 if plan.adaptive else 1), desc="readings", share=share)
    try:
        if plan.adaptive:
            tally, pilot = _two_stage(bench, traced_readings, plan, traced_offsets, bar, hook)
        else:
            rays = np.full(len(traced), settings.rays_per_reading)
            tally = _fixed(bench, traced_readings, settings, rays, traced_offsets, bar.reach, hook)
    finally:
        bar.close()
    back = np.searchsorted(traced, source)
    return Tally(tally.counts, None if pilot is None else pilot.counts, tally.bins, tally.sums).take(back)


def trace_allocated(bench: Any, settings: Settings, readings: Sequence[tuple[float, float, float]],
                    rays: Sequence[int] | np.ndarray, offsets: Sequence[int] | np.ndarray | None = None) -> Tally:
    """
    Trace every (wavelength nm, θi, φi) of ``readings`` with its own number of rays
    ``rays[i]`` (an allocation among wavelengths, e.g. Nₖ ∝ |wₖ| of a derived quantity:
    :mod:`virtspec_mi.applications.targets`) in one batched kernel call with ``settings``'
    seed, beam, sampling and chunk size, and return their
    :class:`~virtspec_mi.engine.tally.Tally`. Every reading has rays of its own — never
    shared across wavelengths, even for a wavelength-independent specimen — from global
    index ``offsets[i]`` (default: consecutive ranges), so the readings are independent.
    The specimen's wavelength checks and the limits on readings and rays apply as for
    :func:`trace_readings`.
    """

    rays = np.asarray(rays, dtype=np.int64)
    if len(rays) != len(readings) or np.any(rays < 1):
        raise ValueError(f"rays must hold one positive count per reading ({len(readings)}), got {rays.tolist()[:8]}")
    if offsets is not None and len(offsets) != len(readings):
        raise ValueError(f"offsets must hold one start per reading ({len(readings)}), got {len(offsets)}")
    readings, _, _ = _traced_readings(bench, readings, False)
    check_readings(len(readings), int(rays.sum()))
    for n in np.unique(rays):
        check_rays_needed(int(n), "the allocation")
    starts = np.concatenate([[0], np.cumsum(rays)])  # the bar moves by rays (an enclosing run's, if any)
    bar = Progress(False, total=int(rays.sum()), unit="ray")
    try:
        tally = _fixed(bench, readings, settings, rays, None if offsets is None else np.asarray(offsets),
                       lambda done: bar.reach(float(np.interp(done, np.arange(len(starts)), starts))))
    finally:
        bar.close()
    return Tally(tally.counts, None, tally.bins, tally.sums)


def in_process_runner(bench: Any, plan: Plan) -> BatchRunner:
    """
    The default :data:`BatchRunner`: every batch here, one after the other, traced by
    :func:`take_keyed_readings` with its seconds.
    """

    def runner(batches: list[np.ndarray]) -> Iterator[tuple[np.ndarray, Tally]]:
        for batch in batches:
            start = time.perf_counter()
            tally = take_keyed_readings(bench, plan, batch)
            yield batch, tally.with_seconds(time.perf_counter() - start)

    return runner


def shares_wavelengths(bench: Any) -> bool:
    """True when the specimen declares itself wavelength-independent (the specimen protocol: ``specimen_of``)."""

    return specimen_of(bench.bsdf).wavelength_independent


def _shares(bench: Any, plan: Plan) -> bool:
    """Whether readings that differ only in wavelength share rays: the specimen's and the hooks' say."""

    return shares_wavelengths(bench) and not plan.spectral


def _readings(plan: Plan, theta: np.ndarray, lam: np.ndarray) -> list[tuple[float, float, float]]:
    """The (wavelength, θi, φi) of readings with angle indices ``theta`` and wavelength indices ``lam``."""

    lams, angles, phi = plan.wavelengths, plan.theta_i, plan.settings.phi_i
    return [(float(lams[i]), angles[t], phi) for t, i in zip(theta, lam)]


def _traced_readings(bench: Any, readings: Sequence[tuple[float, float, float]], shared: bool
                     ) -> tuple[list[tuple[float, float, float]], np.ndarray, np.ndarray]:
    """
    The checked readings as floats, each reading's source (the reading whose rays it
    reports) and the readings to trace: when ``shared``, the first reading of every
    (θi, φi), else every reading (model only what is needed).
    """

    check_readings(len(readings), 0)
    check_specimen(bench.bsdf, sorted({float(r[0]) for r in readings}))
    readings = [(float(w), float(t), float(p)) for w, t, p in readings]
    if shared:
        first: dict[tuple[float, float], int] = {}
        source = np.array([first.setdefault((t, p), k) for k, (_, t, p) in enumerate(readings)], dtype=np.int64)
        traced = np.unique(source)
    else:
        source = traced = np.arange(len(readings))
    return readings, source, traced


def check_specimen(bsdf: Any, wavelengths: list[float]) -> None:
    """
    Refuse, before tracing, wavelengths the specimen does not take (read through the
    specimen protocol, :func:`~virtspec_mi.plugins.specimen.specimen_of`): outside its
    wavelength range (the ABM leaves' data, a measured table's), outside the data of any
    Mitsuba spectrum it holds (:func:`virtspec_mi.kernel.spectra.check_covered`: a
    ``regular``/``irregular`` spectrum's range, an RGB colour's CIE range), or where its
    ``check_wavelengths`` finds a spectral parameter out of range (``turbid_slab``'s spectra).
    """

    from virtspec_mi.kernel.spectra import check_covered  # Mitsuba is set up by now (a bench is loaded)

    specimen = specimen_of(bsdf)
    check_wavelength_range(wavelengths, specimen.wavelength_range, specimen.name)
    check_covered(bsdf, wavelengths, f"the specimen {specimen.name}")
    specimen.check_wavelengths(wavelengths)


def _fixed(bench: Any, readings: Sequence[tuple[float, float, float]], settings: Settings, rays: np.ndarray,
           offsets: np.ndarray | None, on_chunk: Any = None, hook: Any = None) -> Any:
    """One batched kernel call: reading i gets ``rays[i]`` rays from global index ``offsets[i]`` (a KernelTally)."""

    # Dr.Jit loads libLLVM on import: the kernel is imported once Mitsuba is set up
    # (virtspec_mi.runtime refuses a bad libLLVM with the fix, never the abort).
    from virtspec_mi.kernel import tracer

    plans = [tracer.ReadingPlan(w, t, p, int(n)) for (w, t, p), n in zip(readings, rays)]

    def chunk_done(readings_done: int) -> None:  # a safe point: an interrupt stops the run here
        interrupts.check()
        if on_chunk is not None:
            on_chunk(readings_done)

    return tracer.tally_readings(bench, plans, offsets=offsets, hook=hook, on_chunk=chunk_done,
                                 safe_point=interrupts.check, **kernel_options(settings))


def _two_stage(bench: Any, readings: Sequence[tuple[float, float, float]], plan: Plan, offsets: np.ndarray | None,
               bar: Progress, hook: Any) -> tuple[Any, Any]:
    """Pilot batch, N₂ per reading from its pilot's columns, fresh second batch (two calls in all)."""

    settings = plan.settings
    pilot_rays = np.full(len(readings), settings.pilot_rays_per_reading)
    pilot = _fixed(bench, readings, settings, pilot_rays, offsets, bar.reach, hook)
    second = plan.columns.stage_two_rays(plan.columns.of(pilot.counts, pilot.bins), settings)
    check_rays_needed(int(second.max(initial=1)), f"the two-stage second batch for mu = {shown_value(settings.mu)}, "
                                                  f"delta = {shown_value(settings.delta)}")
    stage_two = settings.updated(seed=twostage.stage_two_seed(settings.seed))
    done = len(readings)  # the second stage's readings follow the pilots' on the bar
    return _fixed(bench, readings, stage_two, second, offsets, lambda n: bar.reach(done + n), hook), pilot


def _run_keyed(bench: Any, plan: Plan, shared: bool, checkpoint: Any, progress: bool | None,
               runner: BatchRunner) -> Tally:
    """
    The readings of :func:`run` keyed on their index, in checkpointed batches of about
    ``chunk_size`` rays, each traced by :func:`take_keyed_readings` through ``runner``.
    """

    settings, size = plan.settings, plan.size
    n_lam = len(plan.wavelengths)
    stride = plan.stride
    units = ([np.arange(i, i + n_lam) for i in range(0, size, n_lam)] if shared
             else [np.array([k]) for k in range(size)])
    per_batch = max(1, settings.chunk_size // stride)
    batches = [np.concatenate(units[i:i + per_batch]) for i in range(0, len(units), per_batch)]
    if plan.adaptive:  # a pilot of n1 rays, then a second batch of at most the stride
        rays, pilot_rays = (0, stride), (settings.pilot_rays_per_reading,) * 2
    else:
        rays, pilot_rays = (settings.rays_per_reading,) * 2, (0, 0)
    state = Checkpoint.open(checkpoint, plan.identity(bench, shared), size, rays=rays, pilot_rays=pilot_rays,
                            group=n_lam if shared else 1, bins=plan.bins, sums=plan.sums)
    todo = [b for b in (b[~state.done[b]] for b in batches) if len(b)]
    per_unit = n_lam if shared else 1
    bar = Progress(progress, total=sum(len(b) for b in todo) // per_unit)
    if state.reused:
        bar.note(f"resumed from {checkpoint}: {state.reused} of {size} readings reused")
    finished = runner(todo) if todo else iter(())
    steps = iter([len(b) // per_unit for b in todo] + [0])  # the batches in the order a runner here takes them
    try:
        bar.expect(next(steps))  # a batch's kernel chunks move the bar as they finish (nested bars)
        for batch, tally in finished:
            state.record(batch, tally)
            bar.update(len(batch) // per_unit, tally.seconds)
            bar.expect(next(steps, 0))
            interrupts.check()
    except interrupts.Interrupted as stop:  # the message names the file to resume from
        stop.checkpoint = None if checkpoint is None else Path(checkpoint)
        raise
    finally:
        close = getattr(finished, "close", None)
        if close is not None:
            close()  # a runner elsewhere stops its outstanding work
        bar.close()
        state.flush()  # every finished reading is on disk, interrupted or not (saving may be spaced out)
    return state.tally(pilot=plan.adaptive)
