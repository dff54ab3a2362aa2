"""
Every spectrum of a measured file fitted: :func:`fit_samples`, a table of fits
==============================================================================

A spectral library, a compound JCAMP-DX file or a table of many samples
(:mod:`virtspec_mi.exchange.measured`) holds many labelled spectra; :func:`fit_samples`
runs :func:`~virtspec_mi.applications.fitting.inversion.fit` on each of them with the same
specimen, free parameters and options, and returns a :class:`FitTable`: one row per sample
(its estimate, each parameter's interval from its confidence set, whether the fit is
consistent, its statistic, the parameters its data leave unconstrained), and the
:class:`~virtspec_mi.applications.fitting.result.FitResult` of each.

Each sample's fit is the fit of that spectrum alone, with its own confidence set at level
1 − δ: the table states no joint level over the samples (each row's promise holds for its
row; over k rows a union bound gives 1 − kδ for all at once).

- In this process (``workers=None``) the samples are fitted one after the other and share
  one coarse table (a Zarr store: ``DIRECTORY/table.zarr``, else a temporary one): the
  table's forward readings do not depend on the measurement, so it is traced once.
- With ``workers`` (a number of local Dask worker processes, a scheduler address or a
  ``distributed.Client``, as :func:`virtspec_mi.sweep` takes them) the first sample's fit
  traces the shared table on the cluster (its sweep's tasks), then each other sample's fit
  is one Dask task (:mod:`virtspec_mi.runtime.scaleout`'s workers: libLLVM, the variant and the
  plugins set up); the specimen (a plugin's name, an XML path or a scene dict), the file's
  path and the table's path are sent, and every worker reads them itself (a remote cluster
  needs them on a shared file system: give ``directory``). A fit's readings depend on
  (seed, the readings' keys) only, so the rows equal the in-process ones.

With ``directory`` each sample's readings are kept in ``DIRECTORY/<k>`` (resumable, as a
single fit's).

References
----------
Féret et al. (2017), RSE 193:204–215 (PROSPECT inversion); Dask ``distributed``
documentation (``Client.map``).
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from virtspec_mi.applications.fitting.result import FitResult
from virtspec_mi.exchange.measured import MeasuredFile, read_samples

__all__ = ["fit_samples", "FitTable", "TABLE_SUFFIXES"]

TABLE_SUFFIXES: tuple[str, ...] = (".csv", ".nc")
"""The files a :class:`FitTable` writes."""


@dataclass(frozen=True, eq=False)
class FitTable:
    """The fits of every sample of a measured file (see the module docstring)."""

    source: str
    """The measured file's name."""
    labels: tuple[str, ...]
    fits: tuple[FitResult, ...]
    """Each sample's fit, in the order of :attr:`labels`."""

    @property
    def names(self) -> tuple[str, ...]:
        return self.fits[0].names

    @property
    def estimate(self) -> np.ndarray:
        """(k, n): each sample's estimate of each free parameter."""

        return np.array([fit.estimate for fit in self.fits])

    @property
    def intervals(self) -> np.ndarray:
        """(k, n, 2): each sample's interval of each free parameter (its own confidence set's)."""

        return np.array([fit.intervals for fit in self.fits])

    @property
    def consistent(self) -> np.ndarray:
        return np.array([fit.consistent for fit in self.fits])

    @property
    def statistic(self) -> np.ndarray:
        return np.array([fit.statistic for fit in self.fits])

    def to_dataset(self) -> Any:
        """The table as an ``xarray.Dataset`` over ``sample`` (and ``parameter``)."""

        import xarray as xr

        intervals = self.intervals
        return xr.Dataset(
            {"estimate": (("sample", "parameter"), self.estimate),
             "lowest": (("sample", "parameter"), intervals[..., 0]),
             "highest": (("sample", "parameter"), intervals[..., 1]),
             "unconstrained": (("sample", "parameter"), np.array([fit.unconstrained for fit in self.fits])),
             "consistent": ("sample", self.consistent), "statistic": ("sample", self.statistic)},
            coords={"sample": list(self.labels), "parameter": list(self.names)},
            attrs={"source": self.source, "specimen": self.fits[0].specimen, "delta": self.fits[0].delta,
                   "level": f"each row's confidence set at level {1 - self.fits[0].delta:g} (no joint level)"})

    def summary(self) -> str:
        """One line per sample: its estimate and intervals, consistent or not."""

        level = 1 - self.fits[0].delta
        lines = [f"{len(self.labels)} spectra of {self.source} fitted with {self.fits[0].specimen} (each interval "
                 f"from its own confidence set at level {level:g}; no joint level over the rows)"]
        for label, fit in zip(self.labels, self.fits):
            parts = [f"{name} = {value:.4g} [{low:.4g}, {high:.4g}]" + (" unconstrained" if free else "")
                     for name, value, (low, high), free in zip(fit.names, fit.estimate, fit.intervals,
                                                                 fit.unconstrained)]
            verdict = "consistent" if fit.consistent else "INCONSISTENT"
            lines.append(f"{label}: {', '.join(parts)}; {verdict} (s = {fit.statistic:.3f})")
        return "\n".join(lines)

    def write(self, path: str | os.PathLike) -> Path:
        """The table as ``.csv`` (a row per sample and parameter) or ``.nc``."""

        from virtspec_mi.base.files import atomic_write

        path = Path(path)
        if path.suffix.lower() not in TABLE_SUFFIXES:
            raise ValueError(f"a fit table is {' or '.join(TABLE_SUFFIXES)} (got {path.name})")
        dataset = self.to_dataset()
        if path.suffix.lower() == ".nc":
            return atomic_write(path, lambda name: dataset.to_netcdf(name))
        frame = dataset.to_dataframe().reset_index()
        return atomic_write(path, lambda name: frame.to_csv(name, index=False))


def _fit_one(file: MeasuredFile, specimen: Any, parameters: dict[str, Any], directory: str | None,
             options: dict[str, Any]) -> FitResult:
    """One sample's fit (in this process or a Dask worker: the scene loaded where it runs)."""

    from virtspec_mi.applications.fitting.inversion import fit
    from virtspec_mi.runtime import mitsuba

    mitsuba()  # on a worker: libLLVM, the variant and the plugins in the thread that runs the task (idempotent)
    return fit(file, specimen, parameters, directory=directory, **options)


def fit_samples(measured: MeasuredFile | str | os.PathLike, specimen: Any, parameters: Mapping[str, Any], *,
                samples: Any = None, workers: Any = None, directory: str | os.PathLike | None = None,
                **options: Any) -> FitTable:
    """
    Fit every sample of ``measured`` (or those ``samples`` names: labels or indices) and
    return their :class:`FitTable` (see the module docstring). ``options`` are
    :func:`~virtspec_mi.applications.fitting.inversion.fit`'s (``measurement_uncertainty``,
    ``delta``, ``seed``, the forward readings' settings …; not ``table``, which is shared
    here, nor ``workers``, which places the samples' fits).
    """

    from virtspec_mi.runtime.scaleout import check_workers, connect

    if "table" in options:
        raise ValueError("fit_samples shares one coarse table between the samples (DIRECTORY/table.zarr): "
                         "table= is not taken")
    file = measured if isinstance(measured, MeasuredFile) else MeasuredFile(measured)
    file = replace(file, path=os.path.abspath(os.fspath(file.path)), sample=None)
    table = read_samples(file)
    chosen = list(range(len(table))) if samples is None else [table.index(s) for s in samples]
    if not chosen:
        raise ValueError(f"samples must name at least one sample of {table.source}")
    workers = check_workers(workers)
    with tempfile.TemporaryDirectory(prefix="virtspec-fit-") as scratch:
        work = Path(directory) if directory is not None else Path(scratch)
        work.mkdir(parents=True, exist_ok=True)
        shared = dict(options, table=str(work / "table.zarr"))
        parameters = dict(parameters)
        tasks = [(replace(file, sample=k), None if directory is None else str(work / str(k))) for k in chosen]
        if workers is None:
            fits = [_fit_one(one, specimen, parameters, place, shared) for one, place in tasks]
        else:
            with connect(workers) as client:
                # the first sample's fit traces the shared table on the cluster (its sweep's tasks), once
                first = _fit_one(tasks[0][0], specimen, parameters, tasks[0][1], dict(shared, workers=client))
                rest = tasks[1:]
                futures = client.map(_fit_one, [one for one, _ in rest], [specimen] * len(rest),
                                     [parameters] * len(rest), [place for _, place in rest], [shared] * len(rest),
                                     pure=False)
                fits = [first, *client.gather(futures)]
    return FitTable(source=table.source, labels=tuple(table.labels[k] for k in chosen), fits=tuple(fits))
