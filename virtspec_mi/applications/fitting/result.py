"""
A fit's result: estimate, confidence set, residuals, the forward certificate, the rays
======================================================================================

:class:`FitResult` holds what :func:`virtspec_mi.applications.fitting.fit` found and how:
the estimate, each parameter's interval from the confidence set (and which parameters the
data leave unconstrained), whether the fit is consistent at all, the measured and fitted
spectra with both uncertainty bands and the residuals, every candidate read (values,
tolerance, test statistic, loss, stage: the table, the refinement, the profiles) and the
rays spent. It is written to JSON (``.json``) or NetCDF (``.nc``, through xarray),
atomically (:func:`virtspec_mi.base.files.atomic_file`), read back by :func:`read_fit`, and
plotted by :meth:`FitResult.plot` (measured against fitted with both bands, the
residuals, and each parameter's profile of the test statistic).

References
----------
Baranoski et al. (2001), eq. (23) (the certified tolerance of each fitted value).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.base.version import __version__
from virtspec_mi.base.files import atomic_file

__all__ = ["FitResult", "read_fit", "FIT_FORMAT", "FIT_SUFFIXES"]

FIT_FORMAT: str = "virtspec-mi fit 1"
"""The ``format`` of a fit file."""
FIT_SUFFIXES: tuple[str, ...] = (".json", ".nc")

_ARRAYS = ("bounds", "estimate", "intervals", "wavelengths", "candidate_values", "candidate_mu",
           "candidate_statistic", "candidate_loss", "candidate_consistent")
_SPECTRA = ("measured", "uncertainty", "fitted", "fitted_tolerance")


@dataclass(frozen=True, eq=False)
class FitResult:
    """What a fit found (see the module docstring); arrays in the order of :attr:`names`."""

    names: tuple[str, ...]
    bounds: np.ndarray
    estimate: np.ndarray
    intervals: np.ndarray
    """(n, 2): each parameter's interval from the confidence set (NaN: the set is empty)."""
    unconstrained: tuple[bool, ...]
    consistent: bool
    """Some candidate's certified spectrum is consistent with the measurement."""
    statistic: float
    """The estimate's s = max |F̂ − m| / (μ' + u) (≤ 1: consistent)."""
    loss_name: str
    loss: float
    delta: float
    mu_fraction: float
    forward_mu: float
    """The forward tolerance asked for at the optimum."""
    wavelengths: np.ndarray
    quantities: tuple[str, ...]
    measured: dict[str, np.ndarray]
    uncertainty: dict[str, np.ndarray]
    fitted: dict[str, np.ndarray]
    fitted_tolerance: dict[str, np.ndarray]
    candidate_values: np.ndarray
    candidate_mu: np.ndarray
    candidate_statistic: np.ndarray
    candidate_loss: np.ndarray
    candidate_stage: tuple[str, ...]
    candidate_consistent: np.ndarray
    """Each reading's verdict (that of the finest reading of the same values)."""
    rays: int
    traced_rays: int
    seconds: float
    specimen: str
    seed: int
    reading_delta: float
    version: str = __version__
    search_wavelengths: int = 0
    """Wavelengths of the search and confirmation readings when fewer than all (0: all; their stages say so)."""

    # -- derived -------------------------------------------------------------------------

    @property
    def level(self) -> float:
        """1 − δ: the confidence set's level, less the measurement's own risk."""

        return 1.0 - self.delta

    @property
    def consistent_candidates(self) -> int:
        """Readings whose candidate is consistent (by the finest reading of its values)."""

        return int(np.sum(self.candidate_consistent))

    @property
    def residuals(self) -> dict[str, np.ndarray]:
        """quantity → fitted − measured."""

        return {q: self.fitted[q] - self.measured[q] for q in self.quantities}

    @property
    def forward_tolerance(self) -> float:
        """The largest certified tolerance of the fitted spectrum (its forward error bound)."""

        return float(max(np.max(self.fitted_tolerance[q]) for q in self.quantities))

    @property
    def estimates(self) -> dict[str, float]:
        return dict(zip(self.names, map(float, self.estimate)))

    def profile(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(values, statistic) along ``name`` through the estimate (empty when no profile was read)."""

        if name not in self.names:
            raise ValueError(f"{name!r} is not a free parameter of this fit ({', '.join(self.names)})")
        chosen = np.array([stage == f"profile {name}" for stage in self.candidate_stage], dtype=bool)
        i = self.names.index(name)
        order = np.argsort(self.candidate_values[chosen, i])
        return self.candidate_values[chosen, i][order], self.candidate_statistic[chosen][order]

    def summary(self) -> str:
        """The result in a few lines for people."""

        lines = [f"fit of {self.specimen} to {' and '.join(self.quantities)} at {len(self.wavelengths)} wavelengths "
                 f"({self.wavelengths.min():g}-{self.wavelengths.max():g} nm), loss {self.loss_name} = {self.loss:.4g}"]
        if self.consistent:
            lines.append(f"confidence set (level >= {self.level:g}, less the measurement's own risk): "
                         f"{self.consistent_candidates} of {len(self.candidate_statistic)} readings consistent")
            if self.statistic > 1.0 and self.loss_name.startswith("windows"):
                lines.append(f"the estimate (each parameter from its window) is inconsistent elsewhere in the "
                             f"spectrum (s = {self.statistic:.3g} > 1) while other candidates pass: the model "
                             "matches the windows and the rest of the spectrum at different parameters")
            elif self.statistic > 1.0:
                lines.append(f"NOT CONVERGED: the estimate itself is inconsistent (s = {self.statistic:.3g} > 1) while "
                             "other candidates pass: the intervals may miss the truth; raise evaluations")
        else:
            lines.append(f"INCONSISTENT: no candidate's certified spectrum lies within the measurement uncertainty "
                         f"+ its tolerance (the estimate's largest normalised residual s = {self.statistic:.3g} > 1): "
                         "the model does not reproduce this measurement")
        for i, name in enumerate(self.names):
            low, high = self.intervals[i]
            interval = "-" if math.isnan(low) else f"[{low:.6g}, {high:.6g}]"
            flag = "  UNCONSTRAINED by the data" if self.unconstrained[i] else ""
            lines.append(f"  {name:>14} = {self.estimate[i]:.6g}  interval {interval}  bounds "
                         f"[{self.bounds[i, 0]:g}, {self.bounds[i, 1]:g}]{flag}")
        lines.append(f"forward error at the optimum <= {self.forward_tolerance:.4g} (asked {self.forward_mu:.4g} = "
                     f"{self.forward_tolerance / min(float(self.uncertainty[q].min()) for q in self.quantities):.2f} x "
                     f"the smallest measurement uncertainty), each reading at delta {self.reading_delta:.3g}; "
                     f"s = {self.statistic:.3g}")
        searched = (f" (the search and confirmation on {self.search_wavelengths} of the wavelengths, each judged on "
                    "its own)" if self.search_wavelengths else "")
        lines.append(f"{len(self.candidate_statistic)} forward readings{searched}, {self.rays:,} rays "
                     f"({self.traced_rays:,} traced now), {self.seconds:.1f} s, seed {self.seed}")
        return "\n".join(lines)

    # -- files ---------------------------------------------------------------------------

    def as_dict(self) -> dict[str, Any]:
        """Plain JSON data (the ``.json`` file's content)."""

        data: dict[str, Any] = {"format": FIT_FORMAT, "version": self.version, "names": list(self.names),
                                "quantities": list(self.quantities), "candidate_stage": list(self.candidate_stage),
                                "unconstrained": list(self.unconstrained)}
        for name in ("consistent", "statistic", "loss_name", "loss", "delta", "mu_fraction", "forward_mu", "rays",
                     "traced_rays", "seconds", "specimen", "seed", "reading_delta", "search_wavelengths"):
            data[name] = getattr(self, name)
        for name in _ARRAYS:
            data[name] = _plain(getattr(self, name))
        for name in _SPECTRA:
            data[name] = {q: _plain(v) for q, v in getattr(self, name).items()}
        data["estimates"] = self.estimates
        data["forward_tolerance"] = self.forward_tolerance
        return data

    def write(self, path: str | os.PathLike) -> Path:
        """Write to ``.json`` or ``.nc`` (atomically); ``ValueError`` for another suffix."""

        path = Path(path)
        suffix = path.suffix.lower()
        if suffix not in FIT_SUFFIXES:
            raise ValueError(f"a fit file is {' or '.join(FIT_SUFFIXES)} (got {path.name})")
        with atomic_file(path) as temporary:
            if suffix == ".json":
                temporary.write_text(json.dumps(self.as_dict(), indent=1, allow_nan=True))
            else:
                self.to_xarray().to_netcdf(temporary)
        return path

    def to_xarray(self) -> Any:
        """An ``xarray.Dataset``: spectra over (quantity, wavelength), parameters, candidates."""

        import xarray as xr

        spectra = {name: (("quantity", "wavelength"), np.array([getattr(self, name)[q] for q in self.quantities]))
                   for name in _SPECTRA}
        scalars = {name: getattr(self, name) for name in ("statistic", "loss", "delta", "mu_fraction", "forward_mu",
                                                          "rays", "traced_rays", "seconds", "seed", "reading_delta",
                                                          "search_wavelengths")}
        attrs = {"format": FIT_FORMAT, "version": self.version, "specimen": self.specimen, "loss_name": self.loss_name,
                 "consistent": int(self.consistent), **{k: (float(v) if isinstance(v, float) else int(v))
                                                        for k, v in scalars.items()}}
        return xr.Dataset(
            {**spectra,
             "bounds": (("parameter", "end"), self.bounds), "estimate": (("parameter",), self.estimate),
             "intervals": (("parameter", "end"), self.intervals),
             "unconstrained": (("parameter",), np.array(self.unconstrained, dtype=np.int8)),
             "candidate_values": (("candidate", "parameter"), self.candidate_values),
             "candidate_mu": (("candidate",), self.candidate_mu),
             "candidate_statistic": (("candidate",), self.candidate_statistic),
             "candidate_loss": (("candidate",), self.candidate_loss),
             "candidate_consistent": (("candidate",), self.candidate_consistent.astype(np.int8)),
             "candidate_stage": (("candidate",), np.array(self.candidate_stage, dtype=object))},
            coords={"quantity": list(self.quantities), "wavelength": self.wavelengths, "parameter": list(self.names),
                    "end": ["low", "high"]},
            attrs=attrs)

    # -- figures -------------------------------------------------------------------------

    def plot(self, path: str | os.PathLike | None = None) -> Any:
        """Measured vs fitted (both bands), the residuals and the profiles; saved when ``path`` is given."""

        import matplotlib

        if path is not None:
            matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt

        profiles = [name for name in self.names if len(self.profile(name)[0])]
        figure, axes = plt.subplots(1, 2 + len(profiles), figsize=(4.2 * (2 + len(profiles)), 3.8), squeeze=False)
        spectra, residuals = axes[0, 0], axes[0, 1]
        w = self.wavelengths
        for q in self.quantities:
            m, u = self.measured[q], self.uncertainty[q]
            f, t = self.fitted[q], self.fitted_tolerance[q]
            line, = spectra.plot(w, m, ".", ms=3, label=f"measured {q}")
            spectra.fill_between(w, m - u, m + u, color=line.get_color(), alpha=0.2, lw=0)
            fitted, = spectra.plot(w, f, "-", lw=1, label=f"fitted {q}")
            spectra.fill_between(w, f - t, f + t, color=fitted.get_color(), alpha=0.3, lw=0)
            residuals.plot(w, f - m, "-", lw=1, label=q)
            residuals.fill_between(w, -(u + t), u + t, alpha=0.15, lw=0)
        spectra.set(xlabel="wavelength (nm)", ylabel="fraction", title=self.specimen[:60])
        spectra.legend(fontsize=7)
        residuals.axhline(0, color="k", lw=0.5)
        residuals.set(xlabel="wavelength (nm)", ylabel="fitted - measured", title="residuals, +-(u + mu')")
        for axis, name in zip(axes[0, 2:], profiles):
            values, statistic = self.profile(name)
            axis.plot(values, statistic, "o-", ms=3)
            axis.axhline(1.0, color="r", lw=0.8, ls="--", label="s = 1 (consistent below)")
            low, high = self.intervals[self.names.index(name)]
            if not math.isnan(low):
                axis.axvspan(low, high, color="g", alpha=0.15, label="interval")
            axis.axvline(self.estimate[self.names.index(name)], color="k", lw=0.8)
            axis.set(xlabel=name, ylabel="s = max |F - m| / (mu' + u)", yscale="log", title=f"profile of {name}")
            axis.legend(fontsize=7)
        figure.tight_layout()
        if path is not None:
            figure.savefig(path, dpi=120)
            plt.close(figure)
        return figure


def _plain(values: Any) -> Any:
    array = np.asarray(values, dtype=np.float64)
    return [None if not np.isfinite(v) else float(v) for v in array.ravel()] if array.ndim == 1 else \
        [_plain(row) for row in array]


def read_fit(path: str | os.PathLike) -> FitResult:
    """A :class:`FitResult` from its ``.json`` or ``.nc`` file (``ValueError`` for another file)."""

    path = Path(path)
    if path.suffix.lower() == ".nc":
        import xarray as xr

        with xr.open_dataset(path) as dataset:
            data = dict(dataset.attrs)
            if data.get("format") != FIT_FORMAT:
                raise ValueError(f"{path} is not a fit file (format {data.get('format')!r})")
            quantities = [str(q) for q in dataset["quantity"].values]
            fields = {name: {q: np.asarray(dataset[name].values[i]) for i, q in enumerate(quantities)}
                      for name in _SPECTRA}
            arrays = {name: np.asarray(dataset[name].values, dtype=np.float64) for name in
                      ("bounds", "estimate", "intervals", "candidate_values", "candidate_mu", "candidate_statistic",
                       "candidate_loss")}
            arrays["candidate_consistent"] = np.asarray(dataset["candidate_consistent"].values, dtype=bool)
            return FitResult(
                names=tuple(str(n) for n in dataset["parameter"].values), **arrays,
                wavelengths=np.asarray(dataset["wavelength"].values, dtype=np.float64),
                unconstrained=tuple(bool(v) for v in dataset["unconstrained"].values),
                consistent=bool(data["consistent"]), quantities=tuple(quantities), **fields,
                candidate_stage=tuple(str(s) for s in dataset["candidate_stage"].values),
                search_wavelengths=int(data.get("search_wavelengths", 0)),
                **{k: data[k] for k in ("statistic", "loss_name", "loss", "delta", "mu_fraction", "forward_mu", "rays",
                                        "traced_rays", "seconds", "specimen", "seed", "reading_delta", "version")})
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as error:
        raise ValueError(f"cannot read the fit file {path}: {error}") from None
    if not isinstance(data, dict) or data.get("format") != FIT_FORMAT:
        raise ValueError(f"{path} is not a fit file (format {FIT_FORMAT!r})")

    def array(name: str) -> np.ndarray:
        return np.array(data[name], dtype=np.float64)

    return FitResult(
        names=tuple(data["names"]), bounds=array("bounds"), estimate=array("estimate"), intervals=array("intervals"),
        unconstrained=tuple(data["unconstrained"]), consistent=bool(data["consistent"]),
        quantities=tuple(data["quantities"]), wavelengths=array("wavelengths"),
        **{name: {q: np.array(v, dtype=np.float64) for q, v in data[name].items()} for name in _SPECTRA},
        candidate_values=array("candidate_values"), candidate_mu=array("candidate_mu"),
        candidate_statistic=array("candidate_statistic"), candidate_loss=array("candidate_loss"),
        candidate_consistent=array("candidate_consistent").astype(bool), candidate_stage=tuple(data["candidate_stage"]),
        search_wavelengths=int(data.get("search_wavelengths", 0)),
        **{k: data[k] for k in ("statistic", "loss_name", "loss", "delta", "mu_fraction", "forward_mu", "rays",
                                "traced_rays", "seconds", "specimen", "seed", "reading_delta", "version")})
