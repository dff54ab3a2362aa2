"""
The engine: from planned readings to exact counts and results
=============================================================

:func:`take_readings` is the one path from a list of readings — each a (wavelength,
θi, φi) — to exact :class:`~virtspec_mi.kernel.counts.Counts`: it sizes every reading with
the settings' ray budget (:mod:`virtspec_mi.budgets.rules`) and traces all of them through
the ray kernel (:mod:`virtspec_mi.kernel.tracer`) in as few launches as memory allows
(chunks of ``settings.chunk_size`` rays that may span many readings).
:func:`run` lays a grid of readings (wavelength × θi, and specimen parameter points
when given: :mod:`virtspec_mi.engine.parameters`) out for it — in one call, or in batches keyed
on each reading's index so that a run can be checkpointed, resumed and shown with a
progress bar — and returns one :class:`~virtspec_mi.results.hemispherical.Result`.
:func:`take_keyed_readings` traces one batch of a keyed run (any block of reading
indices): it sets each parameter point on the scene, then traces that point's readings.

Model only what is needed: a specimen whose BSDF declares
``wavelength_independent = True`` (e.g. ``simple_dielectric``) is traced once per
incidence (θi, φi); readings that differ only in wavelength share those rays and counts.

A fixed budget (``hoeffding``, ``chebyshev``, ``exact``, or explicit ``rays``) is one
batched call. ``two-stage`` is two: one batched pilot call over all readings (seed
``settings.seed``), then one batched call with each reading's own N₂ from its pilot
counts (:func:`virtspec_mi.budgets.twostage.stage_two_rays`), traced with the distinct seed
:func:`virtspec_mi.budgets.twostage.stage_two_seed` so its rays are fresh; only the second
call's counts form the estimates (the pilot's are kept apart).

References
----------
Baranoski et al. (2001), eqs. (2) and (23).
"""

from __future__ import annotations

import time
from dataclasses import asdict
from typing import Any, Callable, Iterable, Iterator, Sequence

import numpy as np

from virtspec_mi.budgets import twostage
from virtspec_mi.engine.checkpoint import Checkpoint
from virtspec_mi.checks import check_readings, check_rays_needed, check_wavelength_range, shown_value
from virtspec_mi.kernel.counts import Counts
from virtspec_mi.engine.parameters import ParameterSpace, apply_point, current_values
from virtspec_mi.engine.progress import Progress
from virtspec_mi.results.hemispherical import Result
from virtspec_mi.settings import Settings

__all__ = ["take_readings", "take_keyed_readings", "in_process_runner", "shares_wavelengths", "run", "measure_reading",
           "take_gonio_readings", "run_gonio", "gonio_reading", "BatchRunner"]

BatchRunner = Callable[[list[np.ndarray]], Iterable[tuple[np.ndarray, Counts, "Counts | None", float]]]
"""
What runs the batches of a keyed :func:`run`: given the batches left to do (arrays of
reading indices), yield ``(batch, counts, pilot, seconds)`` for each as it finishes, in
any order, every count from :func:`take_keyed_readings`. The default runs them here, one
after the other; :mod:`virtspec_mi.scaleout` runs them on Dask workers.
"""


def take_readings(
    instrument: Any,
    readings: Sequence[tuple[float, float, float]],
    settings: Settings,
    offsets: Sequence[int] | np.ndarray | None = None,
    progress: bool | None = False,
) -> tuple[Counts, Counts | None]:
    """
    Trace every (wavelength nm, θi, φi) of ``readings``, each with its own independent
    rays, and return their exact counts and, for ``two-stage``, the pilot's (else ``None``).

    Each reading gets ``settings.rays_per_reading`` rays (eq. 23 by default), or, with
    ``bound="two-stage"``, a pilot batch and its own second batch (see above).
    ``offsets`` (optional) gives each reading's first global ray index, so that a
    reading's random numbers depend only on (seed, offset) and not on the other
    readings of the call (default: consecutive ranges of the traced readings; see
    :func:`~virtspec_mi.kernel.tracer.tally_readings`); both two-stage batches use the
    same offsets, with different seeds.

    When the specimen's BSDF has ``wavelength_independent = True``, readings with the
    same (θi, φi) are traced once — with the rays (offset) of the first of them in the
    list — and all report those counts. A specimen with a ``wavelength_range``
    attribute refuses wavelengths outside it, and one with a ``check_wavelengths``
    method parameters out of range at them (``ValueError``). Before anything is traced,
    the call is held to :data:`~virtspec_mi.checks.MAX_READINGS` readings and
    :data:`~virtspec_mi.checks.MAX_TOTAL_RAYS` rays, and every reading's N (the
    two-stage N₂ included) to :data:`~virtspec_mi.checks.MAX_RAYS`. ``progress`` shows
    the readings traced (per chunk; both stages of ``two-stage``) by the rule of
    :mod:`virtspec_mi.engine.progress`.
    """

    readings, source, traced = _traced_readings(instrument, readings)
    if offsets is not None and len(offsets) != len(readings):
        raise ValueError(f"offsets must hold one start per reading ({len(readings)}), got {len(offsets)}")
    check_readings(len(readings), len(traced) * settings.most_rays_spent_per_reading)
    traced_readings = [readings[k] for k in traced]
    traced_offsets = None if offsets is None else np.asarray(offsets)[traced]
    pilot = None
    bar = Progress(progress, total=len(traced) * (2 if settings.adaptive else 1), desc="readings")
    try:
        if settings.adaptive:
            counts, pilot = _two_stage(instrument, traced_readings, settings, traced_offsets, bar)
        else:
            rays = np.full(len(traced), settings.rays_per_reading)
            counts = _fixed(instrument, traced_readings, settings, rays, traced_offsets, bar.reach)
    finally:
        bar.close()
    back = np.searchsorted(traced, source)
    return counts.map(lambda v: v[back]), None if pilot is None else pilot.map(lambda v: v[back])


def _traced_readings(instrument: Any, readings: Sequence[tuple[float, float, float]]
                     ) -> tuple[list[tuple[float, float, float]], np.ndarray, np.ndarray]:
    """
    The checked readings as floats, each reading's source (the reading whose rays it
    reports) and the readings to trace: for a wavelength-independent specimen the first
    reading of every (θi, φi), else every reading (model only what is needed).
    """

    check_readings(len(readings), 0)
    _check_specimen(instrument.bsdf, sorted({float(r[0]) for r in readings}))
    readings = [(float(w), float(t), float(p)) for w, t, p in readings]
    if shares_wavelengths(instrument):
        first: dict[tuple[float, float], int] = {}
        source = np.array([first.setdefault((t, p), k) for k, (_, t, p) in enumerate(readings)], dtype=np.int64)
        traced = np.unique(source)
    else:
        source = traced = np.arange(len(readings))
    return readings, source, traced


def _check_specimen(bsdf: Any, wavelengths: list[float]) -> None:
    """
    Refuse, before tracing, wavelengths the specimen does not take: outside its
    ``wavelength_range`` (the ABM leaves' data), or where its ``check_wavelengths``
    finds a spectral parameter out of range (``turbid_slab``'s spectra).
    """

    check_wavelength_range(wavelengths, getattr(bsdf, "wavelength_range", None),
                           getattr(bsdf, "PLUGIN", "") or type(bsdf).__name__)
    check = getattr(bsdf, "check_wavelengths", None)
    if check is not None:
        check(wavelengths)


def shares_wavelengths(instrument: Any) -> bool:
    """True when the specimen's BSDF declares ``wavelength_independent = True``."""

    return bool(getattr(instrument.bsdf, "wavelength_independent", False))


def take_keyed_readings(instrument: Any, settings: Settings, theta_i: Sequence[float], batch: np.ndarray,
                        parameters: ParameterSpace | None = None) -> tuple[Counts, Counts | None]:
    """
    The exact counts (and two-stage pilot counts, else ``None``, as :func:`take_readings`
    returns them) of readings ``batch`` — flat indices, any subset in any order — of the
    keyed grid ``settings.wavelengths`` × ``theta_i`` × parameter points: reading
    k = (i_p·n_θ + i_θ)·n_λ + i_λ is wavelength i_λ at angle i_θ for parameter point i_p
    (the wavelength fastest; without ``parameters`` one point, k = i_θ·n_λ + i_λ as every
    sweep has always numbered them). It is traced from global ray index
    k·``settings.most_rays_per_reading``, so its counts depend on (seed, k) only — never on
    which other readings share the batch. The readings of one parameter point are traced
    in one :func:`take_readings` call after the point's values are set on the scene
    (:func:`virtspec_mi.engine.parameters.apply_point`); the scene's own values are restored
    before it returns (or raises). The one function that traces a batch of a keyed run, here
    or on a Dask worker (:mod:`virtspec_mi.scaleout`).
    """

    lams = np.asarray(settings.wavelengths, dtype=np.float64)
    angles = np.asarray(theta_i, dtype=np.float64)
    batch = np.asarray(batch, dtype=np.int64)
    n_lam, per_point = len(lams), len(lams) * len(angles)
    stride = settings.most_rays_per_reading

    def readings(indices: np.ndarray) -> list[tuple[float, float, float]]:
        inner = indices % per_point
        return [(lams[k % n_lam], angles[k // n_lam], settings.phi_i) for k in inner]

    if parameters is None:
        return take_readings(instrument, readings(batch), settings, offsets=batch * stride)
    point_of = batch // per_point
    parts, order = [], []
    original = current_values(instrument, parameters.keys)
    try:
        for point in np.unique(point_of):
            members = np.flatnonzero(point_of == point)
            apply_point(instrument, parameters.keys, parameters.point(int(point)))
            parts.append(take_readings(instrument, readings(batch[members]), settings,
                                       offsets=batch[members] * stride))
            order.append(members)
    finally:
        apply_point(instrument, parameters.keys, original)  # the scene as it was, whatever the driver
    back = np.argsort(np.concatenate(order), kind="stable")
    counts = Counts.concatenate([c for c, _ in parts]).map(lambda v: v[back])
    if not settings.adaptive:
        return counts, None
    return counts, Counts.concatenate([p for _, p in parts]).map(lambda v: v[back])


def run(
    instrument: Any,
    settings: Settings,
    theta_i: Sequence[float],
    *,
    keyed: bool,
    scene: str = "",
    checkpoint: Any = None,
    progress: bool | None = False,
    parameters: ParameterSpace | None = None,
    runner: BatchRunner | None = None,
) -> Result:
    """
    Every reading of the grid ``settings.wavelengths`` × ``theta_i`` (× the points of
    ``parameters``, keyed only) at ``settings.phi_i``, as one
    :class:`~virtspec_mi.results.hemispherical.Result` with dims ``("wavelength", "theta_i", *parameter dims)``.

    ``keyed=False``: one :func:`take_readings` call with consecutive ray ranges (how
    ``measure`` has always numbered its rays), its bar updated per chunk. ``keyed=True``: reading k
    (k = (i_p·n_θ + i_θ)·n_λ + i_λ, see :func:`take_keyed_readings`) owns the global ray indices [k·stride, k·stride + rays_k), with
    stride = ``settings.most_rays_per_reading``, so its counts depend on (seed, k) only;
    readings run in batches of about ``chunk_size`` rays, each recorded in
    ``checkpoint`` (a path; see :mod:`virtspec_mi.engine.checkpoint`) and shown by
    ``progress`` (see :mod:`virtspec_mi.engine.progress`). A run that resumes from
    ``checkpoint`` says so on stderr (unless ``progress`` is ``False``). The checkpoint
    is left in place when the run completes: the caller removes it once the result is
    safe (:func:`virtspec_mi.engine.checkpoint.remove`), and holds it meanwhile
    (:func:`virtspec_mi.engine.checkpoint.claim`). ``runner`` (keyed only; a :data:`BatchRunner`)
    runs the batches left to do elsewhere (Dask workers); the default runs them here. The
    batches, the checkpoint and the counts are the same either way.
    """

    angles = np.asarray(theta_i, dtype=np.float64)
    lams = np.asarray(settings.wavelengths, dtype=np.float64)
    n_lam, n_theta = len(lams), len(angles)
    if parameters is not None and not keyed:
        raise ValueError("a run over parameters must be keyed on reading indices (keyed=True)")
    size = n_lam * n_theta * (1 if parameters is None else parameters.size)
    shared = shares_wavelengths(instrument)
    traced = size // n_lam if shared else size
    check_readings(size, traced * settings.most_rays_spent_per_reading)
    if not keyed:
        flat_lam, flat_theta = np.tile(lams, n_theta), np.repeat(angles, n_lam)
        start = time.perf_counter()
        counts, pilot = take_readings(
            instrument, [(w, t, settings.phi_i) for w, t in zip(flat_lam, flat_theta)], settings, progress=progress)
        seconds = time.perf_counter() - start
    else:
        counts, pilot, seconds = _run_keyed(
            instrument, settings, angles, parameters, shared, scene, checkpoint, progress,
            runner or in_process_runner(instrument, settings, theta_i=angles, parameters=parameters))
    extra = () if parameters is None else parameters.shape
    axes = tuple(range(len(extra) + 2))

    def layout(values: np.ndarray) -> np.ndarray:  # flat k -> (wavelength, theta_i, *parameter dims)
        return np.transpose(values.reshape(*extra, n_theta, n_lam), (axes[-1], axes[-2], *axes[:-2])).copy()

    return Result(
        dims=("wavelength", "theta_i", *(() if parameters is None else parameters.dims)),
        coords={"wavelength": lams, "theta_i": angles, **({} if parameters is None else parameters.coords())},
        counts=counts.map(layout),
        pilot=None if pilot is None else pilot.map(layout),
        settings=settings.updated(theta_i=float(angles[0])),
        geometry=instrument.geometry,
        seconds=seconds,
        scene=scene,
        wavelength_independent=shared,
        parameters=None if parameters is None else parameters.as_dict(),
    )


def _run_keyed(instrument: Any, settings: Settings, angles: np.ndarray, parameters: ParameterSpace | None,
               shared: bool, scene: str, checkpoint: Any, progress: bool | None,
               runner: BatchRunner) -> tuple[Counts, Counts | None, float]:
    """
    The readings of :func:`run` keyed on their index, in checkpointed batches of about
    ``chunk_size`` rays, each traced by :func:`take_keyed_readings` through ``runner``.
    """

    n_lam = len(settings.wavelengths)
    size = n_lam * len(angles) * (1 if parameters is None else parameters.size)
    stride = settings.most_rays_per_reading
    units = ([np.arange(i, i + n_lam) for i in range(0, size, n_lam)] if shared
             else [np.array([k]) for k in range(size)])
    per_batch = max(1, settings.chunk_size // stride)
    batches = [np.concatenate(units[i:i + per_batch]) for i in range(0, len(units), per_batch)]
    if settings.adaptive:  # a pilot of n1 rays, then a second batch of at most the stride
        rays, pilot_rays = (0, stride), (settings.pilot_rays_per_reading,) * 2
    else:
        rays, pilot_rays = (settings.rays_per_reading,) * 2, (0, 0)
    state = Checkpoint.open(checkpoint, _identity(settings, angles, parameters, instrument, scene, shared), size,
                            rays=rays, pilot_rays=pilot_rays, group=n_lam if shared else 1)
    todo = [b for b in (b[~state.done[b]] for b in batches) if len(b)]
    per_unit = n_lam if shared else 1
    bar = Progress(progress, total=sum(len(b) for b in todo) // per_unit)
    if state.reused:
        bar.note(f"resumed from {checkpoint}: {state.reused} of {size} readings reused")
    finished = runner(todo) if todo else iter(())
    try:
        for batch, counts, pilot, seconds in finished:
            state.record(batch, counts, pilot, seconds)
            bar.update(len(batch) // per_unit, seconds)
    finally:
        close = getattr(finished, "close", None)
        if close is not None:
            close()  # a runner elsewhere stops its outstanding work
        bar.close()
        state.flush()  # every finished reading is on disk, interrupted or not (saving may be spaced out)
    return state.counts, state.pilot if settings.adaptive else None, state.seconds


def in_process_runner(instrument: Any, settings: Settings, **grid: Any) -> BatchRunner:
    """
    The default :data:`BatchRunner`: every batch here, one after the other, traced by
    ``take_keyed_readings(instrument, settings, batch=batch, **grid)`` (``grid``: the
    keyed grid's other arguments, e.g. ``theta_i``).
    """

    def runner(batches: list[np.ndarray]) -> Iterator[tuple[np.ndarray, Counts, Counts | None, float]]:
        for batch in batches:
            start = time.perf_counter()
            counts, pilot = take_keyed_readings(instrument, settings, batch=batch, **grid)
            yield batch, counts, pilot, time.perf_counter() - start

    return runner


def measure_reading(instrument: Any, settings: Settings, progress: bool | None = False) -> Result:
    """
    One reading per wavelength of ``settings`` at its θi on an instrument read from a
    loaded scene: a :class:`~virtspec_mi.results.hemispherical.Result` with the dim ``wavelength``
    (what :func:`virtspec_mi.measure` and the ``spectrophotometer`` integrator return).
    ``progress``: a bar of the readings traced (see :mod:`virtspec_mi.engine.progress`).
    """

    return run(instrument, settings, [settings.theta_i], keyed=False, progress=progress).squeeze()


def _identity(settings: Settings, angles: np.ndarray, parameters: ParameterSpace | None, instrument: Any, scene: str,
              shared: bool) -> dict[str, Any]:
    """Everything that decides a keyed run's counts (chunk size and version do not); the parameters when swept."""

    common = {k: v for k, v in settings.as_dict().items() if k != "theta_i"}
    identity = {
        **common,
        "theta_i": [float(t) for t in angles],
        "geometry": asdict(instrument.geometry),
        "scene": scene,
        "wavelength_independent": shared,
    }
    if parameters is not None:
        identity["parameters"] = parameters.as_dict()
    return identity


def _fixed(instrument: Any, readings: Sequence[tuple[float, float, float]], settings: Settings,
           rays: np.ndarray, offsets: np.ndarray | None, on_chunk: Any = None) -> Counts:
    """One batched kernel call: reading i gets ``rays[i]`` rays from global index ``offsets[i]``."""

    # Dr.Jit loads libLLVM on import: the kernel is imported once Mitsuba is set up
    # (virtspec_mi.runtime refuses a bad libLLVM with the fix, never the abort).
    from virtspec_mi.kernel.tracer import ReadingPlan, tally_readings

    plans = [ReadingPlan(w, t, p, int(n)) for (w, t, p), n in zip(readings, rays)]
    return tally_readings(instrument, plans, settings, offsets, on_chunk)


def _two_stage(instrument: Any, readings: Sequence[tuple[float, float, float]], settings: Settings,
               offsets: np.ndarray | None, bar: Progress) -> tuple[Counts, Counts]:
    """Pilot batch, N₂ per reading from its counts, fresh second batch (two calls in all)."""

    pilot_rays = np.full(len(readings), settings.pilot_rays_per_reading)
    pilot = _fixed(instrument, readings, settings, pilot_rays, offsets, bar.reach)
    columns = [pilot.reflected, pilot.transmitted] + ([] if settings.joint else [pilot.absorbed])
    second = twostage.stage_two_rays(
        np.stack(columns, axis=1), settings.pilot_rays_per_reading, settings.mu, settings.delta,
        settings.pilot_delta_value, joint=settings.joint,
    )
    check_rays_needed(int(second.max(initial=1)), f"the two-stage second batch for mu = {shown_value(settings.mu)}, "
                                         f"delta = {shown_value(settings.delta)}")
    stage_two = settings.updated(seed=twostage.stage_two_seed(settings.seed))
    done = len(readings)  # the second stage's readings follow the pilots' on the bar
    return _fixed(instrument, readings, stage_two, second, offsets, lambda n: bar.reach(done + n)), pilot


def take_gonio_readings(instrument: Any, readings: Sequence[tuple[float, float, float]], settings: Settings,
                        bins: Any) -> tuple[Counts, np.ndarray]:
    """
    :func:`take_readings` for a goniophotometer reading: the same rays and counts (a
    fixed budget: ``rays`` or the rule's N; two-stage is refused), plus the exact
    per-bin tallies of the escaping rays, shape (readings, θo bins, φo bins)
    (:func:`virtspec_mi.kernel.tracer.tally_gonio_readings`). Readings of a
    wavelength-independent specimen that differ only in wavelength share rays, counts
    and tallies, as in :func:`take_readings`.
    """

    from virtspec_mi.kernel.tracer import ReadingPlan, tally_gonio_readings

    if settings.adaptive:
        raise ValueError("bound must be a fixed budget for a goniophotometer reading (hoeffding, chebyshev, "
                         "exact or rays given; two-stage sizes each reading for R and T, not for its bins)")
    readings, source, traced = _traced_readings(instrument, readings)
    check_readings(len(readings), len(traced) * settings.rays_per_reading)
    plans = [ReadingPlan(*readings[k], settings.rays_per_reading) for k in traced]
    counts, tallies = tally_gonio_readings(instrument, plans, settings, bins)
    back = np.searchsorted(traced, source)
    return counts.map(lambda v: v[back]), tallies[back]


def run_gonio(instrument: Any, settings: Settings, theta_i: Sequence[float], bins: Any, *, scene: str = "",
              guarantee: str = "rays", relative_tolerance: float | None = None,
              brdf_floor: float | None = None) -> Any:
    """
    Goniophotometer readings over the grid ``settings.wavelengths`` × ``theta_i`` at
    ``settings.phi_i``, binned by ``bins``, as one
    :class:`~virtspec_mi.results.goniophotometer.GonioResult` (one kernel call, consecutive ray
    ranges as :func:`run` with ``keyed=False``: the counts equal that reading's).
    """

    from virtspec_mi.results.goniophotometer import GonioResult

    angles = np.asarray(theta_i, dtype=np.float64)
    lams = np.asarray(settings.wavelengths, dtype=np.float64)
    n_lam, n_theta = len(lams), len(angles)
    flat_lam, flat_theta = np.tile(lams, n_theta), np.repeat(angles, n_lam)
    start = time.perf_counter()
    counts, tallies = take_gonio_readings(
        instrument, [(w, t, settings.phi_i) for w, t in zip(flat_lam, flat_theta)], settings, bins)
    seconds = time.perf_counter() - start

    def grid(values: np.ndarray) -> np.ndarray:
        return np.moveaxis(values.reshape(n_theta, n_lam, *values.shape[1:]), 0, 1).copy()

    result = Result(dims=("wavelength", "theta_i"), coords={"wavelength": lams, "theta_i": angles},
                    counts=counts.map(grid), pilot=None, settings=settings.updated(theta_i=float(angles[0])),
                    geometry=instrument.geometry, seconds=seconds, scene=scene,
                    wavelength_independent=shares_wavelengths(instrument))
    return GonioResult(result=result, bin_counts=grid(tallies), bins=bins, guarantee=guarantee,
                       relative_tolerance=relative_tolerance, brdf_floor=brdf_floor)


def gonio_reading(instrument: Any, settings: Settings, options: dict[str, Any],
                  theta_i: Sequence[float] | None = None, scene: str = "") -> Any:
    """
    A goniophotometer reading of an instrument at ``theta_i`` (default: ``settings.theta_i``)
    with the goniophotometer parameters ``options``
    (:data:`~virtspec_mi.geometry.bins.GONIO_PARAMETERS`; absent ones take their default):
    the bins are built (a bad specification is a ``ValueError`` naming the parameter),
    N is ``settings.rays`` or sized by ``guarantee`` over the K bins (the rule's
    :meth:`~virtspec_mi.budgets.rules.Guarantee.rays`, its options checked by
    :func:`virtspec_mi.budgets.rules.check_gonio_options`), then :func:`run_gonio`.
    """

    from virtspec_mi.budgets.rules import check_gonio_options
    from virtspec_mi.geometry.bins import gonio_options, make_bins

    spec = gonio_options(options, "gonio")
    angles = np.atleast_1d(np.asarray(settings.theta_i if theta_i is None else theta_i, dtype=np.float64))
    bins = make_bins(spec["theta_o_bins"], spec["phi_o_bins"], spec["binning"], spec["fold_phi"], spec["hemispheres"])
    rule, relative, floor = check_gonio_options(spec["guarantee"], settings.delta, bins.size,
                                                spec["relative_tolerance"], spec["brdf_floor"])
    if settings.rays is None:
        rays = rule.rays(settings.mu, settings.delta, bins.size, relative=relative, floor=floor,
                         smallest_solid_angle=float(bins.projected_solid_angles().min()))
        guarantee = rule.name
    else:
        rays, guarantee = settings.rays, "rays"
    resolved = settings.updated(theta_i=float(angles[0]), rays=rays)
    return run_gonio(instrument, resolved, angles, bins, scene=scene, guarantee=guarantee,
                     relative_tolerance=relative, brdf_floor=floor)
