"""
Goniophotometer readings: :class:`GonioResult`
=============================================

A goniophotometer reading (:func:`virtspec_mi.gonio`) is a spectrophotometer reading
— a :class:`~virtspec_mi.results.hemispherical.Result` over (wavelength, θi) with its exact counts and
R/T certificate — whose escaping rays were also tallied by outgoing direction
(:mod:`virtspec_mi.geometry.bins`). :class:`GonioResult` shares that result's machinery
(it holds it, and its file formats) and adds the dims ``theta_o`` and ``phi_o``:

- ``bin_counts`` m_k (exact ``int64``; Σ_k m_k + ``outside`` = reflected + transmitted);
- ``fraction`` m_k/N and ``brdf`` f_k = (m_k/N)/Ω_k (sr⁻¹; BTDF for θo > 90°), with
  Ω_k = ∫_bin |cos θo| dωo (:meth:`GonioBins.projected_solid_angles`);
- the simultaneous Clopper–Pearson band of f_k (``brdf_lower``, ``brdf_upper``) at δ/K;
- the empirical CDFs of θo and φo at the bin edges (``cdf_theta_o``, ``cdf_phi_o``);
- the certificates of :mod:`virtspec_mi.budgets.bins`: ``bins_mu`` (every bin fraction
  at once), ``cdf_mu`` (DKW), ``relative_tolerance`` above ``brdf_floor`` when asked —
  NaN ("not certified") where the reading's R/T are not certified or the bound is vacuous.

:meth:`GonioResult.to_dataset` gives the ``xarray.Dataset`` of the data contract
(dims ``wavelength``, ``theta_i``, ``theta_o``, ``phi_o``; variables ``bin_counts``,
``rays``, ``brdf``; bin edges as coordinates ``theta_o_lower`` … ; attributes
``phi_folded``, ``phi_i``, ``mu``, ``delta``, ``guarantee``) that the ``tabulated`` BSDF
loads; :meth:`write` / :meth:`read` store it as NetCDF, CSV or JSON.

References
----------
Nicodemus et al. (1977), NBS Monograph 160; Baranoski et al. (2001), Sect. 6.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.budgets import bins as gonio_bounds
from virtspec_mi.budgets.rules import guarantee_of
from virtspec_mi.geometry.bins import GonioBins
from virtspec_mi.results.hemispherical import Result, _round_up, plain_data

__all__ = ["GonioResult"]

_FORMAT = "virtspec-mi gonio 1"


@dataclass(frozen=True, eq=False)
class GonioResult:
    """
    A goniophotometer reading over (wavelength, θi, θo, φo) (see the module docstring).

    Attributes
    ----------
    result : Result
        The spectrophotometer reading of the same rays, dims ``("wavelength", "theta_i")``.
    bin_counts : ndarray
        Exact per-bin counts, ``int64``, shape (wavelengths, θi, θo bins, φo bins).
    bins : GonioBins
        The bins (edges in degrees, folding).
    guarantee : str
        How N was sized (:data:`~virtspec_mi.budgets.rules.GUARANTEES`), or ``"rays"`` when given.
    relative_tolerance, brdf_floor : float or None
        The relative certificate asked for (``guarantee="relative"``), else ``None``.
    """

    result: Result
    bin_counts: np.ndarray
    bins: GonioBins
    guarantee: str = "union"
    relative_tolerance: float | None = None
    brdf_floor: float | None = None

    # -- labels and counts -------------------------------------------------------------

    @property
    def wavelengths(self) -> np.ndarray:
        return self.result.wavelengths

    @property
    def theta_i(self) -> np.ndarray:
        return np.atleast_1d(self.result.coords["theta_i"])

    @property
    def phi_i(self) -> float:
        return self.result.phi_i

    @property
    def theta_o(self) -> np.ndarray:
        """θo bin centres (degrees)."""

        return self.bins.theta_centres

    @property
    def phi_o(self) -> np.ndarray:
        """φo bin centres (degrees; folded: relative azimuth)."""

        return self.bins.phi_centres

    @property
    def rays(self) -> np.ndarray:
        """Rays N per reading (wavelength, θi)."""

        return self.result.rays

    @property
    def delta(self) -> float:
        return self.result.delta

    @property
    def size(self) -> int:
        """K, the number of bins."""

        return self.bins.size

    @property
    def outside(self) -> np.ndarray:
        """Escaping rays in no bin (outside the bins' range): reflected + transmitted − Σ bins."""

        return self.result.reflected + self.result.transmitted - self.bin_counts.sum(axis=(-2, -1))

    @property
    def solid_angles(self) -> np.ndarray:
        """Ω_k (sr) per bin, shape (θo bins, φo bins)."""

        return self.bins.projected_solid_angles()

    @property
    def fraction(self) -> np.ndarray:
        """m_k/N per bin: the share of the incident rays that left into bin k."""

        return self.bin_counts / self.rays[..., None, None]

    @property
    def brdf(self) -> np.ndarray:
        """f_k = (m_k/N)/Ω_k (sr⁻¹): BRDF for θo < 90°, BTDF beyond, averaged over the bin."""

        return self.fraction / self.solid_angles

    @cached_property
    def _band(self) -> tuple[np.ndarray, np.ndarray]:
        lower, upper = gonio_bounds.brdf_intervals(self.bin_counts, self.rays[..., None, None], self.solid_angles,
                                                   self.delta, self.size)
        return lower, upper

    @property
    def brdf_lower(self) -> np.ndarray:
        """Lower ends of the simultaneous Clopper–Pearson intervals of f_k (all K bins at 1 − δ)."""

        return self._band[0]

    @property
    def brdf_upper(self) -> np.ndarray:
        """Upper ends of the simultaneous Clopper–Pearson intervals of f_k."""

        return self._band[1]

    @property
    def cdf_theta_o(self) -> np.ndarray:
        """
        F̂(θ) = #(escaped with θo < θ)/N at the θo edges, shape (…, θo bins + 1): the
        empirical CDF of X = θo for a ray that escaped into a bin, +∞ otherwise (absorbed,
        or outside the bins), certified by DKW (:attr:`cdf_mu`).
        """

        per_theta = self.bin_counts.sum(axis=-1)
        zero = np.zeros(per_theta.shape[:-1] + (1,), dtype=np.int64)
        return np.concatenate([zero, np.cumsum(per_theta, axis=-1)], axis=-1) / self.rays[..., None]

    @property
    def cdf_phi_o(self) -> np.ndarray:
        """F̂(φ) = #(escaped with φo < φ)/N at the φo edges, shape (…, φo bins + 1) (as :attr:`cdf_theta_o`)."""

        per_phi = self.bin_counts.sum(axis=-2)
        zero = np.zeros(per_phi.shape[:-1] + (1,), dtype=np.int64)
        return np.concatenate([zero, np.cumsum(per_phi, axis=-1)], axis=-1) / self.rays[..., None]

    # -- certificates ------------------------------------------------------------------

    def _certified(self, values: np.ndarray) -> np.ndarray:
        values = values + self.result.rounding_bias
        return np.where(self.result.certified & (values < 1.0), values, np.nan)

    @property
    def bins_mu(self) -> np.ndarray:
        """μ with |m_k/N − p_k| < μ for every bin at once at δ (per reading; NaN: not certified)."""

        return self._certified(guarantee_of(self.guarantee).certified(self.rays, self.delta, self.result.mu,
                                                                      self.size))

    @property
    def cdf_mu(self) -> np.ndarray:
        """DKW–Massart μ: sup |F̂ − F| < μ for the CDF of θo (and of φo) at δ (NaN: not certified)."""

        return self._certified(gonio_bounds.dkw_mu(self.rays, self.delta))

    @property
    def relative_mu(self) -> np.ndarray | None:
        """The relative tolerance on f_k certified for bins with f_k ≥ ``brdf_floor`` (NaN: none); ``None`` if no floor."""

        if self.brdf_floor is None:
            return None
        eps = gonio_bounds.relative_tolerance(self.rays, self.brdf_floor, self.delta, self.size,
                                              float(self.solid_angles.min()))
        return np.where(self.result.certified, eps, np.nan)

    @property
    def sized_by(self) -> str | None:
        """
        The guarantee N was sized for, in words (``None`` when ``rays`` was given): the
        rule, its μ (or relative ε above the floor), δ and K. Whether these rays deliver
        it is :meth:`certificate`'s to say.
        """

        s, rule = self.result.settings, guarantee_of(self.guarantee)
        target = rule.target(s.mu, self.size, self.relative_tolerance, self.brdf_floor)
        return None if target is None else f"{rule.sized} for {target}, delta = {s.delta:g}"

    def certificate(self) -> str:
        """What the reading's rays guarantee, in words (worst reading), or "not certified"."""

        k, delta = self.size, self.delta
        counted = f"N = {int(self.rays.min()):,}" + (f" to {int(self.rays.max()):,}" if self.rays.min() != self.rays.max()
                                                      else "") + f" rays per reading, K = {k} bins"
        rule = guarantee_of(self.guarantee).sized
        bins_mu, cdf_mu = self.bins_mu, self.cdf_mu
        if np.all(np.isnan(cdf_mu)):
            return f"{counted} ({rule}): NOT CERTIFIED (see the reading's warnings, or too few rays)"
        lines = [f"{counted} ({rule}), each statement with probability >= {1 - delta:g} per reading:"]
        lines.append(f"  CDFs of theta_o and phi_o: sup |F - F_N| < {_round_up(float(np.nanmax(cdf_mu))):g} "
                     "(DKW-Massart)")
        if np.all(np.isnan(bins_mu)):
            lines.append("  bin fractions: not certified (too few rays for K bins)")
        else:
            lines.append(f"  every bin fraction at once: |m_k/N - p_k| < {_round_up(float(np.nanmax(bins_mu))):g} "
                         f"({guarantee_of(self.guarantee).union_words})")
        lines.append(f"  f_k: simultaneous Clopper-Pearson intervals, each at delta/K = {delta / k:.3g}")
        relative = self.relative_mu
        if relative is not None:
            lines.append(f"  f_k >= {self.brdf_floor:g}/sr: relative error < "
                         + ("not certified (too few rays)" if np.all(np.isnan(relative))
                            else f"{_round_up(float(np.nanmax(relative))):g}") + " (Chernoff + union)")
        if np.any(np.isnan(cdf_mu)):
            lines.append("  some readings NOT CERTIFIED")
        return "\n".join(lines)

    def summary(self) -> str:
        """The spectrophotometer summary, the bins and the certificate."""

        b = self.bins
        folded = ", phi_o folded to |phi_o - phi_i|" if b.fold_phi else ""
        lines = [self.result.summary(sized_by=self.sized_by), "",
                 f"Goniophotometer: {b.shape[0]} theta_o x {b.shape[1]} phi_o bins ({b.binning}{folded}), "
                 f"theta_o {b.theta_edges[0]:g}..{b.theta_edges[-1]:g}, phi_o {b.phi_edges[0]:g}..{b.phi_edges[-1]:g} "
                 "degrees",
                 self.certificate()]
        if np.any(self.outside):
            lines.append(f"  {int(self.outside.sum()):,} escaping rays fell outside the bins")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (f"GonioResult({len(self.wavelengths)} wavelengths x {len(self.theta_i)} theta_i x "
                f"{self.bins.shape[0]} theta_o x {self.bins.shape[1]} phi_o, N = {int(self.rays.max()):,})")

    # -- plain data, datasets and files ------------------------------------------------

    def as_dict(self) -> dict[str, Any]:
        """Plain data (JSON-ready): the reading's result, the bins, counts and the certificate."""

        return {
            "format": _FORMAT,
            "result": self.result.as_dict(),
            "bins": self.bins.as_dict(),
            "bin_counts": self.bin_counts.tolist(),
            "guarantee": self.guarantee,
            "relative_tolerance": self.relative_tolerance,
            "brdf_floor": self.brdf_floor,
            "brdf": plain_data(self.brdf),
            "bins_mu": plain_data(self.bins_mu),
            "cdf_mu": plain_data(self.cdf_mu),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "GonioResult":
        """The reading of :meth:`as_dict` (``ValueError`` if ``data`` is not one)."""

        try:
            if data.get("format") != _FORMAT:
                raise KeyError("format")
            return cls(result=Result.from_dict(data["result"]).as_grid(),
                       bin_counts=np.asarray(data["bin_counts"], dtype=np.int64),
                       bins=GonioBins.from_dict(data["bins"]), guarantee=str(data["guarantee"]),
                       relative_tolerance=data.get("relative_tolerance"), brdf_floor=data.get("brdf_floor"))
        except (KeyError, TypeError, AttributeError) as error:
            raise ValueError(f"not a virtspec-mi goniophotometer result (missing or bad {error})") from None

    def to_dataset(self) -> Any:
        """
        The ``xarray.Dataset`` of the data contract (see the module docstring), plus the
        spectrophotometer variables (reflectance …, over wavelength × θi), ``fraction``,
        ``brdf_lower`` / ``brdf_upper``, ``solid_angle``, ``cdf_theta_o`` / ``cdf_phi_o``
        (over the edges ``theta_o_edge`` / ``phi_o_edge``), ``outside``, ``bins_mu`` and
        ``cdf_mu``; ``gonio_json`` rebuilds the reading (:meth:`from_dataset`).
        """

        base = self.result.to_dataset()
        base.attrs.pop("result_json", None)
        b = self.bins
        grid = ("wavelength", "theta_i", "theta_o", "phi_o")
        reading = ("wavelength", "theta_i")
        dataset = base.assign({
            "bin_counts": (grid, self.bin_counts.astype(np.int64), {"meaning": "exact count of rays into the bin"}),
            "fraction": (grid, self.fraction, {"meaning": "bin_counts / rays"}),
            "brdf": (grid, self.brdf, {"units": "1/sr", "meaning": "(bin_counts/rays) / solid_angle (BTDF beyond "
                                                                  "theta_o = 90)"}),
            "brdf_lower": (grid, self.brdf_lower, {"units": "1/sr", "clopper_pearson_delta": self.delta / self.size}),
            "brdf_upper": (grid, self.brdf_upper, {"units": "1/sr", "clopper_pearson_delta": self.delta / self.size}),
            "solid_angle": (("theta_o", "phi_o"), self.solid_angles,
                            {"units": "sr", "meaning": "projected solid angle of the bin, integral of |cos theta_o|"
                                                      + (" (both folded halves)" if b.fold_phi else "")}),
            "cdf_theta_o": (("wavelength", "theta_i", "theta_o_edge"), self.cdf_theta_o),
            "cdf_phi_o": (("wavelength", "theta_i", "phi_o_edge"), self.cdf_phi_o),
            "outside": (reading, self.outside.astype(np.int64)),
            "bins_mu": (reading, self.bins_mu, {"meaning": "every bin fraction within bins_mu at delta; NaN: not "
                                                           "certified"}),
            "cdf_mu": (reading, self.cdf_mu, {"meaning": "DKW-Massart sup error of cdf_theta_o and cdf_phi_o at "
                                                         "delta; NaN: not certified"}),
        })
        dataset = dataset.assign_coords({
            "theta_o": ("theta_o", b.theta_centres, {"units": "degree"}),
            "theta_o_lower": ("theta_o", b.theta_edges[:-1], {"units": "degree"}),
            "theta_o_upper": ("theta_o", b.theta_edges[1:], {"units": "degree"}),
            "phi_o": ("phi_o", b.phi_centres, {"units": "degree"}),
            "phi_o_lower": ("phi_o", b.phi_edges[:-1], {"units": "degree"}),
            "phi_o_upper": ("phi_o", b.phi_edges[1:], {"units": "degree"}),
            "theta_o_edge": ("theta_o_edge", b.theta_edges, {"units": "degree"}),
            "phi_o_edge": ("phi_o_edge", b.phi_edges, {"units": "degree"}),
        })
        if "theta_i" not in dataset.dims:
            dataset = dataset.expand_dims("theta_i")
        dataset.attrs.update({
            "phi_folded": int(b.fold_phi), "phi_i": self.phi_i, "binning": b.binning, "guarantee": self.guarantee,
            "bins": self.size, "bins_delta": self.delta,
            "gonio_json": json.dumps(self.as_dict()),
        })
        return dataset

    @classmethod
    def from_dataset(cls, dataset: Any) -> "GonioResult":
        """The reading of a dataset made by :meth:`to_dataset`."""

        if "gonio_json" not in dataset.attrs:
            raise ValueError("not a virtspec-mi goniophotometer result (no gonio_json attribute)")
        return cls.from_dict(json.loads(dataset.attrs["gonio_json"]))

    def write(self, path: str | os.PathLike) -> Path:
        """Write to ``.nc`` (NetCDF-4), ``.csv`` or ``.json`` by suffix (:mod:`virtspec_mi.results.io`)."""

        from virtspec_mi.results import io as results_io

        if Path(path).suffix.lower() == ".csv":  # one row per bin: the edge-indexed CDFs stay in gonio_json
            return results_io.write(_CsvView(self), path)
        return results_io.write(self, path)

    @classmethod
    def read(cls, path: str | os.PathLike) -> "GonioResult":
        """Read a goniophotometer reading written by :meth:`write`."""

        from virtspec_mi.results import io as results_io

        kind, content = results_io.read(path)
        return cls.from_dataset(content) if kind == "dataset" else cls.from_dict(content)

    # -- colour and plots --------------------------------------------------------------

    def to_sd(self, theta_o: float, phi_o: float, theta_i: float | None = None) -> Any:
        """
        f over wavelength in the bin holding (θo, φo) at one θi (default: the first) as a
        ``colour.SpectralDistribution`` (1/sr; needs several wavelengths).
        """

        import colour

        i = 0 if theta_i is None else int(np.argmin(np.abs(self.theta_i - theta_i)))
        t = int(np.clip(np.searchsorted(self.bins.theta_edges, theta_o, side="right") - 1, 0, self.bins.shape[0] - 1))
        p = int(np.clip(np.searchsorted(self.bins.phi_edges, phi_o, side="right") - 1, 0, self.bins.shape[1] - 1))
        if len(self.wavelengths) < 2:
            raise ValueError("to_sd needs a reading over several wavelengths (got 1)")
        order = np.argsort(self.wavelengths)
        name = f"f at theta_o {self.theta_o[t]:g}, phi_o {self.phi_o[p]:g} deg (theta_i {self.theta_i[i]:g})"
        return colour.SpectralDistribution(dict(zip(self.wavelengths[order], self.brdf[order, i, t, p])), name=name)

    def plot(self, path: str | os.PathLike | None = None, **options: Any) -> Any:
        """Polar plot of f in the plane of incidence and across it, with the certified band (:mod:`virtspec_mi.results.angular_plot`)."""

        from virtspec_mi.results.angular_plot import plot_polar

        return plot_polar(self, path, **options)

    def plot_series(self, path: str | os.PathLike | None = None, **options: Any) -> Any:
        """The angular distribution over θi as a series, with the certified bands (:func:`~virtspec_mi.results.angular_plot.plot_series`)."""

        from virtspec_mi.results.angular_plot import plot_series

        return plot_series(self, path, **options)


@dataclass(frozen=True)
class _CsvView:
    """A reading as its CSV table: the dataset without the CDF variables over bin edges."""

    reading: GonioResult

    def to_dataset(self) -> Any:
        dataset = self.reading.to_dataset()
        return dataset.drop_vars(["cdf_theta_o", "cdf_phi_o", "theta_o_edge", "phi_o_edge"])
