"""
One result type for one reading or many: :class:`Result`
========================================================

A :class:`Result` holds exact :class:`~virtspec_mi.kernel.counts.Counts` over labelled
dimensions (xarray conventions): a single reading of :func:`virtspec_mi.measure` has the
dim ``wavelength`` (θi is a scalar coordinate), a sweep has ``(wavelength, theta_i)``;
new dimensions add labels, not classes. Everything else is derived here, once, from the
counts: reflectance ρ = m/N (eq. 2), transmittance, absorptance, the specular/regular
parts, the Clopper–Pearson intervals, the back-lit fraction and the **certified
tolerance** — the μ that the rays actually spent guarantee at δ under the rule used
(:mod:`virtspec_mi.budgets.rules`), or "not certified" (NaN) where no rule applies.

The same methods serve one reading or many, and every result kind
(:class:`~virtspec_mi.results.base.ResultBase`: ``sel`` / ``isel``, files, spectra):
:meth:`Result.summary`, :meth:`Result.as_dict` (JSON, format ``"virtspec-mi result 1"``),
:meth:`Result.to_dataset` (``xarray.Dataset``), ``write`` / ``read`` (NetCDF, CSV, JSON,
Zarr; :mod:`virtspec_mi.results.io`), ``to_sd`` / :meth:`Result.to_msds` / ``colour``
(colour-science; :mod:`virtspec_mi.colorimetry.cie`) and :meth:`Result.plot`
(:mod:`virtspec_mi.results.plot`).

References
----------
Baranoski et al. (2001), eqs. (2), (14), (19), (23); Clopper & Pearson (1934).
"""

from __future__ import annotations

import json
import warnings
from dataclasses import asdict
from functools import cached_property
from typing import Any, ClassVar, Mapping

import numpy as np

from virtspec_mi.base.version import __version__
from virtspec_mi.kernel.counts import DIRECTION_TOLERANCE, QUANTITIES, WEIGHT_ROUNDING, Counts
from virtspec_mi.geometry.disks import InstrumentGeometry, backlit_fraction
from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.results.base import ResultBase, attribute, per_count, plain_data, round_up, span
from virtspec_mi.results.figures import Figure, spectra, sweep
from virtspec_mi.results.variables import Variable, bounds
from virtspec_mi.results.integrity import (CountRules, agree_stored, check_counts, check_shapes, field_value,
                                           optional_numbers, reading_at, whole_counts)
from virtspec_mi.settings import Settings

__all__ = ["Result", "plain_data", "COUNT_RULES", "fluctuation"]

COUNT_RULES = CountRules(
    "rays",
    parts={"reflected": "rays", "transmitted": "rays", "capped": "rays", "invalid_directions": "rays",
           "weight_violations": "rays", "rounded_weights": "rays", "specular_reflected": "reflected",
           "regular_transmitted": "transmitted"},
    sums=((("reflected", "transmitted", "capped", "invalid_directions"), "rays", False),),
)
"""How a reading's counts add up: each a share of its rays, the delta events a share of their fate, and
reflected + transmitted + capped + invalid_directions <= rays (absorbed, the rest, is never negative)."""

_STORED = CountRules(None, sums=((("reflected", "transmitted", "absorbed", "capped", "invalid_directions"), "rays",
                                  True),))
"""A file's own ``absorbed`` (derived, yet written): the five fates add up to the rays."""

_PARTS = ("specular_reflectance", "diffuse_reflectance", "regular_transmittance", "diffuse_transmittance")


def _stored_name(name: str) -> str:
    """``counts.rays`` → ``rays``, ``pilot.rays`` → ``pilot_rays``: a count's variable in the stored Dataset."""

    group, _, count = name.partition(".")
    return count if group == "counts" else f"{group}_{count}"


def _counts(name: str, doc: str) -> property:
    return property(lambda self: getattr(self.counts, name), doc=doc)


class Result(ResultBase):
    """
    Certified hemispherical readings over labelled dimensions (see the module docstring):
    one ``xarray.Dataset`` (:attr:`data`) of the counts (``rays``, ``reflected`` …; a
    two-stage pilot's as ``pilot_rays`` …) with the settings, geometry and provenance in
    its attributes.

    Parameters
    ----------
    dims : tuple of str
        The dimensions of every per-reading array, e.g. ``("wavelength",)`` or
        ``("wavelength", "theta_i")``.
    coords : dict of str to ndarray
        Labels: ``wavelength`` (nm) and ``theta_i`` (degrees); a coordinate that is not a
        dim is a 0-d array (θi of a single reading).
    counts : Counts
        Exact counts by name behind the estimates.
    pilot : Counts or None
        Two-stage pilot counts (spent, not in the estimates); ``None`` for a fixed budget.
    settings : Settings
        The settings used (its ``theta_i`` is the first angle).
    geometry : InstrumentGeometry
        r₁, r₂ and D of the scene.
    seconds : float
        Time spent tracing, summed over the batches (and over interrupted and resumed
        runs): the wall time of a sweep in this process; for a sweep on Dask workers the
        workers' tracing time added up (worker-seconds), not the wall time.
    scene : str
        Fingerprint of the scene (``sha256:…``), or "".
    wavelength_independent : bool
        The specimen declared itself wavelength-independent: readings that differ only
        in wavelength were traced once and share their counts.
    version : str
        virtspec-mi version that made the result.
    parameters : dict or None
        The swept specimen parameters (:meth:`virtspec_mi.engine.parameters.ParameterSpace.as_dict`:
        names, ``mi.traverse`` keys, values, grid or points), ``None`` for none. A grid adds
        one dim per parameter (named as given) after ``theta_i``; points add the dim
        ``point`` with each parameter as a coordinate along it. A parameter selected with
        :meth:`sel` stays as a scalar coordinate.
    source : dict or None
        The scene's name and ``-D`` defines (:func:`virtspec_mi.runtime.scene.scene_source`), or ``None``.
    """

    FORMAT: ClassVar[str] = "virtspec-mi result 1"
    KIND: ClassVar[str] = "hemispherical reading"
    QUANTITIES: ClassVar[tuple[str, ...]] = QUANTITIES
    DERIVED: ClassVar[dict[str, Variable]] = {
        "reflectance": Variable("1", "hemispherical reflectance m/N", lambda r: r.reflectance),
        "transmittance": Variable("1", "hemispherical transmittance t/N", lambda r: r.transmittance),
        "absorptance": Variable("1", "absorptance (absorbed rays)/N", lambda r: r.absorptance),
        "specular_reflectance": Variable("1", "specular reflectance (rays reflected by a delta event)/N",
                                         lambda r: r.specular_reflectance),
        "diffuse_reflectance": Variable("1", "diffuse reflectance (reflected rays not by a delta event)/N",
                                        lambda r: r.diffuse_reflectance),
        "regular_transmittance": Variable("1", "regular transmittance (rays transmitted by a delta event)/N",
                                          lambda r: r.regular_transmittance),
        "diffuse_transmittance": Variable("1", "diffuse transmittance (transmitted rays not by a delta event)/N",
                                          lambda r: r.diffuse_transmittance),
        "absorbed": Variable("1", "rays absorbed (rays - reflected - transmitted - capped - invalid_directions)",
                             lambda r: r.absorbed, count=True),
        "certified_mu": Variable(
            "1", "tolerance the rays guarantee at interval_delta under the rule used (NaN: not certified)",
            lambda r: r.certified_mu,
            attrs=lambda r: {"meaning": "tolerance the rays guarantee at interval_delta under the rule used; NaN: "
                                        "not certified"}),
        "rounding_bias": Variable("1", "largest shift of the estimates by rounded BSDF weights",
                                  lambda r: r.rounding_bias),
        **bounds({name: f"the {name}" for name in QUANTITIES}, lambda r, name: r.interval(name),
                 lambda r: r.interval_delta),
    }
    """Every variable derived from the counts: R, T, A and their parts, the certificate and the intervals."""
    FIGURES: ClassVar[dict[str, Figure]] = {"sweep": sweep, "spectra": spectra()}
    """A quantity against θi or wavelength; quantities over wavelength at one θi."""

    def __init__(self, dims: tuple[str, ...], coords: Mapping[str, Any], counts: Counts, pilot: Counts | None,
                 settings: Settings, geometry: InstrumentGeometry, seconds: float, scene: str = "",
                 wavelength_independent: bool = False, version: str = __version__, parameters: dict | None = None,
                 source: dict | None = None) -> None:
        groups = {"counts": counts} if pilot is None else {"counts": counts, "pilot": pilot}
        checked = {f"{group}.{name}": (tuple(dims), getattr(named, name)) for group, named in groups.items()
                   for name in Counts.names()}
        attrs = {"settings": settings, "geometry": geometry, "seconds": float(seconds), "scene": scene,
                 "wavelength_independent": bool(wavelength_independent), "version": version,
                 "parameters": parameters, "source": source}
        self._store(dims, coords, {_stored_name(name): array for name, array in checked.items()}, attrs, checked)

    @cached_property
    def counts(self) -> Counts:
        """Exact counts by name behind the estimates."""

        return Counts(**{name: self.data.variables[name].values for name in Counts.names()})

    @cached_property
    def pilot(self) -> Counts | None:
        """Two-stage pilot counts (spent, not in the estimates); ``None`` for a fixed budget."""

        if "pilot_rays" not in self.data:
            return None
        return Counts(**{name: self.data.variables[f"pilot_{name}"].values for name in Counts.names()})

    geometry = attribute("geometry", "r₁, r₂ and D of the scene "
                                     "(:class:`~virtspec_mi.geometry.disks.InstrumentGeometry`).")
    wavelength_independent = attribute(
        "wavelength_independent", "The specimen declared itself wavelength-independent: readings that differ only in "
                                  "wavelength share counts.", bool)

    # -- counts by name ----------------------------------------------------------------

    rays = _counts("rays", "Rays N per reading behind the estimates (int64).")
    reflected = _counts("reflected", "Rays reflected into the upper hemisphere, per reading.")
    transmitted = _counts("transmitted", "Rays transmitted into the lower hemisphere, per reading.")
    capped = _counts("capped", "Random walks stopped by the specimen's step cap: in none of R, T, A.")
    invalid_directions = _counts(
        "invalid_directions", "Rays the BSDF sent in an invalid direction (NaN, infinite, not unit): in none of R, T, A.")
    weight_violations = _counts("weight_violations", "Rays whose BSDF weight was outside [−ε, 1 + ε] or NaN.")
    rounded_weights = _counts("rounded_weights", "Rays whose BSDF weight was within ε of [0, 1] (rounding).")
    specular_reflected = _counts("specular_reflected", "Reflected rays whose sampled event was a delta event.")
    regular_transmitted = _counts("regular_transmitted", "Transmitted rays whose sampled event was a delta event.")
    largest_weight = _counts("largest_weight", "Largest violating BSDF weight per reading (NaN: none).")

    @property
    def absorbed(self) -> np.ndarray:
        """Absorbed rays: rays − reflected − transmitted − capped − invalid_directions."""

        return self.counts.absorbed

    @property
    def pilot_rays(self) -> np.ndarray | None:
        """Two-stage pilot rays per reading (spent, not in the estimates); ``None`` for a fixed budget."""

        return None if self.pilot is None else self.pilot.rays

    @property
    def rays_spent(self) -> np.ndarray:
        """All rays traced per reading (two-stage: pilot included)."""

        return self.rays if self.pilot is None else self.rays + self.pilot.rays

    # -- estimates ---------------------------------------------------------------------

    @property
    def reflectance(self) -> np.ndarray:
        """ρ = m/N per reading (eq. 2)."""

        return self.reflected / self.rays

    @property
    def transmittance(self) -> np.ndarray:
        """τ = t/N per reading."""

        return self.transmitted / self.rays

    @property
    def absorptance(self) -> np.ndarray:
        """α = absorbed/N per reading (ρ + τ + α = 1 − (capped + invalid_directions)/N)."""

        return self.absorbed / self.rays

    @property
    def specular_reflectance(self) -> np.ndarray:
        """ρs: reflected by a mirror (delta) event (CIE regular reflectance; MCML Rsp)."""

        return self.specular_reflected / self.rays

    @property
    def diffuse_reflectance(self) -> np.ndarray:
        """ρd = ρ − ρs: reflected by scattering (MCML's Rd)."""

        return (self.reflected - self.specular_reflected) / self.rays

    @property
    def regular_transmittance(self) -> np.ndarray:
        """τr: transmitted by a delta event (unscattered, collimated transmittance)."""

        return self.regular_transmitted / self.rays

    @property
    def diffuse_transmittance(self) -> np.ndarray:
        """τd = τ − τr: transmitted after scattering."""

        return (self.transmitted - self.regular_transmitted) / self.rays

    def quantity(self, name: str) -> np.ndarray:
        """``reflectance``, ``transmittance`` or ``absorptance`` by name."""

        if name not in QUANTITIES:
            raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)} (got {name!r})")
        return getattr(self, name)

    @property
    def backlit_fraction(self) -> Any:
        """
        Share of the emitter area below the specimen plane (conical beam, θi > atan(D/r₁)):
        those rays strike the specimen's back face. A float for one θi, else per θi.
        """

        angles = np.atleast_1d(self.coords["theta_i"])
        values = np.array([backlit_fraction(self.geometry, t) if self.settings.beam == "conical" else 0.0
                           for t in angles])
        return float(values[0]) if np.ndim(self.coords["theta_i"]) == 0 else values

    # -- the certificate ---------------------------------------------------------------

    @property
    def bound(self) -> str:
        """The ray budget used: the settings' bound, or ``"rays"`` when N was given explicitly."""

        return self.settings.bound if self.settings.rays is None else "rays"

    @property
    def interval_delta(self) -> float:
        """δ of each certified quantity and interval: δ, or δ/2 with ``joint``."""

        return self.settings.quantity_delta

    @property
    def rounding_bias(self) -> np.ndarray:
        """Largest shift of each estimate by BSDF weights rounded to 0 or 1: rounded_weights·ε/N."""

        return self.rounded_weights * WEIGHT_ROUNDING / self.rays

    @property
    def certified(self) -> np.ndarray:
        """True for the readings a rule certifies: no weight violations, capped walks or invalid directions."""

        return (self.weight_violations == 0) & (self.capped == 0) & (self.invalid_directions == 0)

    @cached_property
    def certified_mu(self) -> np.ndarray:
        """
        The tolerance each reading's rays guarantee at its δ (:attr:`interval_delta`),
        per reading: μ for a reading sized by an adaptive rule (two-stage), else the
        rule's :meth:`~virtspec_mi.budgets.rules.RayBudget.certified` tolerance of its N —
        ≤ μ when N came from the rule, larger when fewer rays were asked for (e.g.
        ``rays=1000`` gives 0.0515 under eq. (19)) — plus :attr:`rounding_bias`. NaN
        where no rule applies (weight violations, capped walks or invalid directions).
        """

        s = self.settings
        if s.adaptive:
            tolerance = np.full(self.shape, s.mu)
        else:
            tolerance = per_count(self.rays, lambda n: s.budget.certified(n, self.interval_delta, s.mu))
        return np.where(self.certified, tolerance + self.rounding_bias, np.nan)

    def interval(self, quantity: str = "reflectance") -> tuple[np.ndarray, np.ndarray]:
        """Clopper–Pearson interval ``(lower, upper)`` of ``quantity`` per reading at :attr:`interval_delta`."""

        self.quantity(quantity)  # validates the name
        return self._intervals[quantity]

    @cached_property
    def _intervals(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Every quantity's interval, computed once (the beta quantiles cost ~1 µs per reading)."""

        counts = {"reflectance": self.reflected, "transmittance": self.transmitted, "absorptance": self.absorbed}
        return {name: clopper_pearson(values, self.rays, self.interval_delta) for name, values in counts.items()}

    @property
    def reflectance_interval(self) -> np.ndarray:
        """Clopper–Pearson interval ``[lower, upper]`` of ρ per reading, shape (…, 2)."""

        return np.stack(self.interval("reflectance"), axis=-1)

    @property
    def transmittance_interval(self) -> np.ndarray:
        """Clopper–Pearson interval of τ per reading, shape (…, 2)."""

        return np.stack(self.interval("transmittance"), axis=-1)

    @property
    def absorptance_interval(self) -> np.ndarray:
        """Clopper–Pearson interval of α per reading, shape (…, 2)."""

        return np.stack(self.interval("absorptance"), axis=-1)

    def warn_if_uncertified(self, stacklevel: int = 3) -> None:
        """``RuntimeWarning`` for every reason a reading escaped its certificate."""

        for line in self._uncertified():
            warnings.warn(line, RuntimeWarning, stacklevel=stacklevel)

    def _uncertified(self) -> list[str]:
        lines = []
        if np.any(self.weight_violations):
            largest = self.largest_weight[~np.isnan(self.largest_weight)]
            seen = f", the largest {largest.max():.6g}" if largest.size else " (NaN)"
            lines.append(f"{int(np.sum(self.weight_violations))} BSDF sample weights fell outside [0, 1] by more "
                         f"than the rounding tolerance {WEIGHT_ROUNDING:g}{seen}: the specimen is not energy "
                         "conserving, so these readings are not certified")
        if np.any(self.capped):
            lines.append(f"{int(np.sum(self.capped))} random walks reached the specimen's step cap; they are counted "
                         "in capped and in none of reflectance, transmittance and absorptance (not certified)")
        if np.any(self.invalid_directions):
            lines.append(f"{int(np.sum(self.invalid_directions))} rays left the specimen BSDF in an invalid direction "
                         f"(NaN, infinite, or length off 1 by more than {DIRECTION_TOLERANCE:g}); they are counted in "
                         "invalid_directions and in none of reflectance, transmittance and absorptance (not certified)")
        return lines

    # -- text --------------------------------------------------------------------------

    def __repr__(self) -> str:
        sizes = ", ".join(f"{d}: {n}" for d, n in zip(self.dims, self.shape))
        mu = self.certified_mu
        certified = "not certified" if np.all(np.isnan(mu)) else f"certified mu <= {round_up(float(np.nanmax(mu))):g}"
        return (f"<virtspec_mi.{type(self).__name__} ({sizes}) {self.settings.beam}, {self.bound} bound, "
                f"N = {span(self.rays)}, {certified} at delta = {self.interval_delta:g}>")

    def summary(self, sized_by: str | None = None) -> str:
        """
        Human-readable summary: settings, the certificate, and a table for a single reading.
        ``sized_by`` names the rule that sized N when it was not this result's own bound
        (a goniophotometer's guarantee over its bins): it replaces "rays given".
        """

        ones = [d for d, n in zip(self.dims, self.shape) if n == 1 and d != "wavelength"]
        if ones and all(n == 1 for d, n in zip(self.dims, self.shape) if d != "wavelength"):
            # one reading over wavelength, whether its other labels are dims of one or scalars (a file read back,
            # a command's squeezed print): one heading for both
            return Result.summary(self.squeeze(*ones), sized_by)
        s = self.settings
        incidence = ("cosine-weighted over the hemisphere" if s.beam == "diffuse"
                     else f"theta_i = {self._angles()} deg, phi_i = {s.phi_i:g} deg")
        single = self.dims in ((), ("wavelength",))
        if single:
            head = f"{s.beam} reading, {incidence}, sampling = {s.sampling}, seed = {s.seed}"
        else:
            sizes = " x ".join(f"{n} {'wavelengths' if d == 'wavelength' else d}"
                               for d, n in reversed(list(zip(self.dims, self.shape))))
            head = f"{s.beam} sweep: {sizes} (phi_i = {s.phi_i:g} deg, sampling = {s.sampling}, seed = {s.seed})"
        spent = f"; {self.seconds * 1e3:.1f} ms"
        if not single:
            spent += " of tracing summed over the batches (on Dask workers: worker time, not wall time)"
        lines = [head, self._certificate(sized_by) + spent]
        fixed = [f"{name} = {float(self.coords[name]):g}" for name in self.parameter_names
                 if not self.coord_dims(name)]
        if fixed:
            lines.insert(1, "specimen parameters: " + ", ".join(fixed))
        if single:
            lines += self._table()
        if self.wavelength_independent and np.size(self.wavelengths) > 1:
            lines.append("note: wavelength-independent specimen: traced once"
                         + ("" if single else " per theta_i") + ", the same rays for every wavelength")
        backlit = np.atleast_1d(self.backlit_fraction)
        if np.any(backlit > 0):
            lines.append(f"note: up to {backlit.max():.2%} of the emitter lies below the specimen plane "
                         f"(theta_i > {self.geometry.backlit_threshold:.2f} deg): those rays strike the back face")
        if np.any(self.rounded_weights):
            lines.append(f"note: {int(self.rounded_weights.sum())} BSDF weights within {WEIGHT_ROUNDING:g} of [0, 1] "
                         f"were rounded (bias <= {round_up(float(self.rounding_bias.max())):g}, in the tolerance)")
        lines += [f"WARNING: {line}" for line in self._uncertified()]
        return "\n".join(lines)

    def _angles(self) -> str:
        angles = np.atleast_1d(self.coords["theta_i"])
        return f"{angles[0]:g}" if len(angles) == 1 else f"{angles.min():g}..{angles.max():g}"

    def _certificate(self, sized_by: str | None = None) -> str:
        s = self.settings
        unit = "wavelength" if self.dims == ("wavelength",) else "reading"
        pilot = "" if self.pilot is None else f" + {int(self.pilot.rays.max()):,} pilot"
        counted = f"N = {span(self.rays)}{pilot} rays per {unit}"
        mu = self.certified_mu
        if np.all(np.isnan(mu)):
            return f"{counted} ({'' if sized_by is None else sized_by + '; '}NOT CERTIFIED: see the warnings below)"
        worst = round_up(float(np.nanmax(mu)))
        together = "R and T together" if s.joint else "|rho - m/N|"
        if sized_by is not None:
            rule = f"{sized_by}; at these N the {s.bound} bound gives"
        else:
            rule = f"{s.bound} bound" if s.rays is None else f"rays given; {s.bound} bound"
        text = f"{counted} ({rule}: {together} < {worst:g} with probability >= {1 - s.delta:g}"
        if sized_by is None and s.rays is None and worst > s.mu * (1 + 1e-9):  # mu sized N (rays given: it did not)
            text += f"; mu = {s.mu:g} was asked: these rays guarantee only {worst:g}"
        if np.any(np.isnan(mu)):
            text += "; some readings NOT CERTIFIED"
        return text + ")"

    def _table(self) -> list[str]:
        if self.dims != ("wavelength",):  # one reading at one wavelength: a table of one row
            return self.as_grid().squeeze()._table()
        rays = self.rays
        lines = [f"{'lambda/nm':>10} {'reflectance':>12} {'transmittance':>14} {'absorptance':>12}"
                 f"   Clopper-Pearson {1 - self.interval_delta:g} intervals (R; T)"]
        r_int, t_int = self.reflectance_interval, self.transmittance_interval
        varies = rays.min() != rays.max()
        for i, wavelength in enumerate(self.wavelengths):
            lines.append(
                f"{wavelength:>10g} {self.reflectance[i]:>12.5f} {self.transmittance[i]:>14.5f} "
                f"{self.absorptance[i]:>12.5f}   [{r_int[i, 0]:.5f}, {r_int[i, 1]:.5f}]; "
                f"[{t_int[i, 0]:.5f}, {t_int[i, 1]:.5f}]" + (f"  N = {int(rays[i]):,}" if varies else ""))
        mixed = ((0 < self.specular_reflected) & (self.specular_reflected < self.reflected)) | (
            (0 < self.regular_transmitted) & (self.regular_transmitted < self.transmitted))
        if np.any(mixed):  # a specimen with both mirror and scattered light: show the parts
            lines.append(f"{'lambda/nm':>10} {'specular R':>12} {'diffuse R':>14} {'regular T':>12} {'diffuse T':>12}")
            for i, wavelength in enumerate(self.wavelengths):
                lines.append(f"{wavelength:>10g} " + " ".join(
                    f"{getattr(self, part)[i]:>{width}.5f}" for part, width in zip(_PARTS, (12, 14, 12, 12))))
        return lines

    # -- plain data, datasets and files ------------------------------------------------

    def as_dict(self) -> dict[str, Any]:
        """
        Every field by name as plain data (JSON-ready; NaN as ``None``): counts, estimates,
        parts, intervals, the certificate, the pilot, settings, geometry and provenance.
        Arrays are nested lists over :attr:`dims`. :meth:`from_dict` reads it back.
        """

        plain = plain_data
        return {
            "format": self.FORMAT,
            **self._labels_as_dict(),
            **{name: plain(values) for name, values in self.counts.as_dict().items()},
            **{name: plain(self.quantity(name)) for name in QUANTITIES},
            **{name: plain(getattr(self, name)) for name in _PARTS},
            **{f"{name}_interval": plain(getattr(self, f"{name}_interval")) for name in QUANTITIES},
            "interval_delta": self.interval_delta,
            "bound": self.bound,
            "certified_mu": plain(self.certified_mu),
            "rounding_bias": plain(self.rounding_bias),
            "backlit_fraction": plain(self.backlit_fraction),
            "rays_spent": plain(self.rays_spent),
            "pilot_rays": None if self.pilot is None else plain(self.pilot.rays),
            "pilot": None if self.pilot is None else {k: plain(v) for k, v in self.pilot.as_dict().items()},
            "seconds": self.seconds,
            "settings": {**asdict(self.settings), "wavelengths": list(self.settings.wavelengths)},
            "geometry": asdict(self.geometry),
            "scene": self.scene,
            "wavelength_independent": self.wavelength_independent,
            "version": self.version,
            **self._parameters_as_dict(),
        }

    @classmethod
    def _from_plain(cls, tag: str, data: Any) -> "Result":
        if hasattr(data, "data_vars"):  # a sweep's Zarr table (a dataset): its counts are its variables
            from virtspec_mi.results.zarr import as_plain

            data = as_plain(data)
        return cls.from_dict(data)

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> "Result":
        """The result of :meth:`as_dict` (checked by :meth:`from_dict <virtspec_mi.results.base.ResultBase.from_dict>`)."""

        def counts(source: Mapping[str, Any], group: str) -> Counts:
            # Results written before invalid directions were counted have none.
            if not isinstance(source, Mapping):
                raise ValueError(f"'{group}' must be an object of counts (got {type(source).__name__})")
            fields = {name: whole_counts(source[name], name) for name in Counts.names()
                      if name != "largest_weight" and (name != "invalid_directions" or name in source)}
            fields.setdefault("invalid_directions", np.zeros_like(fields["rays"]))
            return Counts(**fields, largest_weight=optional_numbers(source["largest_weight"], "largest_weight"))

        return cls(
            **cls.labels_from_dict(data),
            counts=counts(data, "counts"),
            pilot=None if data["pilot"] is None else counts(data["pilot"], "pilot"),
            settings=Settings(**field_value(data, "settings", "object")),
            geometry=InstrumentGeometry(**field_value(data, "geometry", "object")),
            seconds=float(field_value(data, "seconds", "seconds")),
            scene=field_value(data, "scene", "text"),
            wavelength_independent=bool(field_value(data, "wavelength_independent", "flag")),
            version=field_value(data, "version", "text"),
        )

    def _check_stored(self, data: Mapping[str, Any]) -> None:
        """
        The ``absorbed`` counts a JSON object holds (its own, and its pilot's) are the rest of the rays; the
        ``rays_spent`` it states are its rays and its pilot's, and the ``certified_mu`` it states the tolerance its
        counts give (:attr:`certified_mu`): a certificate edited against its counts is refused.
        """

        for group, counts, source in (("", self.counts, data), ("pilot", self.pilot, data.get("pilot"))):
            if counts is not None and isinstance(source, Mapping) and "absorbed" in source:
                stored = whole_counts(source["absorbed"], "absorbed")
                check_shapes({"absorbed": (self.dims, stored)}, self.sizes)
                check_counts(group, {**counts.as_dict(), "absorbed": stored}, _STORED, reading_at(self.dims, self.coords))
        if data.get("rays_spent") is not None:
            spent = whole_counts(data["rays_spent"], "rays_spent")
            check_shapes({"rays_spent": (self.dims, spent)}, self.sizes)
            agree_stored("rays_spent", spent, self.rays_spent, exact=True)
        if data.get("certified_mu") is not None:
            stated = optional_numbers(data["certified_mu"], "certified_mu")
            check_shapes({"certified_mu": (self.dims, stated)}, self.sizes)
            agree_stored("certified_mu", stated, self.certified_mu)

    def _count_groups(self) -> list[tuple[str, Mapping[str, np.ndarray], CountRules, tuple[str, ...]]]:
        groups = [("", self.counts.as_dict(), COUNT_RULES, self.dims)]
        if self.pilot is not None:
            groups.append(("pilot", self.pilot.as_dict(), COUNT_RULES, self.dims))
        return groups

    def _file_attrs(self) -> dict[str, Any]:
        """The settings, geometry and provenance as numbers and text (a NetCDF file's attributes)."""

        s = self.settings
        return {"mu": s.mu, "delta": s.delta, "bound": s.bound, "joint": int(s.joint), "beam": s.beam,
                "sampling": s.sampling, "seed": s.seed, "phi_i": s.phi_i, "interval_delta": self.interval_delta,
                **asdict(self.geometry), "seconds": self.seconds, "scene": self.scene,
                "wavelength_independent": int(self.wavelength_independent), "version": self.version,
                **({} if self.parameters is None else {"parameters": json.dumps(self.parameters)})}

    # -- spectra, colour and plots ------------------------------------------------------

    def _quantity(self, quantity: str) -> tuple[np.ndarray, np.ndarray, float]:
        return self.quantity(quantity), self.certified_mu, self.interval_delta

    def to_msds(self, theta_i: float | None = None) -> Any:
        """R, T and A at one θi as a ``colour.MultiSpectralDistributions``."""

        from virtspec_mi.colorimetry.cie import multi_spectral_distributions

        return multi_spectral_distributions(self, theta_i)


def fluctuation(a: Result | np.ndarray, b: Result | np.ndarray, quantity: str = "reflectance") -> float:
    """
    Average magnitude of the fluctuations between two sweeps, eq. (24):

        Δ = Σᵢ |ρᵢ^(N_j) − ρᵢ^(N_{j−1})| / n

    over the n readings of the sweeps (all their (wavelength, θi) pairs), for
    ``quantity`` (reflectance by default). ``a`` and ``b`` are results over the same grid
    (typically at successive ray densities N_{j−1} and N_j), or arrays of one shape.

    References
    ----------
    Baranoski et al. (2001), eq. (24), Fig. 6a.
    """

    if isinstance(a, Result) and isinstance(b, Result):
        for name in ("wavelengths", "theta_i"):
            if not np.array_equal(getattr(a, name), getattr(b, name)):
                raise ValueError(f"fluctuation needs sweeps over the same {name} (they differ)")
        a, b = a.quantity(quantity), b.quantity(quantity)
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.shape != b.shape or a.size == 0:
        raise ValueError(f"fluctuation needs two non-empty arrays of one shape (got {a.shape} and {b.shape})")
    return float(np.mean(np.abs(a - b)))
