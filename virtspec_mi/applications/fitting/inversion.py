"""
``fit``: a specimen's parameters from a measured spectrum, with an honest confidence set
========================================================================================

:func:`fit` finds the free parameters of a specimen (a leaf's pigments, water and dry
matter, a slab's μa and μs, a rough surface's α …) whose certified forward spectrum
matches a measured reflectance and/or transmittance, and says which parameters the
measurement cannot tell apart from them.

The forward model is the instrument itself (:mod:`.forward`): noisy, but certified, and
on common random numbers across candidates. The fit goes

1. **table**: a coarse grid over the box of bounds, one sweep at a coarse tolerance
   (a Zarr store, reusable by a later fit: a look-up-table inversion);
2. **refinement**: from the minimum of the table's multilinear interpolation (no rays;
   :func:`.search.table_start`), Nelder–Mead (``scipy.optimize``) on the chosen ``loss`` in
   stages whose tolerance shrinks (4 μ*, 2 μ*, μ*; never coarser than the table's), each
   stage starting from the last one's best, the simplex shrinking with it: rays are raised as
   the fit converges, and the **estimate** is the best candidate of the last stage, read at
   μ* = ``mu_fraction`` × the smallest measurement uncertainty (or ``forward_mu``). With more
   than ``search_wavelengths`` fitted wavelengths the stages read a subset of them — where the
   table's spectra change most along each parameter, the rest evenly spread
   (:func:`.search.search_problem`; candidates judged on their own wavelengths) — and the
   estimate is read again on all;
3. **profiles**: along each free parameter through the estimate (the others held), at μ*:
   ``profile_points`` over the bounds, then each end of the consistent stretch bisected
   :data:`PROFILE_BISECTIONS` times;
4. **confirmation**: a candidate that makes an end of an interval while judged only at a
   coarser tolerance (the table's, an early stage's) is read again at μ* and judged by that
   reading, until every end is judged at μ* (``confirm``), each read on the way at the
   refinement's tolerances below its own (4 μ*, 2 μ*: a sixteenth and a quarter of the rays —
   most such candidates fail there and drop out).

**The confidence set.** A candidate θ is *consistent* with the measurement when its
certified spectrum F̂(θ) lies within the combined tolerance at every fitted point:
s(θ) = max |F̂(θ) − m| / (μ'(θ) + u) ≤ 1, with μ'(θ) its certified tolerance and u the
measurement's uncertainty. For the true parameters θ₀ the test fails with probability
≤ δ (the forward readings' joint risk, :mod:`.forward`) plus the measurement's own risk
(that |m − truth| > u somewhere), so the consistent candidates are a confidence set of
level ≥ 1 − δ less that risk — the test is the one :func:`virtspec_mi.applications.comparison.compare`
counts, made simultaneous. The set is exact for the candidates tested (each passed or failed
its own test); each parameter's **interval** summarises it, running from the parameter's
smallest to its largest value among consistent candidates, each end carried out to the next
value of that parameter any candidate was tested at (or the bound). The intervals cover the
true parameters only as well as the search sampled near them: the profiles and the
confirmation (below) sample the ends, and an estimate that is itself inconsistent (s > 1
while other candidates pass) means the search has not converged — the summary says so;
raise ``evaluations``. A parameter whose interval covers ≥ 90 % of its bounds is flagged
**unconstrained** (the data do not tell its values apart). When no
candidate is consistent the fit is reported **inconsistent**: the specimen model cannot
reproduce the measurement within its stated uncertainty (a model of another material, a
biased instrument, an uncertainty too small).

Losses: ``chi2`` (mean squared residual in units of the measurement uncertainty, the
default), ``rmse`` (unweighted), ``max`` (the largest normalised residual) and ``windows``
(each parameter estimated on its own optimal spectral window, Féret et al. 2019, 2021,
Spafford et al. 2021: :mod:`.windows`; the default when ``windows=`` is given).

References
----------
J.A. Nelder, R. Mead (1965), *A simplex method for function minimization*, Comput. J. 7,
308–313; G. Casella, R.L. Berger (2002), *Statistical Inference*, 2nd ed., Sect. 9.2.1
(confidence sets by inverting a test); Féret et al. (2017), RSE 193:204–215 and
Jacquemoud & Baret (1990) (PROSPECT inversion by minimising a spectral loss).
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np
from scipy.optimize import minimize

from virtspec_mi.applications.fitting.forward import Forward, Reading, note
from virtspec_mi.applications.fitting.problem import FitProblem, describe, fit_problem
from virtspec_mi.applications.fitting.result import UNCONSTRAINED_SHARE, FitResult, intervals
from virtspec_mi.applications.fitting.search import search_problem, table_start
from virtspec_mi.applications.fitting.windows import FitWindows, fit_windows, window_loss
from virtspec_mi.base.checks import real
from virtspec_mi.base.files import check_distinct
from virtspec_mi.engine.parameters import apply_point, known_parameters
from virtspec_mi.engine.progress import Progress

__all__ = ["fit", "LOSSES", "LOSS_NAMES", "SEARCH_WAVELENGTHS", "UNCONSTRAINED_SHARE", "PROFILE_BISECTIONS",
           "consistency", "intervals", "verdicts"]

PROFILE_BISECTIONS: int = 4
"""Bisections at each end of a profile's consistent stretch."""

SEARCH_WAVELENGTHS: int = 16
"""The refinement's search and the confirmation read about this many of the fitted wavelengths (:mod:`.search`)."""

_STAGES = (4.0, 2.0, 1.0)  # the refinement's tolerances, in units of mu*
_TABLE_MU = 0.02  # the table's tolerance (unless mu* is larger)


def _against(reading: Reading, problem: FitProblem, q: str) -> tuple[np.ndarray, np.ndarray]:
    """The measurement and its uncertainty on the reading's own wavelengths (all, or a search reading's subset)."""

    if reading.subset is None:
        return problem.measured[q], problem.uncertainty[q]
    return problem.measured[q][reading.subset], problem.uncertainty[q][reading.subset]


def _chi2(reading: Reading, problem: FitProblem) -> float:
    return float(np.mean([np.mean(((reading.predicted[q] - m) / u) ** 2)
                          for q in problem.quantities for m, u in [_against(reading, problem, q)]]))


def _rmse(reading: Reading, problem: FitProblem) -> float:
    return float(np.sqrt(np.mean([np.mean((reading.predicted[q] - _against(reading, problem, q)[0]) ** 2)
                                  for q in problem.quantities])))


def _largest(reading: Reading, problem: FitProblem) -> float:
    return float(max(np.max(np.abs(reading.predicted[q] - m) / u)
                     for q in problem.quantities for m, u in [_against(reading, problem, q)]))


LOSSES: dict[str, Callable[[Reading, FitProblem], float]] = {"chi2": _chi2, "rmse": _rmse, "max": _largest}
"""The losses over the whole fitted spectrum, by name."""

LOSS_NAMES: tuple[str, ...] = (*LOSSES, "windows")
"""Every loss a fit minimises: :data:`LOSSES` and ``windows`` (one window per parameter, :mod:`.windows`)."""


def consistency(reading: Reading, problem: FitProblem) -> float:
    """
    s = max |F̂ − m| / (μ' + u) over every point of the reading (≤ 1: consistent; NaN tolerance:
    inf): all the fitted wavelengths, or a search reading's subset of them.
    """

    worst = 0.0
    for q in problem.quantities:
        measured, uncertainty = _against(reading, problem, q)
        tolerance = reading.tolerance[q] + uncertainty
        ratio = np.abs(reading.predicted[q] - measured) / tolerance
        worst = max(worst, float(np.max(np.where(np.isnan(ratio), np.inf, ratio))))
    return worst


def verdicts(readings: Sequence[Reading], statistic: np.ndarray) -> np.ndarray:
    """
    Whether each reading's candidate is consistent: the verdict of the finest reading of the
    same parameter values (a candidate read again at a smaller tolerance is judged by that).
    """

    finest: dict[tuple, tuple[tuple[float, bool], float]] = {}
    for reading, s in zip(readings, statistic):
        key = tuple(reading.values.tolist())
        rank = (reading.mu, reading.subset is not None)  # at one tolerance, a reading of every wavelength first
        if key not in finest or rank < finest[key][0]:
            finest[key] = (rank, float(s))
    return np.array([finest[tuple(r.values.tolist())][1] <= 1.0 for r in readings], dtype=bool)


def _table_points(count: int) -> int:
    return {1: 9, 2: 5, 3: 4}.get(count, 3)


def _check_choices(loss: str, delta: float, mu_fraction: float, forward_mu: float | None, table_points: int | None,
                   profile_points: int, evaluations: Sequence[int] | None) -> None:
    if loss not in LOSS_NAMES:
        raise ValueError(f"loss must be one of {', '.join(LOSS_NAMES)} (got {loss!r})")
    if not 0.0 < delta < 1.0:
        raise ValueError(f"delta must satisfy 0 < delta < 1 (got {delta!r})")
    if not 0.0 < mu_fraction <= 1.0:
        raise ValueError(f"mu_fraction must satisfy 0 < mu_fraction <= 1 (got {mu_fraction!r})")
    if forward_mu is not None and not 0.0 < forward_mu < 0.5:
        raise ValueError(f"forward_mu must satisfy 0 < forward_mu < 0.5 (got {forward_mu!r})")
    if table_points is not None and not (isinstance(table_points, int) and 2 <= table_points <= 100):
        raise ValueError(f"table_points must be a whole number, 2 <= table_points <= 100 (got {table_points!r})")
    if not (isinstance(profile_points, int) and (profile_points == 0 or 2 <= profile_points <= 100)):
        raise ValueError(f"profile_points must be 0 (none) or a whole number 2 ... 100 (got {profile_points!r})")
    if evaluations is not None and (len(evaluations) != len(_STAGES)
                                    or not all(isinstance(e, int) and e >= 0 for e in evaluations)):
        raise ValueError(f"evaluations must be {len(_STAGES)} whole numbers >= 0, one per refinement stage "
                         f"(got {evaluations!r})")


def fit(measured: Any, specimen: Any, parameters: Mapping[str, Any], *, quantities: Sequence[str] | None = None,
        measurement_uncertainty: Any = None, wavelengths: Any = None, loss: str | None = None,
        windows: Mapping[str, Any] | None = None, delta: float = 0.05,
        mu_fraction: float = 0.5, forward_mu: float | None = None, table: str | os.PathLike | None = None,
        table_points: int | None = None, evaluations: Sequence[int] | None = None, profile_points: int = 5,
        confirm: bool = True, search_wavelengths: int | None = SEARCH_WAVELENGTHS, seed: int = 0,
        directory: str | os.PathLike | None = None, defines: dict[str, Any] | None = None,
        workers: Any = None, progress: bool | None = None, **settings: Any) -> FitResult:
    """
    Fit the free ``parameters`` of ``specimen`` to a measured spectrum (see the module docstring).

    Parameters
    ----------
    measured
        A measured spectrum (any :func:`~virtspec_mi.applications.comparison.read_measured` source: a
        ``wavelength,value,uncertainty`` CSV, a NetCDF file, a ``(wavelengths, values,
        uncertainty)`` tuple, a result), read as each of ``quantities``; or a dict
        quantity → source (``{"reflectance": ..., "transmittance": ...}``).
    specimen
        A BSDF plugin's name (``"abm_b"``, ``"prospect_d"``: the paper's instrument around
        it), a shipped scene's name, an XML path, a scene dict, an ``mi.Scene`` or a
        :class:`~virtspec_mi.runtime.scene.LoadedScene`: loaded once, every forward reading takes it.
    parameters
        Free parameter → (lowest, highest) (or ``"lo:hi"``), named as the specimen shows
        them (``"Cab"`` or ``"specimen.Cab"``); both bounds are checked by the specimen.
    quantities
        What ``measured`` holds when it is not a dict: ``("reflectance",)`` (default),
        ``("transmittance",)`` or both (a file with both columns).
    measurement_uncertainty
        A number or one value per measured point: the measurement's uncertainty (a
        half-width), overriding the file's. Required when the file has none.
    wavelengths
        The wavelengths to fit (nm, inside the measured range; the measurement is
        interpolated onto them); default the measured ones.
    loss
        ``chi2`` (the default without ``windows``), ``rmse``, ``max`` (:data:`LOSSES`) or
        ``windows`` (the default with ``windows``): each parameter with a window estimated by a
        refinement on the chi-square over its window only, the others on the full range
        (:mod:`.windows`).
    windows
        Free parameter → its window(s) in nm, ``(lowest, highest)`` or a list of them, for
        ``loss="windows"``; each inside the fitted wavelengths. Free parameters named as
        PROSPECT-D's (``Cab``, ``Car``, ``Anth``, ``Cw``, ``Cm``) not given take the published
        optimal windows (:data:`.windows.OPTIMAL_WINDOWS`).
    delta
        Risk of the forward readings for one candidate's whole spectrum (the confidence
        set's level is 1 − δ less the measurement's own risk).
    mu_fraction, forward_mu
        The tolerance of the forward readings at the optimum: ``mu_fraction`` × the
        smallest measurement uncertainty, or ``forward_mu`` when given.
    table
        A Zarr store of the coarse table (:func:`virtspec_mi.api.sweep` over the free
        parameters as a grid named ``specimen.NAME``, on the fit's wavelengths, each reading
        at δ / n_λ or better): read when it exists, else written there. Default:
        ``DIRECTORY/table.zarr`` with ``directory``, else kept in memory.
    table_points
        Values per parameter in the table (default 9, 5, 4, then 3 for 1, 2, 3, more parameters).
    evaluations
        Forward readings per refinement stage (default 12, 6, 3 per free parameter).
    profile_points
        Points of each parameter's profile at μ* (0: none).
    search_wavelengths
        The refinement's stages and the confirmation read about this many of the fitted
        wavelengths (where the table's spectra change most along each free parameter, the rest
        evenly spread, each window's kept; default :data:`SEARCH_WAVELENGTHS`; ``None``: all).
        Those readings are candidates judged on their own wavelengths (a test on fewer
        wavelengths rejects less: still valid, the set wider); the estimate is the search's best
        point read again on every fitted wavelength at μ* (:mod:`.search`).
    confirm
        Read the candidates that make the intervals' ends while judged only at a coarser
        tolerance again at μ*, and judge them by that reading (default ``True``; ``False``
        keeps the coarse verdicts: still a valid, wider confidence set).
    seed
        The seed of every forward reading (common random numbers).
    directory
        Work directory: the table and every forward reading are kept there, so that the
        same call, run again, resumes (:mod:`.forward`).
    workers
        Dask workers for the table's sweep (as :func:`virtspec_mi.api.sweep`).
    progress
        ``True``: a progress bar and a line on stderr per stage; ``False``: neither;
        default: both when stderr is a terminal (the bar once the fit lasts more than ~2 s).
    **settings
        The forward readings' other settings (``theta_i``, ``beam``, ``bound`` …,
        :class:`~virtspec_mi.settings.Settings`); ``mu``, ``delta``, ``seed``, ``joint``,
        ``rays`` and ``wavelengths`` are the fit's own.

    Raises
    ------
    ValueError
        Bad input: a parameter the specimen does not have, bounds outside its validity, a
        measured spectrum outside the specimen's data range or without uncertainty, …
    """

    started = time.perf_counter()
    delta = real("delta", delta)
    mu_fraction = real("mu_fraction", mu_fraction)
    forward_mu = None if forward_mu is None else real("forward_mu", forward_mu)
    loss = ("windows" if windows is not None else "chi2") if loss is None else loss
    if windows is not None and loss != "windows":
        raise ValueError(f"windows= chooses the windows of loss='windows' (got loss={loss!r})")
    _check_choices(loss, delta, mu_fraction, forward_mu, table_points, profile_points, evaluations)
    if search_wavelengths is not None and not (isinstance(search_wavelengths, int) and search_wavelengths >= 2):
        raise ValueError(f"search_wavelengths must be None (all) or a whole number >= 2 (got {search_wavelengths!r})")
    sources = measured.items() if isinstance(measured, Mapping) else [("measured", measured)]
    check_distinct([("table", table), ("directory", directory)],  # no output over an input, before any reading
                   [*((f"measured[{key!r}]" if isinstance(measured, Mapping) else key, path) for key, path in sources),
                    ("specimen", specimen)])
    problem = fit_problem(measured, specimen, parameters, quantities=quantities, wavelengths=wavelengths,
                          measurement_uncertainty=measurement_uncertainty, defines=defines)
    chosen = fit_windows(windows, problem.names, problem.wavelengths) if loss == "windows" else None
    drawn, progress = progress, sys.stderr.isatty() if progress is None else bool(progress)
    smallest = min(float(problem.uncertainty[q].min()) for q in problem.quantities)
    target = forward_mu if forward_mu is not None else mu_fraction * smallest
    if not 0.0 < target < 0.5:
        raise ValueError(f"the forward tolerance at the optimum, {target:g}, must lie in (0, 0.5)")
    work = None if directory is None else Path(directory)
    if work is not None:
        work.mkdir(parents=True, exist_ok=True)
    table_path = Path(table) if table is not None else (None if work is None else work / "table.zarr")
    forward = Forward(problem, delta=delta, seed=seed, settings=settings, directory=work, workers=workers,
                      progress=progress)
    measure_loss = LOSSES[loss] if chosen is None else chosen.loss()
    loss_name = loss if chosen is None else chosen.describe(problem.names)
    count = len(problem.names)
    points = table_points or _table_points(count)
    budget = evaluations if evaluations is not None else tuple(k * count for k in (12, 6, 3))
    refinements = 1 if chosen is None else len(chosen.masks) + 1
    bar = Progress(drawn, points ** count + refinements * sum(budget) + profile_points * count, desc="fit")
    forward.bar = bar  # one update per forward reading (a longer bar when the fit reads more)
    try:
        grid = [np.linspace(low, high, points) for low, high in problem.bounds]
        table_mu = max(_TABLE_MU, target)
        readings = forward.table(grid, table_mu, table_path)
        keep = None if chosen is None else np.logical_or.reduce(list(chosen.masks.values()))
        subset = search_problem(problem, search_wavelengths, keep, readings)
        search = forward if subset is None else Forward(subset[0], delta=delta, seed=seed, settings=settings,
                                                         directory=work, progress=progress, subset=subset[1])
        search.bar = bar
        step = 0.5 / (points - 1)
        settled: list[bool] = []
        if chosen is None:
            start = table_start(readings, problem, measure_loss)
            found = _refine(search, problem, start, target, table_mu, budget, step, measure_loss, settled=settled)
            estimate = found if search is forward else forward.reading(found.values, target, "estimate")
        else:
            estimate = _refine_windows(forward, problem, chosen, readings, search, target, table_mu, budget, step,
                                       settled)
        if profile_points:
            for i, name in enumerate(problem.names):
                count_read = _profile(forward, problem, estimate, i, target, profile_points)
                note(progress, f"fit: profile of {name} ({count_read} points at mu = {target:g})")
        if confirm:
            confirmed = _confirm_ends(forward, search, problem, target)
            note(progress, f"fit: {confirmed} candidates at the confidence set's ends read again at mu = {target:g}")
    finally:
        bar.close()
        keys = known_parameters(problem.scene)
        apply_point(problem.bench, [keys.get(k, k) for k in problem.keys], problem.start)
    return _result(problem, forward, estimate, loss_name, measure_loss, delta, target, mu_fraction, seed, started,
                   None if search is forward else search, converged=all(settled))


def _refine_windows(forward: Forward, problem: FitProblem, chosen: FitWindows, readings: list[Reading],
                    search: Forward, target: float, ceiling: float, budget: Sequence[int], step: float,
                    settled: list[bool] | None = None) -> Reading:
    """
    One refinement per window (all free parameters free, the loss over that window only), keeping
    its parameter's value; the parameters without a window from a refinement on the full range
    (``chi2``). The estimate: that combination, read at ``target`` (:mod:`.windows`).
    """

    values = np.full(len(problem.names), np.nan)
    for i, mask in chosen.masks.items():
        start = table_start(readings, problem, window_loss(mask))
        found = _refine(search, problem, start, target, ceiling, budget, step, window_loss(mask),
                        label=f"window {problem.names[i]}", settled=settled)
        values[i] = found.values[i]
    rest = np.isnan(values)
    if rest.any():
        start = table_start(readings, problem, _chi2)
        found = _refine(search, problem, start, target, ceiling, budget, step, _chi2, label="full range",
                        settled=settled)
        values[rest] = found.values[rest]
    return forward.reading(values, target, "windows estimate")


def _refine(forward: Forward, problem: FitProblem, start: np.ndarray, target: float, ceiling: float,
            budget: Sequence[int], step: float, measure_loss: Callable[[Reading, FitProblem], float],
            label: str = "refine", settled: list[bool] | None = None) -> Reading:
    """
    Nelder–Mead from ``start`` in stages of shrinking tolerance (module docstring), on ``forward``'s
    readings (the fit's, or the search's on fewer wavelengths); the best reading at ``target``.
    Appends to ``settled`` whether the search settled (:func:`_settled`).
    """

    x = problem.normalised(start)
    count = len(x)
    final = None
    for stage, (factor, evaluations) in enumerate(zip(_STAGES, budget), start=1):
        mu = min(target * factor, ceiling)  # never coarser than the table
        last = stage == len(_STAGES)
        tried: list[Reading] = []

        def objective(point: np.ndarray, mu: float = mu, tried: list = tried) -> float:
            reading = forward.reading(problem.denormalised(point), mu, f"{label} {stage}")
            tried.append(reading)
            return measure_loss(reading, problem)

        objective(x)  # the stage's start, at its own tolerance
        if evaluations > 1:
            simplex = np.vstack([x, *(np.clip(x + step * np.eye(count)[i] * (1 if x[i] <= 0.5 else -1), 0, 1)
                                      for i in range(count))])
            minimize(objective, x, method="Nelder-Mead", bounds=[(0.0, 1.0)] * count,
                     options={"maxfev": max(1, evaluations - 1), "initial_simplex": simplex, "xatol": 1e-4,
                              "fatol": 0.0})
        stage_best = min(tried, key=lambda r: measure_loss(r, problem))
        note(forward.progress, f"fit: {label} stage {stage}/{len(_STAGES)} at mu = {mu:g}: {len(tried)} readings, "
                               f"best loss {measure_loss(stage_best, problem):.4g}")
        moved = float(np.max(np.abs(problem.normalised(stage_best.values) - x)))
        x = problem.normalised(stage_best.values)
        if last:
            final = stage_best
            if settled is not None:
                settled.append(_settled(evaluations, count, moved, step))
        step /= 2.0
    assert final is not None
    return final


def _settled(evaluations: int, count: int, moved: float, step: float) -> bool:
    """
    Whether a refinement's last stage settled: it had room for a Nelder–Mead move beyond its
    first simplex (``count`` + 2 readings) and its best point stayed within the stage's
    simplex step of where the stage began (a search still travelling has not found the
    minimum: its estimate cannot show the model fails).
    """

    return evaluations >= count + 2 and moved <= step * (1.0 + 1e-9)


def _confirm_ends(forward: Forward, search: Forward, problem: FitProblem, target: float) -> int:
    """
    Read again at ``target`` (on the search's wavelengths) every candidate that makes an end of
    an interval while judged only at a coarser tolerance, until every end is a candidate judged
    at ``target``. Each is read at the next of the refinement's tolerances (4, 2, 1 × ``target``)
    below its finest so far: a candidate far from the estimate fails at 4 or 2 × ``target`` for a
    sixteenth or a quarter of the rays of a reading at ``target``. Returns the readings taken.
    """

    taken = 0
    while True:
        readings = forward.readings + (search.readings if search is not forward else [])
        values = np.array([r.values for r in readings])
        consistent = verdicts(readings, np.array([consistency(r, problem) for r in readings]))
        if not consistent.any():
            return taken
        finest: dict[tuple, float] = {}
        for r in readings:
            key = tuple(r.values.tolist())
            finest[key] = min(finest.get(key, np.inf), r.mu)
        ends = []
        for i in range(values.shape[1]):
            chosen = np.flatnonzero(consistent)
            for j in (chosen[np.argmin(values[chosen, i])], chosen[np.argmax(values[chosen, i])]):
                if finest[tuple(values[j].tolist())] > target:
                    ends.append(j)
        if not ends:
            return taken
        for j in dict.fromkeys(ends):
            judged = finest[tuple(values[j].tolist())]
            mu = max((target * f for f in _STAGES if target * f * (1.0 + 1e-9) < judged), default=target)
            search.reading(values[j], mu, "confirm")
            taken += 1


def _profile(forward: Forward, problem: FitProblem, estimate: Reading, i: int, target: float, points: int) -> int:
    """
    The test statistic along parameter ``i`` through the estimate (the others held): ``points``
    evenly over the bounds, then each end of the consistent stretch around the estimate found
    to 1/2^PROFILE_BISECTIONS of the step by bisection. Returns the readings taken.
    """

    stage = f"profile {problem.names[i]}"

    def statistic(value: float) -> float:
        values = estimate.values.copy()
        values[i] = value
        return consistency(forward.reading(values, target, stage), problem)

    centre = float(estimate.values[i])
    scanned = {float(v): statistic(float(v)) for v in np.linspace(*problem.bounds[i], points)}
    taken = len(scanned)
    if consistency(estimate, problem) > 1.0:
        return taken
    for side in (-1.0, 1.0):
        outside = sorted((v for v, s in scanned.items() if s > 1.0 and (v - centre) * side > 0),
                         key=lambda v: abs(v - centre))
        if not outside:
            continue
        reach = abs(outside[0] - centre)
        inside_values = [v for v, s in scanned.items() if s <= 1.0 and 0 <= (v - centre) * side < reach]
        good = max(inside_values, key=lambda v: abs(v - centre), default=centre)
        bad = outside[0]
        for _ in range(PROFILE_BISECTIONS):
            middle = 0.5 * (good + bad)
            if statistic(middle) <= 1.0:
                good = middle
            else:
                bad = middle
            taken += 1
    return taken


def _result(problem: FitProblem, forward: Forward, estimate: Reading, loss: str,
            measure_loss: Callable[[Reading, FitProblem], float], delta: float, target: float, mu_fraction: float,
            seed: int, started: float, searched: Forward | None, converged: bool = True) -> FitResult:
    readings = forward.readings + ([] if searched is None else searched.readings)
    values = np.array([r.values for r in readings])
    statistic = np.array([consistency(r, problem) for r in readings])
    consistent = verdicts(readings, statistic)
    found = intervals(values, consistent, problem.bounds)
    span = problem.bounds[:, 1] - problem.bounds[:, 0]
    unconstrained = tuple(bool(np.isfinite(w) and w >= UNCONSTRAINED_SHARE * s)
                          for w, s in zip(found[:, 1] - found[:, 0], span))
    return FitResult(
        names=problem.names, bounds=problem.bounds, estimate=estimate.values, intervals=found,
        unconstrained=unconstrained, consistent=bool(consistent.any()), statistic=consistency(estimate, problem),
        loss_name=loss, loss=measure_loss(estimate, problem), delta=delta, mu_fraction=mu_fraction,
        forward_mu=target, wavelengths=problem.wavelengths, quantities=problem.quantities,
        measured=problem.measured, uncertainty=problem.uncertainty, fitted=estimate.predicted,
        fitted_tolerance=estimate.tolerance, candidate_values=values, candidate_mu=np.array([r.mu for r in readings]),
        candidate_statistic=statistic, candidate_loss=np.array([measure_loss(r, problem) for r in readings]),
        candidate_stage=tuple(r.stage for r in readings), candidate_consistent=consistent,
        rays=int(sum(r.rays for r in readings)),
        traced_rays=forward.traced_rays + (0 if searched is None else searched.traced_rays),
        search_wavelengths=0 if searched is None else len(searched.problem.wavelengths),
        seconds=time.perf_counter() - started,
        specimen=describe(problem),
        seed=int(seed), reading_delta=forward.reading_delta, converged=bool(converged))
