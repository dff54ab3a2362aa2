"""
A fit's result: estimate, confidence set, residuals, the forward certificate, the rays
======================================================================================

:class:`FitResult` holds what :func:`virtspec_mi.applications.fitting.fit` found and how:
the estimate, each parameter's interval from the confidence set (and which parameters the
data leave unconstrained), whether the fit is consistent at all, the measured and fitted
spectra with both uncertainty bands and the residuals, every candidate read (values,
tolerance, test statistic, loss, stage: the table, the refinement, the profiles) and the
rays spent. It is a result kind of the one family (:class:`~virtspec_mi.results.records.Record`,
format ``"virtspec-mi fit 1"``): written to JSON (``.json``) or NetCDF (``.nc``) by the
one writer (:mod:`virtspec_mi.results.io`, atomically), read back by
:func:`virtspec_mi.read_result` (:func:`read_fit`: the same, refusing another kind; a fit's
``.nc`` of an earlier release, without ``result_json``, reads too), and plotted by :meth:`FitResult.plot` (measured against fitted with both bands, the
residuals, and each parameter's profile of the test statistic).

References
----------
Baranoski et al. (2001), eq. (23) (the certified tolerance of each fitted value).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any, ClassVar, Mapping

import numpy as np

from virtspec_mi.base.version import __version__
from virtspec_mi.results.integrity import CountRules, optional_numbers, whole_counts
from virtspec_mi.results.figures import Figure
from virtspec_mi.results.records import Record
from virtspec_mi.results.variables import Variable

__all__ = ["FitResult", "read_fit", "FIT_FORMAT", "FIT_SUFFIXES", "UNCONSTRAINED_SHARE", "intervals"]

FIT_FORMAT: str = "virtspec-mi fit 1"
"""The format tag of a fit's files."""
FIT_SUFFIXES: tuple[str, ...] = (".json", ".nc")

UNCONSTRAINED_SHARE: float = 0.9
"""A parameter whose interval covers at least this share of its bounds is flagged unconstrained."""

_ARRAYS = ("bounds", "estimate", "intervals", "wavelengths", "candidate_values", "candidate_mu",
           "candidate_statistic", "candidate_loss", "candidate_consistent")
_SPECTRA = ("measured", "uncertainty", "fitted", "fitted_tolerance")


_RAYS = CountRules(None, parts={"traced_rays": "rays"})
"""The rays traced now are some of the rays the readings hold (the others were read from the store)."""


@dataclass(frozen=True, eq=False)
class FitResult(Record):
    """
    What a fit found (see the module docstring); arrays in the order of :attr:`names`. A
    result kind (format ``"virtspec-mi fit 1"``): its Dataset has the spectra over
    (quantity, wavelength), the parameters' bounds, estimate and intervals, every
    candidate read, the scalars as attributes.
    """

    FORMAT: ClassVar[str] = FIT_FORMAT
    KIND: ClassVar[str] = "fit"
    VARIABLES: ClassVar[dict[str, tuple[str, str]]] = {
        "quantity": ("1", "measured quantity"), "parameter": ("1", "free parameter"), "end": ("1", "interval end"),
        "candidate": ("1", "forward reading"),
        "measured": ("1", "measured value"), "uncertainty": ("1", "measurement uncertainty"),
        "fitted": ("1", "fitted value (the forward reading at the estimate)"),
        "fitted_tolerance": ("1", "certified tolerance of the fitted value"),
        "bounds": ("as in the specimen plugin", "search bounds of the parameter"),
        "estimate": ("as in the specimen plugin", "estimated parameter value"),
        "intervals": ("as in the specimen plugin", "interval of the parameter from the confidence set (NaN: empty)"),
        "unconstrained": ("1", "the data leave the parameter unconstrained (1) or not (0)"),
        "candidate_values": ("as in the specimen plugin", "parameter values of the forward reading"),
        "candidate_mu": ("1", "tolerance the forward reading was certified to"),
        "candidate_statistic": ("1", "test statistic s = max |F - m| / (mu' + u)"),
        "candidate_loss": ("1", "loss of the forward reading"),
        "candidate_consistent": ("1", "the candidate is consistent with the measurement (1) or not (0)"),
        "candidate_stage": ("1", "stage of the fit that read the candidate"),
        "residuals": ("1", "fitted - measured"),
    }
    DERIVED: ClassVar[dict[str, Variable]] = {
        "residuals": Variable("1", "fitted - measured", lambda r: np.array([r.residuals[q] for q in r.quantities]),
                              ("quantity", "wavelength")),
    }
    FIGURES: ClassVar[dict[str, Figure]] = {
        "fit": Figure(lambda result, path, quantity, **options: result.plot(path),
                      "measured against fitted with both bands, the residuals and each parameter's profile"),
    }

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
    delta: float = field()
    mu_fraction: float
    forward_mu: float
    """The forward tolerance asked for at the optimum."""
    wavelengths: np.ndarray = field()
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
    seconds: float = field()
    specimen: str
    seed: int
    reading_delta: float
    version: str = __version__
    search_wavelengths: int = 0
    """Wavelengths of the search and confirmation readings when fewer than all (0: all; their stages say so)."""
    converged: bool = True
    """The refinement settled (its last stage had room to move and stayed within its step): only then does an
    empty confidence set show that the model cannot reproduce the measurement."""

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
        elif not self.converged:
            lines.append(f"NOT CONVERGED: no candidate read so far is consistent (the best found has s = "
                         f"{self.statistic:.3g} > 1), but the search stopped before it settled, so this says nothing "
                         "about the model; give it more budget: evaluations= (virtspec fit --evaluations A B C, "
                         "readings per refinement stage) or table_points= (--table-points)")
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

    # -- the result family: its Dataset, its files ------------------------------------------

    def as_dict(self) -> dict[str, Any]:
        """Plain JSON data (the ``.json`` file's content; a ``.nc`` file's ``result_json``)."""

        data: dict[str, Any] = {"format": FIT_FORMAT, "version": self.version, "names": list(self.names),
                                "quantities": list(self.quantities), "candidate_stage": list(self.candidate_stage),
                                "unconstrained": list(self.unconstrained)}
        for name in ("consistent", "statistic", "loss_name", "loss", "delta", "mu_fraction", "forward_mu", "rays",
                     "traced_rays", "seconds", "specimen", "seed", "reading_delta", "search_wavelengths"):
            data[name] = getattr(self, name)
        if not self.converged:  # stated only when false: a file of a settled fit is what it was before the field
            data["converged"] = False
        for name in _ARRAYS:
            data[name] = _plain(getattr(self, name))
        for name in _SPECTRA:
            data[name] = {q: _plain(v) for q, v in getattr(self, name).items()}
        data["estimates"] = self.estimates
        data["forward_tolerance"] = self.forward_tolerance
        return data

    def _stored(self) -> Any:
        """Spectra over (quantity, wavelength), parameters, candidates; the scalars as attributes."""

        import xarray as xr

        spectra = {name: (("quantity", "wavelength"), np.array([getattr(self, name)[q] for q in self.quantities]))
                   for name in _SPECTRA}
        scalars = {name: getattr(self, name) for name in ("statistic", "loss", "delta", "mu_fraction", "forward_mu",
                                                          "rays", "traced_rays", "seconds", "seed", "reading_delta",
                                                          "search_wavelengths")}
        attrs = {"version": self.version, "specimen": self.specimen, "loss_name": self.loss_name,
                 "consistent": int(self.consistent), **({} if self.converged else {"converged": 0}), **{k: (float(v) if isinstance(v, float) else int(v))
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

    def _file_attrs(self) -> dict[str, Any]:
        return dict(self.data.attrs)

    def _check(self) -> None:
        super()._check()
        check_candidates(self)

    def _count_groups(self) -> list[tuple[str, Any, CountRules, tuple[str, ...]]]:
        counts = {"rays": whole_counts(self.rays, "rays"), "traced_rays": whole_counts(self.traced_rays, "traced_rays")}
        return [("", counts, _RAYS, ())]

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> "FitResult":
        def array(name: str) -> np.ndarray:
            return np.array(optional_numbers(data[name], name), dtype=np.float64)

        return cls(
            names=tuple(data["names"]), bounds=array("bounds"), estimate=array("estimate"),
            intervals=array("intervals"), unconstrained=tuple(data["unconstrained"]),
            consistent=bool(data["consistent"]), quantities=tuple(data["quantities"]), wavelengths=array("wavelengths"),
            **{name: {q: np.array(optional_numbers(v, name), dtype=np.float64) for q, v in data[name].items()}
               for name in _SPECTRA},
            candidate_values=array("candidate_values"), candidate_mu=array("candidate_mu"),
            candidate_statistic=array("candidate_statistic"), candidate_loss=array("candidate_loss"),
            candidate_consistent=array("candidate_consistent").astype(bool),
            candidate_stage=tuple(data["candidate_stage"]), search_wavelengths=int(data.get("search_wavelengths", 0)),
            converged=bool(data.get("converged", True)),
            **{k: data[k] for k in ("statistic", "loss_name", "loss", "delta", "mu_fraction", "forward_mu", "rays",
                                    "traced_rays", "seconds", "specimen", "seed", "reading_delta", "version")})

    @classmethod
    def _from_legacy(cls, dataset: Any) -> "FitResult":
        """A fit's NetCDF file written before the result family (its fields as variables and attributes)."""

        data = dict(dataset.attrs)
        quantities = [str(q) for q in dataset["quantity"].values]
        fields = {name: {q: np.asarray(dataset[name].values[i]) for i, q in enumerate(quantities)}
                  for name in _SPECTRA}
        arrays = {name: np.asarray(dataset[name].values, dtype=np.float64) for name in
                  ("bounds", "estimate", "intervals", "candidate_values", "candidate_mu", "candidate_statistic",
                   "candidate_loss")}
        arrays["candidate_consistent"] = np.asarray(dataset["candidate_consistent"].values, dtype=bool)
        try:
            return cls(
                names=tuple(str(n) for n in dataset["parameter"].values), **arrays,
                wavelengths=np.asarray(dataset["wavelength"].values, dtype=np.float64),
                unconstrained=tuple(bool(v) for v in dataset["unconstrained"].values),
                consistent=bool(data["consistent"]), quantities=tuple(quantities), **fields,
                candidate_stage=tuple(str(s) for s in dataset["candidate_stage"].values),
                search_wavelengths=int(data.get("search_wavelengths", 0)),
                converged=bool(_attribute(data.get("converged", 1))),
                **{k: _attribute(data[k]) for k in ("statistic", "loss_name", "loss", "delta", "mu_fraction",
                                                    "forward_mu", "rays", "traced_rays", "seconds", "specimen",
                                                    "seed", "reading_delta", "version")})
        except KeyError as error:
            raise ValueError(f"lacks the field {error} of a fit") from None

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


def intervals(values: np.ndarray, consistent: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """
    (n, 2): each parameter's interval from the consistent candidates' values, each end
    carried out to the next value of that parameter tested (the bound when none); NaN when
    no candidate is consistent.
    """

    found = np.full((values.shape[1], 2), np.nan)
    if not consistent.any():
        return found
    for i in range(values.shape[1]):
        tested = np.unique(values[:, i])
        inside = values[consistent, i]
        low, high = inside.min(), inside.max()
        below, above = tested[tested < low], tested[tested > high]
        found[i] = (below.max() if below.size else bounds[i, 0], above.min() if above.size else bounds[i, 1])
    return found


def _plain(values: Any) -> Any:
    array = np.asarray(values, dtype=np.float64)
    return [None if not np.isfinite(v) else float(v) for v in array.ravel()] if array.ndim == 1 else \
        [_plain(row) for row in array]


def _attribute(value: Any) -> Any:
    """A NetCDF attribute as Python's (numpy's scalars as ``int``, ``float``, ``str``)."""

    return value.item() if hasattr(value, "item") else value


def read_fit(path: str | os.PathLike) -> FitResult:
    """
    A :class:`FitResult` from its ``.json`` or ``.nc`` file: :func:`virtspec_mi.read_result`
    that refuses a file of another kind (``ValueError`` naming the kind it holds).
    """

    return FitResult.read(path)


def check_candidates(fit: "FitResult") -> None:
    """
    A fit read from a file, checked against itself (a record's own rule, run as it is read):
    what it claims (the verdicts, the intervals, ``consistent``, the unconstrained flags) must
    be what its candidates give —
    each candidate's verdict that of the finest reading of its values (s <= 1), the intervals
    :func:`~virtspec_mi.applications.fitting.inversion.intervals` of them. A file edited
    against its readings (an interval tightened by hand, ``consistent`` flipped) is refused,
    naming what disagrees.
    """

    def refuse(what: str) -> None:
        raise ValueError(f"{what} disagrees with the fit's own candidates (the file was edited or is damaged); "
                         "re-run the fit rather than edit its file")

    n, count = len(fit.names), len(fit.candidate_statistic)
    shapes = {"bounds": (n, 2), "estimate": (n,), "intervals": (n, 2), "candidate_values": (count, n),
              "candidate_mu": (count,), "candidate_loss": (count,), "candidate_consistent": (count,)}
    for name, shape in shapes.items():
        if np.shape(getattr(fit, name)) != shape:
            refuse(f"{name} (shape {np.shape(getattr(fit, name))}, expected {shape})")
    if len(fit.candidate_stage) != count or len(fit.unconstrained) != n:
        refuse("the number of candidate stages or of unconstrained flags")
    finest: dict[tuple, tuple[float, set]] = {}  # the verdicts of each candidate's finest readings
    for values, mu, s in zip(fit.candidate_values.tolist(), fit.candidate_mu, fit.candidate_statistic):
        key, verdict = tuple(values), bool(s <= 1.0)
        if key not in finest or mu < finest[key][0]:
            finest[key] = (float(mu), {verdict})
        elif mu == finest[key][0]:  # one tolerance, a search reading beside a full one: either may be the one judged
            finest[key][1].add(verdict)
    given: dict[tuple, bool] = {}
    for values, stored in zip(fit.candidate_values.tolist(), fit.candidate_consistent):
        key = tuple(values)
        if bool(stored) not in finest[key][1] or given.setdefault(key, bool(stored)) != bool(stored):
            refuse(f"candidate {values}'s verdict {'consistent' if stored else 'inconsistent'} (its finest reading "
                   f"has s {'>' if stored else '<='} 1)")
    if bool(fit.consistent) != bool(np.any(fit.candidate_consistent)):
        refuse(f"consistent = {bool(fit.consistent)}")
    expected = intervals(fit.candidate_values, np.asarray(fit.candidate_consistent, dtype=bool), fit.bounds)
    if not np.allclose(fit.intervals, expected, rtol=1e-12, atol=0.0, equal_nan=True):
        refuse(f"intervals {fit.intervals.tolist()} (the candidates give {expected.tolist()})")
    span = fit.bounds[:, 1] - fit.bounds[:, 0]
    flags = tuple(bool(np.isfinite(w) and w >= UNCONSTRAINED_SHARE * s) for w, s in zip(expected[:, 1] - expected[:, 0],
                                                                                         span))
    if tuple(map(bool, fit.unconstrained)) != flags:
        refuse(f"unconstrained = {list(fit.unconstrained)}")
