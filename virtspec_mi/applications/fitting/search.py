"""
The search of a fit made cheaper: a start from the table, and fewer wavelengths while searching
=================================================================================================

Two helpers of :func:`virtspec_mi.applications.fitting.fit` that save forward rays without
touching what the fit certifies:

- :func:`table_start`: the table (a grid of certified readings over the free parameters) is
  interpolated multilinearly, spectrum by spectrum, and the loss minimised over a fine grid
  of that interpolation — free of rays. Its best point starts the refinement, which the
  table's best node alone would start one table step away from the optimum at worst. The
  interpolation only chooses where to look: no reading, no verdict comes from it.
- :func:`search_problem`: when the measurement has many wavelengths, the refinement's
  stages and the confirmation of the intervals' ends read a subset of them (about ``count``):
  for each free parameter the wavelengths where the table's spectra change most along it, in
  units of the measurement's uncertainty — where the data can tell its values apart — and the
  rest evenly spread over the fitted range (its first and last, and each window's own
  wavelengths, kept). A reading's rays grow with its wavelengths (each is certified at
  δ / (n_λ n_q), so a wavelength costs a little less when there are fewer), so these stages
  cost about ``count / n_λ`` of full ones. Their readings are candidates of the confidence set
  **judged on their own wavelengths**: such a reading is certified jointly at the same δ, so
  the true parameters pass its test with the same probability; it rejects less than a test on
  every wavelength, so the set keeps its level and is only wider. The estimate is the
  search's best point read again on every fitted wavelength at μ*; a candidate read both ways
  at one tolerance is judged by the full reading.

References
----------
W.H. Press, S.A. Teukolsky, W.T. Vetterling, B.P. Flannery (2007), *Numerical Recipes*, 3rd
ed., Sect. 3.6 (multilinear interpolation on a grid) and Sect. 10.5 (the downhill simplex
started near the minimum).
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Sequence

import numpy as np
from scipy.interpolate import RegularGridInterpolator

from virtspec_mi.applications.fitting.forward import Reading
from virtspec_mi.applications.fitting.problem import FitProblem

__all__ = ["table_start", "search_problem", "SURROGATE_POINTS"]

SURROGATE_POINTS: int = 4097
"""About this many points of the fine grid on which the interpolated table's loss is evaluated."""


def table_start(readings: Sequence[Reading], problem: FitProblem,
                loss: Callable[[Reading, FitProblem], float]) -> np.ndarray:
    """
    The free parameters' values minimising ``loss`` over the table's multilinear interpolation
    (the table's best node when the readings are not a full grid of at least 2 values each).
    """

    best = min(readings, key=lambda r: loss(r, problem)).values
    grid = _grid(readings, problem)
    if grid is None:
        return best
    axes, spectra = grid
    interpolators = {q: RegularGridInterpolator(axes, spectra[q]) for q in problem.quantities}
    per_axis = max(3, int(round(SURROGATE_POINTS ** (1.0 / len(axes)))))
    fine = np.stack(np.meshgrid(*(np.linspace(a[0], a[-1], per_axis) for a in axes), indexing="ij"), axis=-1)
    fine = fine.reshape(-1, len(axes))
    predicted = {q: interpolators[q](fine) for q in problem.quantities}
    scores = [loss(Reading(values=fine[k], mu=np.nan, predicted={q: predicted[q][k] for q in predicted},
                           tolerance={}, rays=0, stage="table interpolation"), problem) for k in range(len(fine))]
    return fine[int(np.argmin(scores))] if np.isfinite(np.min(scores)) else best


def _grid(readings: Sequence[Reading], problem: FitProblem) -> tuple[list[np.ndarray], dict[str, np.ndarray]] | None:
    """The table's axes and spectra (quantity → array of shape grid + (n_λ,)); ``None``: not a full grid."""

    if not readings or any(r.subset is not None for r in readings):
        return None
    values = np.array([r.values for r in readings])
    axes = [np.unique(values[:, i]) for i in range(values.shape[1])]
    shape = tuple(len(a) for a in axes)
    if min(shape) < 2 or int(np.prod(shape)) != len(readings):
        return None
    index = tuple(np.searchsorted(axis, values[:, i]) for i, axis in enumerate(axes))
    spectra = {}
    for quantity in problem.quantities:
        spectra[quantity] = np.empty(shape + (len(problem.wavelengths),))
        spectra[quantity][index] = np.array([r.predicted[quantity] for r in readings])
    return axes, spectra


def search_problem(problem: FitProblem, count: int | None, keep: np.ndarray | None = None,
                   table: Sequence[Reading] = ()) -> tuple[FitProblem, np.ndarray] | None:
    """
    The fit's problem on at most ``count`` of its wavelengths and the mask of those, or ``None``
    when that would be all of them. Chosen: with a ``table`` (a full grid), for each free
    parameter the ``count`` / (n + 1) wavelengths where the table's spectra change most along that
    parameter, in units of the measurement's uncertainty (mean |step| between neighbouring
    nodes), the rest evenly spread (the first and last included); without, all evenly spread.
    Those where ``keep`` is true are added.
    """

    size = len(problem.wavelengths)
    if count is None or size <= count:
        return None
    chosen = np.zeros(size, dtype=bool)
    grid = _grid(table, problem)
    parameters = 0 if grid is None else len(grid[0])
    share = count // (parameters + 1)
    chosen[np.unique(np.round(np.linspace(0, size - 1, count - parameters * share)).astype(int))] = True
    if grid is not None:
        spectra = grid[1]
        for i in range(parameters):
            change = sum(np.mean(np.abs(np.diff(spectra[q], axis=i)), axis=tuple(range(parameters)))
                         / problem.uncertainty[q] for q in problem.quantities)
            taken = 0
            for k in np.argsort(-change, kind="stable"):
                if taken == share:
                    break
                if not chosen[k]:
                    chosen[k] = True
                    taken += 1
    if keep is not None:
        chosen |= keep
    if chosen.all():
        return None
    return dataclasses.replace(problem, wavelengths=problem.wavelengths[chosen],
                               measured={q: v[chosen] for q, v in problem.measured.items()},
                               uncertainty={q: v[chosen] for q, v in problem.uncertainty.items()}), chosen
