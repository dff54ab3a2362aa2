"""
Certified forward readings of a fit: common random numbers, kept for a resumed fit
==================================================================================

A fit asks the specimen model for its spectrum at many candidate parameter values. Each
answer here is a certified reading of the instrument (:func:`virtspec_mi.api.sweep` at one
parameter point): every value within its ``tolerance`` of the model's true value, and
**all of a candidate's values at once** with probability ≥ 1 − δ — each reading is certified
at δ / (n_λ · n_q) (Bonferroni over the n_λ wavelengths and the n_q quantities fitted; with
both reflectance and transmittance the readings are ``joint``).

**Common random numbers.** Every candidate's reading uses the same seed, and a one-point
sweep's reading k owns the same ray indices whatever the parameter values
(:mod:`virtspec_mi.engine.readings`): two candidates are compared on the same rays, so the
difference of their spectra is the model's, not the Monte Carlo noise's, and the loss is a
deterministic function of the candidate that an optimiser can follow.

**The table.** A coarse grid over the free parameters is one sweep (its readings are each
certified, not on common random numbers) written to a Zarr store: a look-up table that
another fit of the same specimen and wavelengths reuses (``table=``), and that
``workers`` spread over Dask.

**Resuming.** With a work ``directory`` every forward reading is kept in the engine's
:class:`~virtspec_mi.engine.checkpoint.ResultStore` ``DIRECTORY/readings`` (one file per
reading, written by the sweep's own ``out=`` with its checkpoint meanwhile; the store's
``identity.json`` names the specimen and its free parameters, so that a fit of another
specimen is refused there, naming what differs) and the table in ``DIRECTORY/table.zarr``:
a fit run again with the same directory reads what is there — the optimiser,
deterministic under common random numbers, retraces its own path — and an interrupted
reading resumes from its checkpoint. A reading's label in the store is everything else
that decides its counts (parameter values, μ, δ, seed, joint, wavelengths, settings).
(Work directories of earlier releases kept ``reading-<hash>.nc`` files of their own:
they are not read, and those readings are traced again.)

References
----------
Baranoski et al. (2001), eq. (23) (the certificate); P. Glasserman (2004), *Monte Carlo
Methods in Financial Engineering*, Sect. 4.2 (common random numbers).
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from virtspec_mi.runtime.reading import read_result, take
from virtspec_mi.applications.fitting.problem import FitProblem
from virtspec_mi.engine.checkpoint import ResultStore, checkpoint_for
from virtspec_mi.base.surface import spoken
from virtspec_mi.engine.progress import Progress, expect, write
from virtspec_mi.results.zarr import unfinished
from virtspec_mi.settings import Settings, resolve

__all__ = ["Reading", "Forward", "FIT_OWNS", "STORE", "note"]

STORE: str = "readings"
"""The folder of a work directory where the forward readings are kept (a :class:`ResultStore`)."""

FIT_OWNS: tuple[str, ...] = ("wavelengths", "mu", "delta", "seed", "joint", "rays")
"""Settings a fit decides itself (refused among the forward settings)."""


@dataclass(frozen=True, eq=False)
class Reading:
    """One candidate's certified forward spectrum."""

    values: np.ndarray
    """The free parameters' values."""
    mu: float
    """The tolerance asked for."""
    predicted: dict[str, np.ndarray]
    """quantity → the reading's values on the fit's wavelengths."""
    tolerance: dict[str, np.ndarray]
    """quantity → each value's certified tolerance."""
    rays: int
    stage: str
    seconds: float = 0.0
    stats: dict[str, float] = field(default_factory=dict)
    subset: np.ndarray | None = None
    """Mask over the fit's wavelengths when the reading holds only those (a search reading); ``None``: all."""


class Forward:
    """The forward readings of one fit (see the module docstring)."""

    def __init__(self, problem: FitProblem, *, delta: float, seed: int, settings: dict[str, Any],
                 directory: Path | None, workers: Any = None, progress: bool = False,
                 subset: np.ndarray | None = None) -> None:
        owned = sorted(set(settings) & set(FIT_OWNS))
        if owned:
            raise ValueError(f"a fit sets {', '.join(owned)} of its forward readings itself (the fit's own keywords: "
                             "delta, seed, mu_fraction/forward_mu, and the measured wavelengths)")
        resolve("fit", settings, Settings())  # an unknown name: TypeError listing the settings; a bad value: ValueError
        self.problem = problem
        self.delta = float(delta)
        self.seed = int(seed)
        self.settings = dict(settings)
        self.directory = directory
        self.workers = workers
        self.progress = progress
        self.bar: Progress | None = None  # the fit's bar, when it has one (one update per forward reading)
        self.subset = subset  # the problem is the fit's on these of its wavelengths (mask), or None: the fit's own
        count = len(problem.wavelengths) * len(problem.quantities)
        self.reading_delta = self.delta / count
        self.joint = len(problem.quantities) > 1
        self.store = None if directory is None else ResultStore(
            directory / STORE, {"format": "virtspec-mi fit forward readings 1", "fingerprint": problem.fingerprint,
                                "keys": list(problem.keys)}, "fit's forward readings")
        self.cache: dict[tuple, Reading] = {}
        self.readings: list[Reading] = []
        self.traced_rays = 0

    # -- one candidate ---------------------------------------------------------------

    def _label(self, values: Sequence[float], mu: float) -> str:
        """The reading's label in the store: what decides its counts beside the store's identity."""

        return json.dumps({"values": [repr(float(v)) for v in values], "mu": repr(float(mu)),
                           "delta": repr(self.reading_delta), "seed": self.seed, "joint": self.joint,
                           "wavelengths": [repr(float(w)) for w in self.problem.wavelengths],
                           "settings": sorted((k, repr(v)) for k, v in self.settings.items())}, sort_keys=True)

    def _sweep(self, parameters: dict[str, Any], mu: float, out: Path | None, workers: Any = None) -> Any:
        wavelengths = list(map(float, self.problem.wavelengths))
        try:
            return take("sweep", self.problem.loaded, parameters=parameters, wavelengths=wavelengths, mu=mu,
                        delta=self.reading_delta, joint=self.joint, seed=self.seed, out=out, progress=False,
                        workers=workers, **self.settings)
        except KeyboardInterrupt as stop:  # the fit's work is its directory, not one reading's file
            if self.directory is not None:
                stop.checkpoint, stop.written = self.directory, None  # type: ignore[attr-defined]
            raise

    def reading(self, values: Sequence[float], mu: float, stage: str) -> Reading:
        """The certified spectrum at ``values`` (to ``mu``), traced, read from the work directory or remembered."""

        values = np.asarray(values, dtype=np.float64)
        memo = (tuple(values.tolist()), float(mu))
        if memo in self.cache:
            return self.cache[memo]
        started = time.perf_counter()
        label = self._label(values, mu)
        result = None if self.store is None else self.store.load(label, read_result)
        if result is None:
            path = None if self.store is None else self.store.path(label)  # written whole, its checkpoint meanwhile
            expect(1)  # the fit's bar moves with the reading's kernel chunks
            result = self._sweep({key: [float(v)] for key, v in zip(self.problem.keys, values)}, mu, path)
            self.traced_rays += int(np.sum(result.rays_spent))
        if self.bar is not None:
            self.bar.update(1)
        result = result.squeeze("theta_i", *self.problem.keys)
        reading = self._from_result(result, values, mu, stage, time.perf_counter() - started)
        self.cache[memo] = reading
        self.readings.append(reading)
        return reading

    def _from_result(self, result: Any, values: np.ndarray, mu: float, stage: str, seconds: float) -> Reading:
        predicted, tolerance = {}, {}
        for quantity in self.problem.quantities:
            spectrum = result.spectrum(quantity)
            predicted[quantity] = spectrum.values
            tolerance[quantity] = spectrum.tolerance
        if self.subset is not None:
            stage = f"{stage} ({len(self.problem.wavelengths)} wavelengths)"
        return Reading(values=values, mu=float(mu), predicted=predicted, tolerance=tolerance,
                       rays=int(np.sum(result.rays_spent)), stage=stage, seconds=seconds, subset=self.subset)

    # -- the table ---------------------------------------------------------------------

    def table(self, grid: Sequence[np.ndarray], mu: float, path: Path | None) -> list[Reading]:
        """
        The readings of the grid (one array of values per free parameter): one sweep, written
        to ``path`` (a ``.zarr`` store) and read back from it when it is already there.
        """

        keys = self.problem.keys
        started = time.perf_counter()
        finished = path is not None and path.exists() and not checkpoint_for(path).exists()
        if finished and unfinished(path):  # a table sweep stopped before its first reading: measured again
            finished = False
        if finished:
            result = self._check_table(read_result(path), path)
        else:
            note(self.progress, f"fit: table of {int(np.prod([len(g) for g in grid]))} points at mu = {mu:g}")
            expect(int(np.prod([len(g) for g in grid])))
            result = self._sweep({key: list(map(float, values)) for key, values in zip(keys, grid)}, mu, path,
                                 self.workers)
            self.traced_rays += int(np.sum(result.rays_spent))
        result = result.squeeze("theta_i")
        mu = float(result.settings.mu)  # a table read back: the tolerance it was measured to
        seconds = time.perf_counter() - started
        readings: list[Reading] = []
        size = int(np.prod([len(np.atleast_1d(result.coords[key])) for key in keys]))
        if self.bar is not None:
            self.bar.update(size)
        for index in np.ndindex(*(len(np.atleast_1d(result.coords[key])) for key in keys)):
            point = {key: float(np.atleast_1d(result.coords[key])[i]) for key, i in zip(keys, index)}
            one = result.sel(point)
            reading = self._from_result(one, np.array(list(point.values())), mu, "table", seconds / size)
            self.readings.append(reading)
            readings.append(reading)
        return readings

    def _check_table(self, result: Any, path: Path) -> Any:
        missing = [key for key in self.problem.keys if key not in result.dims]
        if missing:
            raise ValueError(f"the table {path} is no grid over {', '.join(missing)} (its dims: "
                             f"{', '.join(result.dims)}): make one with "
                             f"{spoken('sweep(parameters=...)', 'virtspec sweep --param NAME=VALUES --out FILE.zarr')}")
        extra = [d for d in result.dims if d not in (*self.problem.keys, "wavelength", "theta_i")]
        if extra:
            raise ValueError(f"the table {path} also varies {', '.join(extra)}: select one value first")
        if result.scene and result.scene not in self.problem.fingerprints:
            raise ValueError(f"the table {path} was measured on another scene ({result.scene}, this fit's: "
                             f"{self.problem.fingerprint})")
        if result.settings.quantity_delta > self.reading_delta * (1 + 1e-9):
            raise ValueError(f"the table {path} certifies each reading at delta {result.settings.quantity_delta:g}; "
                             f"this fit needs {self.reading_delta:g} (delta / wavelengths): measure it again")
        try:
            return result.sel(wavelength=list(map(float, self.problem.wavelengths)))
        except ValueError:
            raise ValueError(f"the table {path} lacks some of the fit's wavelengths "
                             f"({self.problem.wavelengths.min():g}-{self.problem.wavelengths.max():g} nm, "
                             f"{len(self.problem.wavelengths)} of them)") from None


def note(progress: bool, line: str) -> None:
    """One line of progress on stderr (when asked)."""

    if progress:
        write(line)  # above the fit's bar, when one is drawn
