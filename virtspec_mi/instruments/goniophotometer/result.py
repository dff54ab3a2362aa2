"""
Goniophotometer readings: :class:`GonioResult`
==============================================

A goniophotometer reading (:func:`virtspec_mi.gonio`) is a spectrophotometer reading
— a :class:`~virtspec_mi.results.readings.Result` over (wavelength, θi) with its exact counts and
R/T certificate — whose escaping rays were also tallied by outgoing direction
(:mod:`virtspec_mi.instruments.goniophotometer.bins`). :class:`GonioResult` shares that result's machinery
(it holds it, and its file formats) and adds the dims ``theta_o`` and ``phi_o``:

- ``bin_counts`` m_k (exact ``int64``; Σ_k m_k + ``outside`` = reflected + transmitted);
- ``fraction`` m_k/N and ``brdf`` f_k = (m_k/N)/Ω_k (sr⁻¹; BTDF for θo > 90°), with
  Ω_k = ∫_bin |cos θo| dωo (:meth:`GonioBins.projected_solid_angles`);
- the simultaneous Clopper–Pearson band of f_k (``brdf_lower``, ``brdf_upper``) at δ/K;
- the empirical CDFs of θo and φo at the bin edges (``cdf_theta_o``, ``cdf_phi_o``);
- the certificates of :mod:`virtspec_mi.budgets.bins`: ``bins_mu`` (every bin fraction
  at once), ``cdf_mu`` (DKW), ``relative_tolerance`` above ``brdf_floor`` when asked —
  NaN ("not certified") where the reading's R/T are not certified or the bound is vacuous.

It is a result like the others (:class:`~virtspec_mi.results.base.ResultBase`): its dims
are its spectrophotometer reading's (``wavelength``, ``theta_i``, parameter dims) then
``theta_o`` and ``phi_o``; ``sel`` / ``isel`` pick readings (the bins stay whole: the
certificate is a union over all K of them); spectra, colours and comparisons go through
its R and T (``spectrum``, ``to_sd``, ``colour``), or, with ``theta_o`` and ``phi_o``,
``to_sd`` gives one bin's f over wavelength; :meth:`GonioResult.plot` draws the lobes.

:meth:`GonioResult.to_dataset` gives the ``xarray.Dataset`` of the data contract
(dims ``wavelength``, ``theta_i``, ``theta_o``, ``phi_o``; variables ``bin_counts``,
``rays``, ``brdf``; bin edges as coordinates ``theta_o_lower`` … ; attributes
``phi_folded``, ``phi_i``, ``mu``, ``delta``, ``guarantee``) that the ``tabulated`` BSDF
loads; ``write`` / ``read`` store it as NetCDF, CSV, JSON or Zarr (format
``"virtspec-mi gonio 1"``; files written with the former ``gonio_json`` attribute read too).

References
----------
Nicodemus et al. (1977), NBS Monograph 160; Baranoski et al. (2001), Sect. 6.
"""

from __future__ import annotations

import os

from functools import cached_property
from typing import Any, ClassVar, Mapping

import numpy as np

from virtspec_mi.budgets import bins as histogram_bounds
from virtspec_mi.budgets.rules import guarantee_of
from virtspec_mi.instruments.goniophotometer.bins import GonioBins
from virtspec_mi.kernel.counts import QUANTITIES
from virtspec_mi.results.base import ResultBase, attribute, plain_data, round_up, span, stored
from virtspec_mi.results.figures import Figure, sweep
from virtspec_mi.results.variables import READINGS, Coordinate, Variable, of_reading
from virtspec_mi.results.integrity import CountRules, field_value, whole_counts
from virtspec_mi.results.readings import Result

__all__ = ["GonioResult"]

_BINS = ("theta_o", "phi_o")
_REFLECTION_BINS = "bin_counts (theta_o < 90)"
_TRANSMISSION_BINS = "bin_counts (theta_o > 90)"
_BIN_RULES = CountRules(None, parts={_REFLECTION_BINS: "reflected", _TRANSMISSION_BINS: "transmitted"})
"""A reading's bins of each hemisphere add up to at most its reflected (θo < 90°) or transmitted rays (the rest
is ``outside``: escaping rays in no bin)."""


def _polar(result: "GonioResult", path: Any, quantity: str | None, **options: Any) -> Any:
    from virtspec_mi.instruments.goniophotometer.plot import plot_polar

    return plot_polar(result.as_grid(), path, **options)


def _series(result: "GonioResult", path: Any, quantity: str | None, **options: Any) -> Any:
    from virtspec_mi.instruments.goniophotometer.plot import plot_series

    return plot_series(result.as_grid(), path, **options)


class GonioResult(ResultBase):
    """
    A goniophotometer reading over (wavelength, θi, θo, φo) (see the module docstring):
    the Dataset of its spectrophotometer reading (:attr:`result`) with the bins' counts
    ``bin_counts`` over ``theta_o`` and ``phi_o`` (the bin centres), the bins and the
    guarantee in its attributes.

    Parameters
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

    FORMAT: ClassVar[str] = "virtspec-mi gonio 1"
    VARIABLES: ClassVar[dict[str, tuple[str, str]]] = {
        "theta_o": ("degree", "polar angle of the outgoing direction, bin centre"),
        "phi_o": ("degree", "azimuth of the outgoing direction, bin centre"),
        "bin_counts": ("1", "rays that left into the bin (exact)"),
    }
    """``(units, long_name)`` of this kind's stored variables and coordinates (beside
    :data:`~virtspec_mi.results.formats.VARIABLES`)."""
    DERIVED: ClassVar[dict[str, Variable]] = {
        **of_reading(Result.DERIVED),
        "fraction": Variable("1", "bin_counts / rays", lambda g: g.fraction),
        "brdf": Variable("1/sr", "BRDF (BTDF beyond theta_o = 90 deg) averaged over the bin: fraction / solid_angle",
                         lambda g: g.brdf),
        **{f"brdf_{side}": Variable("1/sr", f"simultaneous Clopper-Pearson {side} bound of brdf (all bins at once)",
                                    lambda g, end=end: g._band[end],
                                    attrs=lambda g: {"clopper_pearson_delta": g.delta / g.size})
           for end, side in ((0, "lower"), (1, "upper"))},
        "solid_angle": Variable("sr", "projected solid angle of the bin, integral of |cos theta_o|",
                                lambda g: g.solid_angles, _BINS,
                                lambda g: {"meaning": "both folded halves" if g.bins.fold_phi else "one bin"}),
        "cdf_theta_o": Variable("1", "empirical CDF of theta_o at the bin edges", lambda g: g.cdf_theta_o,
                                lambda g: (*g.reading_dims, "theta_o_edge"), csv=False),
        "cdf_phi_o": Variable("1", "empirical CDF of phi_o at the bin edges", lambda g: g.cdf_phi_o,
                              lambda g: (*g.reading_dims, "phi_o_edge"), csv=False),
        "outside": Variable("1", "escaping rays in no bin", lambda g: g.outside, READINGS, count=True),
        "bins_mu": Variable("1", "every bin fraction within bins_mu at once at delta (NaN: not certified)",
                            lambda g: g.bins_mu, READINGS),
        "cdf_mu": Variable("1", "DKW-Massart sup error of cdf_theta_o and cdf_phi_o at delta (NaN: not certified)",
                           lambda g: g.cdf_mu, READINGS),
    }
    """Every variable derived from the counts: the reading's (R, T, A …), the bins' fractions and BRDF with their
    simultaneous bounds, the solid angles, the CDFs over the bin edges and the certificates."""
    COORDS: ClassVar[dict[str, Coordinate]] = {
        **{f"{angle}_{side}": Coordinate("degree", f"{words} of the outgoing direction, bin {side} edge", (angle,),
                                         lambda g, angle=angle, cut=cut: g._edges(angle)[cut])
           for angle, words in (("theta_o", "polar angle"), ("phi_o", "azimuth"))
           for side, cut in (("lower", slice(None, -1)), ("upper", slice(1, None)))},
        **{f"{angle}_edge": Coordinate("degree", f"{words} of the outgoing direction, bin edge", (f"{angle}_edge",),
                                       lambda g, angle=angle: g._edges(angle), csv=False)
           for angle, words in (("theta_o", "polar angle"), ("phi_o", "azimuth"))},
    }
    """The bins' edges: each bin's lower and upper edge along ``theta_o`` / ``phi_o``, and every edge (the CDFs')."""
    FIGURES: ClassVar[dict[str, Figure]] = {
        "polar": Figure(_polar, "polar plots of f in and across the plane of incidence, one curve per theta_i, with "
                                "the simultaneous bands", ("brdf",)),
        "series": Figure(_series, "the distribution over theta_i as a series (f in the plane of incidence, one column "
                                  "per theta_i), with the simultaneous bands", ("brdf",)),
        "sweep": Figure(lambda g, path, quantity, **options: sweep.draw(g.result, path, quantity, **options),
                        "the reading's R, T or A against theta_i or wavelength", QUANTITIES),
    }
    """The lobes (polar and as a series over θi) and the reading's R, T and A."""
    KIND: ClassVar[str] = "goniophotometer reading"
    KIND_DIMS: ClassVar[tuple[str, ...]] = _BINS
    KIND_DIMS_REASON: ClassVar[str] = (
        "its certificate is a union over all K bins; select bins in to_dataset() (xarray), e.g. "
        "result.to_dataset().sel(theta_o=40, method='nearest')")
    QUANTITIES: ClassVar[tuple[str, ...]] = QUANTITIES
    _QUANTITY_NOTE: ClassVar[str] = ("a goniophotometer reading's spectra are its R, T and A; "
                                     "to_sd(theta_o=..., phi_o=...) gives one bin's f")

    # -- labels and counts -------------------------------------------------------------

    SHAPED_BY: ClassVar[str] = "bin_counts"

    def __init__(self, result: Result, bin_counts: Any, bins: GonioBins, guarantee: str = "union",
                 relative_tolerance: float | None = None, brdf_floor: float | None = None) -> None:
        self._extend(result, {"bin_counts": ((*result.dims, *_BINS), bin_counts)},
                     {"theta_o": bins.theta_centres, "phi_o": bins.phi_centres},
                     {"bins": bins, "guarantee": guarantee, "relative_tolerance": relative_tolerance,
                      "brdf_floor": brdf_floor})

    @cached_property
    def result(self) -> Result:
        """The spectrophotometer reading of the same rays, dims ``("wavelength", "theta_i")``."""

        return Result._of(self.data.drop_dims(list(_BINS)))

    bin_counts = stored("bin_counts", "Exact per-bin counts, ``int64``, shape (wavelengths, θi, θo bins, φo bins).")
    bins = attribute("bins", "The bins (:class:`~virtspec_mi.instruments.goniophotometer.bins.GonioBins`: edges in "
                             "degrees, folding).")
    guarantee = attribute("guarantee", "How N was sized (:data:`~virtspec_mi.budgets.rules.GUARANTEES`), or "
                                       "``\"rays\"`` when given.", str)
    relative_tolerance = attribute("relative_tolerance", "The relative certificate asked for "
                                                         "(``guarantee=\"relative\"``), else ``None``.")
    brdf_floor = attribute("brdf_floor", "The BRDF floor of the relative certificate (``guarantee=\"relative\"``), "
                                         "else ``None``.")

    @property
    def interval_delta(self) -> float:
        return self.result.interval_delta

    @property
    def theta_i(self) -> np.ndarray:
        """Polar incidence in degrees, as an array (one element for a scalar label)."""

        return np.atleast_1d(self.result.coords["theta_i"])

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
        lower, upper = histogram_bounds.brdf_intervals(self.bin_counts, self.rays[..., None, None], self.solid_angles,
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
        F̂(θ) = #(escaped with θo < θ)/N at the θo edges, shape (…, θo bins + 1) — the
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
    def two_stage(self) -> bool:
        """True when each reading's N was sized from its own pilot (``bound="two-stage"``; its rays are spent)."""

        return self.result.pilot is not None

    @property
    def bins_mu(self) -> np.ndarray:
        """
        μ with |m_k/N − p_k| < μ for every bin at once at δ (per reading; NaN: not
        certified): the guarantee's μ for the N spent, or, for a :attr:`two_stage`
        reading, μ itself — what the pilot sized N for (each bin fraction a column of
        the two-stage rule at δ/K over both stages, so all K at once at δ).
        """

        if self.two_stage:
            return self._certified(np.full(np.shape(self.rays), float(self.result.mu)))
        return self._certified(guarantee_of(self.guarantee).certified(self.rays, self.delta, self.result.mu,
                                                                      self.size))

    @property
    def cdf_mu(self) -> np.ndarray:
        """DKW–Massart μ: sup |F̂ − F| < μ for the CDF of θo (and of φo) at δ (NaN: not certified)."""

        return self._certified(histogram_bounds.dkw_mu(self.rays, self.delta))

    @property
    def relative_mu(self) -> np.ndarray | None:
        """The relative tolerance on f_k certified for bins with f_k ≥ ``brdf_floor`` (NaN: none); ``None`` if no floor."""

        if self.brdf_floor is None:
            return None
        eps = histogram_bounds.relative_tolerance(self.rays, self.brdf_floor, self.delta, self.size,
                                              float(self.solid_angles.min()))
        return np.where(self.result.certified, eps, np.nan)

    @property
    def sized_by(self) -> str | None:
        """
        The guarantee N was sized for, in words (``None`` when ``rays`` was given): the
        rule, its μ (or relative ε above the floor), δ and K; for a :attr:`two_stage`
        reading, its pilot and what the pilot sized N for. Whether these rays deliver it
        is :meth:`certificate`'s to say.
        """

        s, rule = self.result.settings, guarantee_of(self.guarantee)
        if self.two_stage:
            return (f"sized by two-stage: a pilot of {span(self.result.pilot.rays)} rays, then N per reading from the "
                    f"pilot's {self.size} bin fractions and R, T, A, for every bin fraction within mu = {s.mu:g} at "
                    f"once (the exact rule at delta/K per bin over both stages, K = {self.size}), delta = {s.delta:g}")
        target = rule.target(s.mu, self.size, self.relative_tolerance, self.brdf_floor)
        return None if target is None else f"{rule.sized} for {target}, delta = {s.delta:g}"

    def certificate(self) -> str:
        """What the reading's rays guarantee, in words (worst reading), or "not certified"."""

        k, delta = self.size, self.delta
        pilot = "" if not self.two_stage else f" + {span(self.result.pilot.rays)} pilot"
        counted = f"N = {span(self.rays)}{pilot} rays per reading, K = {k} bins"
        rule = "sized by two-stage" if self.two_stage else guarantee_of(self.guarantee).sized
        bins_mu, cdf_mu = self.bins_mu, self.cdf_mu
        if np.all(np.isnan(cdf_mu)):
            return f"{counted} ({rule}): NOT CERTIFIED (see the reading's warnings, or too few rays)"
        lines = [f"{counted} ({rule}), each statement with probability >= {1 - delta:g} per reading:"]
        lines.append(f"  CDFs of theta_o and phi_o: sup |F - F_N| < {round_up(float(np.nanmax(cdf_mu))):g} "
                     "(DKW-Massart)")
        if np.all(np.isnan(bins_mu)):
            lines.append("  bin fractions: not certified (too few rays for K bins)")
        else:
            union = ("two-stage: what the pilot sized N for, each bin at delta/K" if self.two_stage
                     else guarantee_of(self.guarantee).union_words)
            lines.append(f"  every bin fraction at once: |m_k/N - p_k| < {round_up(float(np.nanmax(bins_mu))):g} "
                         f"({union})")
        lines.append(f"  f_k: simultaneous Clopper-Pearson intervals, each at delta/K = {delta / k:.3g}")
        relative = self.relative_mu
        if relative is not None:
            lines.append(f"  f_k >= {self.brdf_floor:g}/sr: relative error < "
                         + ("not certified (too few rays)" if np.all(np.isnan(relative))
                            else f"{round_up(float(np.nanmax(relative))):g}") + " (Chernoff + union)")
        if np.any(np.isnan(cdf_mu)):
            lines.append("  some readings NOT CERTIFIED")
        return "\n".join(lines)

    def summary(self) -> str:
        """The spectrophotometer summary (R and T certified), the bins, their certificate and :meth:`theta_o_table`."""

        b = self.bins
        folded = ", phi_o folded to |phi_o - phi_i|" if b.fold_phi else ""
        lines = [self.result.summary(sized_by=self.sized_by), "",
                 f"Goniophotometer: {b.shape[0]} theta_o x {b.shape[1]} phi_o bins ({b.binning}{folded}), "
                 f"theta_o {b.theta_edges[0]:g}..{b.theta_edges[-1]:g}, phi_o {b.phi_edges[0]:g}..{b.phi_edges[-1]:g} "
                 "degrees",
                 self.certificate()]
        if np.any(self.outside):
            lines.append(f"  {int(self.outside.sum()):,} escaping rays fell outside the bins")
        return "\n".join([*lines, "", self.theta_o_table()])

    def theta_o_table(self, most: int = 8) -> str:
        """
        The readings per θo bin, compactly: one row per θo bin (its centre, degrees), one
        column per reading (the first ``most`` of them), the fraction of the incident rays
        that left into the bin, summed over φo; then each reading's R and T. A row is the
        difference of the empirical CDF of θo (:attr:`cdf_theta_o`) at the bin's edges, so
        every row of a reading lies within 2·:attr:`cdf_mu` of its expectation at once
        (DKW–Massart, probability ≥ 1 − δ); the reflection rows add up to R, the
        transmission rows to T (less the rays outside the bins).

        References
        ----------
        Massart (1990), Ann. Probab. 18, 1269–1283 (the DKW constant).
        """

        rings = (self.bin_counts.sum(axis=-1) / self.rays[..., None]).reshape(-1, self.bins.shape[0])
        reading = self.result
        shape = tuple(reading.sizes[d] for d in reading.dims)
        varying = [d for d in reading.dims if reading.sizes[d] > 1]
        units = {"wavelength": " nm", "theta_i": " deg"}
        labels = []
        for index in np.ndindex(*shape):
            at = dict(zip(reading.dims, index))
            labels.append(", ".join(f"{np.atleast_1d(reading.coords[d])[at[d]]:g}{units.get(d, '')}" if d in units
                                    else f"{d} {np.atleast_1d(reading.coords[d])[at[d]]:g}" for d in varying)
                          or "fraction")
        shown = min(len(labels), most)
        widths = [max(9, len(label)) for label in labels[:shown]]
        cdf_mu = self.cdf_mu
        certified = ("not certified" if np.all(np.isnan(cdf_mu)) else
                     f"every row of a reading within {round_up(2 * float(np.nanmax(cdf_mu))):g} at once (2 x the DKW "
                     f"tolerance of the CDF of theta_o, probability >= {1 - self.delta:g})")
        lines = [f"Per theta_o bin (rows: bin centres, degrees): the fraction of the incident rays leaving into it, "
                 f"summed over phi_o; {certified}",
                 f"{'theta_o':>8}  " + "  ".join(f"{label:>{w}}" for label, w in zip(labels, widths))]
        for row, centre in enumerate(self.bins.theta_centres):
            lines.append(f"{centre:>8g}  " + "  ".join(f"{rings[k, row]:>{w}.5f}" for k, w in enumerate(widths)))
        for name, values in (("R", reading.reflectance), ("T", reading.transmittance)):
            flat = np.ravel(values)
            lines.append(f"{name:>8}  " + "  ".join(f"{flat[k]:>{w}.5f}" for k, w in enumerate(widths)))
        if shown < len(labels):
            lines.append(f"(the first {shown} of {len(labels)} readings; every one in to_dataset(), write() and "
                         "as_dict())")
        return "\n".join(lines)

    def __repr__(self) -> str:
        sizes = " x ".join(f"{n} {d}" for d, n in self.sizes.items())
        return f"GonioResult({sizes}, N = {int(np.max(self.rays)):,})"

    # -- plain data, datasets and files ------------------------------------------------

    def as_dict(self) -> dict[str, Any]:
        """Plain data (JSON-ready): the reading's result, the bins, counts and the certificate."""

        return {
            "format": self.FORMAT,
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
    def _from_dict(cls, data: Mapping[str, Any]) -> "GonioResult":
        """The reading of :meth:`as_dict` (checked by :meth:`from_dict <virtspec_mi.results.base.ResultBase.from_dict>`)."""

        relative, floor = (field_value(data, key, "number or null") if key in data else None
                           for key in ("relative_tolerance", "brdf_floor"))
        return cls(result=Result.from_dict(field_value(data, "result", "object")),
                   bin_counts=whole_counts(data["bin_counts"], "bin_counts"),
                   bins=GonioBins.from_dict(field_value(data, "bins", "object")),
                   guarantee=field_value(data, "guarantee", "text"),
                   relative_tolerance=None if relative is None else float(relative),
                   brdf_floor=None if floor is None else float(floor))

    def _count_groups(self) -> list[tuple[str, Mapping[str, np.ndarray], CountRules, tuple[str, ...]]]:
        """The reading's counts, and its bins of each hemisphere against its reflected and transmitted rays."""

        transmission = self.bins.transmitted
        hemispheres = {"reflected": self.result.reflected, "transmitted": self.result.transmitted,
                       _REFLECTION_BINS: self.bin_counts[..., ~transmission, :].sum(axis=(-2, -1)),
                       _TRANSMISSION_BINS: self.bin_counts[..., transmission, :].sum(axis=(-2, -1))}
        return [*self.result._count_groups(), ("", hemispheres, _BIN_RULES, self.result.dims)]

    def _edges(self, angle: str) -> np.ndarray:
        """The bins' edges along ``theta_o`` or ``phi_o`` (degrees)."""

        return self.bins.theta_edges if angle == "theta_o" else self.bins.phi_edges

    def _file_attrs(self) -> dict[str, Any]:
        """The reading's attributes and the bins': folding, binning, the guarantee, K and its δ."""

        b = self.bins
        return {**self.result._file_attrs(), "phi_folded": int(b.fold_phi), "phi_i": self.phi_i,
                "binning": b.binning, "guarantee": self.guarantee, "bins": self.size, "bins_delta": self.delta}

    # -- spectra, colour and plots -----------------------------------------------------

    def _quantity(self, quantity: str) -> tuple[np.ndarray, np.ndarray, float]:
        return self.result._quantity(quantity)

    def to_rgl(self, path: str | os.PathLike, resolution: int = 32) -> Any:
        """
        Refused: a θo × φo bin's interval certifies the bin's average, not a node of the ``.bsdf``'s grid. An RGL
        ``.bsdf`` with certified values comes from a reading binned on its grid: ``vm.gonio(…, binning="rgl",
        rgl_resolution=n, beam="collimated").to_rgl(path)``
        (:class:`~virtspec_mi.instruments.goniophotometer.rgl_reading.RGLReading`).
        """

        raise ValueError("an RGL .bsdf stores certified cell means only of a reading binned on its grid: measure "
                         f"with binning='rgl', rgl_resolution={resolution}, beam='collimated' (virtspec gonio --rgl "
                         "FILE does); this reading's theta_o x phi_o bins are not the file's cells")

    def to_sd(self, quantity: str | None = None, theta_i: float | None = None, *, theta_o: float | None = None,
              phi_o: float | None = None) -> Any:
        """
        A spectrum as a ``colour.SpectralDistribution``: R, T or A of the reading (as
        :meth:`Result.to_sd <virtspec_mi.results.base.ResultBase.to_sd>`), or, given
        ``theta_o`` and ``phi_o``, f over wavelength in the bin holding (θo, φo) at one θi
        (default: the first; 1/sr; needs several wavelengths).
        """

        if theta_o is None and phi_o is None:
            return super().to_sd(quantity, theta_i)
        if theta_o is None or phi_o is None or quantity not in (None, "brdf"):
            raise ValueError("to_sd of one bin needs theta_o and phi_o (and quantity None or 'brdf'; got "
                             f"quantity={quantity!r}, theta_o={theta_o!r}, phi_o={phi_o!r})")
        import colour

        grid = self.as_grid()
        i = 0 if theta_i is None else int(np.argmin(np.abs(grid.theta_i - theta_i)))
        t = int(np.clip(np.searchsorted(self.bins.theta_edges, theta_o, side="right") - 1, 0, self.bins.shape[0] - 1))
        p = int(np.clip(np.searchsorted(self.bins.phi_edges, phi_o, side="right") - 1, 0, self.bins.shape[1] - 1))
        if len(grid.wavelengths) < 2:
            raise ValueError("to_sd needs a reading over several wavelengths (got 1)")
        order = np.argsort(grid.wavelengths)
        name = f"f at theta_o {self.theta_o[t]:g}, phi_o {self.phi_o[p]:g} deg (theta_i {grid.theta_i[i]:g})"
        return colour.SpectralDistribution(dict(zip(grid.wavelengths[order], grid.brdf[order, i, t, p])), name=name)

    def to_msds(self, theta_i: float | None = None) -> Any:
        """R, T and A of the reading at one θi as a ``colour.MultiSpectralDistributions``."""

        return self.result.to_msds(theta_i)

    def drawn_note(self, quantity: str | None = None) -> str:
        """The lobes are drawn at one wavelength: which, when there are several."""

        drawn = np.atleast_1d(self.coords["wavelength"])
        if quantity not in (None, "brdf") or len(drawn) < 2:
            return ""
        return (f"drew the lobes at {drawn[0]:g} nm, the first of {len(drawn)} wavelengths "
                "(another: --sel wavelength=NM)")
