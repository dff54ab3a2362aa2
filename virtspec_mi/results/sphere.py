"""
Sphere results: sample over standard, certified, beside the hemispherical reading
================================================================================

:class:`SphereResult` holds the exact counts of both configurations of an integrating
sphere reading (:mod:`virtspec_mi.instruments.sphere`) over wavelength and derives
everything from them once.

The reading is R = ρ_std · p_sample / p_standard (p: detector fractions, each m/N of
its own N rays, the same seed in both configurations). **Certificate:** each detector
fraction gets a Clopper–Pearson interval at δ/2, so both hold together with probability
≥ 1 − δ by the union bound (whatever the dependence between the configurations); the
ratio's interval is then [ρ_std·p_s⁻/p_r⁺, ρ_std·p_s⁺/p_r⁻] (the extreme combinations).
The hemispherical reading (the first specimen interaction's hemisphere) comes from the
sample configuration's very rays; the instrument error is reading − hemispherical.

**Correction:** :meth:`SphereResult.corrected` / :meth:`SphereResult.corrected_interval`
invert the sphere theory's readout model (:mod:`virtspec_mi.references.sphere_theory` with
the inputs of :func:`virtspec_mi.references.sphere_model.theory_inputs`, from the sphere
description the result keeps) to recover the hemispherical value from the reading.

References
----------
Baranoski et al. (2001), eqs. (2), (19), (23); Clopper & Pearson (1934); Goebel (1967).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from virtspec_mi.budgets.bounds import hoeffding_mu
from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.geometry.sphere import sphere_from_parameters
from virtspec_mi.references.sphere_model import correct_readings, theory_inputs

__all__ = ["CONFIGURATIONS", "SphereResult"]

CONFIGURATIONS: tuple[str, ...] = ("sample", "standard")
"""The two simulated configurations of every reading."""


@dataclass
class SphereResult:
    """
    Sphere readings over wavelength: the exact counts of both configurations and
    everything derived from them (see the module docstring).
    """

    wavelengths: np.ndarray
    rays: int
    counts: dict[str, dict[str, np.ndarray]]
    sphere: str
    cap_fractions: dict[str, float]
    wall_reflectance: np.ndarray
    options: dict[str, Any]
    settings: dict[str, Any]
    seconds: float = 0.0
    scene: str = ""
    sphere_parameters: dict[str, Any] = field(default_factory=dict)
    specimen_radius: float | None = None
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    # -- counts and fractions ---------------------------------------------------------

    def fraction(self, name: str, configuration: str = "sample") -> np.ndarray:
        """A count of ``configuration`` over its rays (e.g. ``fraction("lost_entrance")``)."""

        return self.counts[configuration][name] / self.rays

    @property
    def detector_fraction(self) -> np.ndarray:
        """p_sample: the detected fraction with the sample."""

        return self.fraction("detected", "sample")

    @property
    def standard_fraction(self) -> np.ndarray:
        """p_standard: the detected fraction with the reference standard (or the open port)."""

        return self.fraction("detected", "standard")

    @property
    def fraction_delta(self) -> float:
        """δ/2: the failure probability of each detector fraction's interval."""

        return float(self.settings["delta"]) / 2.0

    def fraction_interval(self, configuration: str = "sample") -> np.ndarray:
        """Clopper–Pearson interval (n, 2) of a configuration's detector fraction at δ/2."""

        lower, upper = clopper_pearson(self.counts[configuration]["detected"], self.rays, self.fraction_delta)
        return np.stack([lower, upper], axis=-1)

    @property
    def certified(self) -> np.ndarray:
        """False where either configuration has capped walks, invalid directions or weight violations."""

        bad = sum(self.counts[c][n] for c in CONFIGURATIONS for n in ("capped", "invalid_directions",
                                                                       "weight_violations"))
        return np.asarray(bad == 0)

    @property
    def fraction_mu(self) -> np.ndarray:
        """
        Tolerance each detector fraction is certified to at δ/2: μ when its N was sized by
        the rule at (μ, δ/2), else what the N spent guarantee under eq. (19) (Hoeffding's μ,
        which holds for every N); NaN where not certified.
        """

        if self.settings.get("rays") is None:
            mu = float(self.settings["mu"])
        else:
            mu = hoeffding_mu(self.rays, self.fraction_delta)
        return np.where(self.certified, mu, np.nan)

    # -- the readout ------------------------------------------------------------------

    @property
    def standard_value(self) -> float:
        """ρ_std (reflectance) or 1 (transmittance: the open port)."""

        return 1.0 if self.options["measurement"] == "transmittance" else float(self.options["standard"])

    @property
    def reading(self) -> np.ndarray:
        """The instrument's reading: standard value · p_sample / p_standard."""

        with np.errstate(divide="ignore", invalid="ignore"):
            return self.standard_value * self.detector_fraction / self.standard_fraction

    @property
    def reading_interval(self) -> np.ndarray:
        """[ρ_std·p_s⁻/p_r⁺, ρ_std·p_s⁺/p_r⁻] (n, 2): holds with probability ≥ 1 − δ; NaN if not certified."""

        sample, standard = self.fraction_interval("sample"), self.fraction_interval("standard")
        with np.errstate(divide="ignore", invalid="ignore"):
            out = self.standard_value * np.stack([sample[:, 0] / standard[:, 1], sample[:, 1] / standard[:, 0]],
                                                 axis=-1)
        out[~self.certified] = np.nan
        return out

    @property
    def hemispherical(self) -> np.ndarray:
        """The hemispherical reading of the same rays (reflectance, or transmittance)."""

        name = "hemispherical_transmitted" if self.options["measurement"] == "transmittance" \
            else "hemispherical_reflected"
        return self.fraction(name, "sample")

    @property
    def hemispherical_interval(self) -> np.ndarray:
        """Clopper–Pearson interval of the hemispherical reading at δ."""

        name = "hemispherical_transmitted" if self.options["measurement"] == "transmittance" \
            else "hemispherical_reflected"
        lower, upper = clopper_pearson(self.counts["sample"][name], self.rays, float(self.settings["delta"]))
        return np.stack([lower, upper], axis=-1)

    @property
    def hemispherical_diffuse(self) -> np.ndarray:
        """
        The hemispherical reflectance without its specular part (rays reflected by a delta
        event, e.g. a smooth surface): what an SCE reading aims at. Equal to
        :attr:`hemispherical` for transmittance and for specimens without delta lobes.
        """

        if self.options["measurement"] == "transmittance":
            return self.hemispherical
        return self.hemispherical - self.fraction("hemispherical_specular", "sample")

    @property
    def instrument_error(self) -> np.ndarray:
        """reading − hemispherical: what the sphere adds to the specimen's own value."""

        return self.reading - self.hemispherical

    # -- the correction (the theory's inverse of the readout) --------------------------

    @property
    def sphere_description(self) -> Sphere:
        """The :class:`~virtspec_mi.geometry.sphere.Sphere` this result was read with."""

        if not self.sphere_parameters:
            raise ValueError("this sphere result carries no sphere description (sphere_parameters is empty: "
                             "written by an older version); read the specimen again")
        return sphere_from_parameters(self.sphere_parameters)

    def theory_inputs(self) -> dict[str, Any]:
        """
        The :mod:`virtspec_mi.references.sphere_theory` keywords of this reading
        (:func:`virtspec_mi.references.sphere_model.theory_inputs` of its sphere, mode and specimen radius).
        """

        mode = SimpleNamespace(**self.options)  # the reading mode's plain values (references.sphere_model.ReadingMode)
        return theory_inputs(self.sphere_description, mode, self.wavelengths, self.specimen_radius)

    def corrected(self, *, specular_reflectance: Any = 0.0, sample_reflectance: Any = None,
                  collimated_transmittance: Any = 0.0) -> np.ndarray:
        """
        The hemispherical value recovered from :attr:`reading` by the sphere theory's
        inverse (:func:`virtspec_mi.references.sphere_model.correct_readings`; keywords there): what
        a user computes from an instrument's reading and its sphere's description. It
        assumes the theory's sphere (flat disks, no baffle) and a Lambertian specimen
        (unless ``sample_reflectance``, its reflectance for diffuse light, is given; required
        for transmittance); the difference from :attr:`hemispherical` is the model's
        residual for this specimen.
        """

        return correct_readings(self.reading, self.theory_inputs(), specular_reflectance=specular_reflectance,
                                sample_reflectance=sample_reflectance,
                                collimated_transmittance=collimated_transmittance)

    def corrected_interval(self, *, specular_reflectance: Any = 0.0, sample_reflectance: Any = None,
                           collimated_transmittance: Any = 0.0) -> np.ndarray:
        """
        :attr:`reading_interval` through the (increasing) correction, (n, 2): holds the
        corrected value of the expected reading with probability ≥ 1 − δ (NaN where not
        certified).
        """

        return correct_readings(self.reading_interval, self.theory_inputs(),
                                specular_reflectance=specular_reflectance, sample_reflectance=sample_reflectance,
                                collimated_transmittance=collimated_transmittance)

    @property
    def wall_reflections_per_ray(self) -> np.ndarray:
        """Mean wall (and baffle) reflections per ray, sample configuration."""

        return self.counts["sample"]["wall_reflections"] / self.rays

    # -- output -----------------------------------------------------------------------

    def summary(self) -> str:
        """A table: wavelength, detector fractions, reading with its interval, hemispherical, error."""

        options = self.options
        kind = "transmittance" if options["measurement"] == "transmittance" else f"reflectance ({options['specular']})"
        mu = self.fraction_mu
        lines = [f"integrating sphere {kind}, method = {options['method']}, standard = {self.standard_value:g}; "
                 f"{self.sphere}",
                 f"N = {self.rays:,} rays per configuration and wavelength; "
                 + (f"each detector fraction certified to {_up(float(np.nanmax(mu)))} at delta/2 = "
                    f"{self.fraction_delta:g} (reading interval: both at once, probability >= "
                    f"{1 - float(self.settings['delta']):g})" if np.any(self.certified) else
                    "NOT CERTIFIED (capped walks, invalid directions or weight violations)")
                 + f"; {self.seconds * 1e3:.1f} ms",
                 " lambda/nm  rho_w   p_sample  p_standard   reading  [interval]            hemispherical    error"]
        interval = self.reading_interval
        for k, lam in enumerate(self.wavelengths):
            certified = "" if self.certified[k] else "  NOT CERTIFIED"
            lines.append(f"{lam:10g}  {self.wall_reflectance[k]:.4f}  {self.detector_fraction[k]:.5f}  "
                         f"{self.standard_fraction[k]:.5f}    {self.reading[k]:.5f}  [{interval[k, 0]:.5f}, "
                         f"{interval[k, 1]:.5f}]  {self.hemispherical[k]:.5f}     {self.instrument_error[k]:+.5f}"
                         f"{certified}")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"<SphereResult {len(self.wavelengths)} wavelengths, N = {self.rays:,}, {self.options['measurement']}>"

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: counts of both configurations, derived values, options, settings."""

        def plain(value: Any) -> Any:
            if isinstance(value, np.ndarray):
                return plain(value.tolist())
            if isinstance(value, dict):
                return {k: plain(v) for k, v in value.items()}
            if isinstance(value, (list, tuple)):
                return [plain(v) for v in value]
            if isinstance(value, float) and not math.isfinite(value):
                return None  # NaN (not certified, 0/0): null in JSON
            return value

        return plain({
            "kind": "sphere_result", "wavelengths": self.wavelengths, "rays": self.rays, "counts": self.counts,
            "sphere": self.sphere, "cap_fractions": self.cap_fractions, "wall_reflectance": self.wall_reflectance,
            "options": self.options, "settings": self.settings, "seconds": self.seconds, "scene": self.scene,
            "sphere_parameters": self.sphere_parameters, "specimen_radius": self.specimen_radius,
            "reading": self.reading, "reading_interval": self.reading_interval.T,
            "hemispherical": self.hemispherical, "instrument_error": self.instrument_error,
            "fraction_mu": self.fraction_mu,
        })

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "SphereResult":
        if data.get("kind") != "sphere_result":
            raise ValueError("not a sphere result (its 'kind' is not 'sphere_result')")
        counts = {c: {k: np.asarray(v, dtype=np.int64) for k, v in d.items()} for c, d in data["counts"].items()}
        settings = dict(data["settings"])
        return cls(np.asarray(data["wavelengths"], float), int(data["rays"]), counts, data["sphere"],
                   dict(data["cap_fractions"]), np.asarray(data["wall_reflectance"], float), dict(data["options"]),
                   settings, float(data["seconds"]), data.get("scene", ""), dict(data.get("sphere_parameters") or {}),
                   data.get("specimen_radius"))

    def to_dataset(self) -> Any:
        """An ``xarray.Dataset`` over ``wavelength``: every count (``<configuration>_<name>``) and derived value."""

        import xarray as xr

        coords = {"wavelength": ("wavelength", self.wavelengths, {"units": "nm"})}
        data = {f"{c}_{k}": ("wavelength", v) for c, d in self.counts.items() for k, v in d.items()}
        data.update({
            "wall_reflectance": ("wavelength", self.wall_reflectance),
            "reading": ("wavelength", self.reading),
            "reading_lower": ("wavelength", self.reading_interval[:, 0]),
            "reading_upper": ("wavelength", self.reading_interval[:, 1]),
            "hemispherical": ("wavelength", self.hemispherical),
            "instrument_error": ("wavelength", self.instrument_error),
            "fraction_mu": ("wavelength", self.fraction_mu),
        })
        attrs = {"rays": self.rays, "sphere": self.sphere, "scene": self.scene, "seconds": self.seconds,
                 "json": json.dumps({k: v for k, v in self.as_dict().items() if k in (
                     "cap_fractions", "options", "settings", "sphere_parameters", "specimen_radius")})}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    def write(self, path: str | os.PathLike) -> Path:
        """Write to ``.json`` (everything) or ``.nc`` (:meth:`to_dataset`)."""

        path = Path(path)
        if path.suffix == ".json":
            path.write_text(json.dumps(self.as_dict(), indent=1))
        elif path.suffix == ".nc":
            self.to_dataset().to_netcdf(path)
        else:
            raise ValueError(f"path must end in .json or .nc (got {path.name!r})")
        return path

    @classmethod
    def read(cls, path: str | os.PathLike) -> "SphereResult":
        """A result written by :meth:`write`."""

        path = Path(path)
        if path.suffix == ".json":
            return cls.from_dict(json.loads(path.read_text()))
        if path.suffix == ".nc":
            import xarray as xr

            with xr.open_dataset(path) as ds:
                extra = json.loads(ds.attrs["json"])
                counts: dict[str, dict[str, np.ndarray]] = {c: {} for c in CONFIGURATIONS}
                for name in ds.data_vars:
                    config, _, key = str(name).partition("_")
                    if config in counts:
                        counts[config][key] = ds[name].values.astype(np.int64)
                return cls(ds["wavelength"].values, int(ds.attrs["rays"]), counts, ds.attrs["sphere"],
                           extra["cap_fractions"], ds["wall_reflectance"].values, extra["options"],
                           extra["settings"], float(ds.attrs["seconds"]), ds.attrs["scene"],
                           dict(extra.get("sphere_parameters") or {}), extra.get("specimen_radius"))
        raise ValueError(f"path must end in .json or .nc (got {path.name!r})")


def _up(value: float, digits: int = 3) -> str:
    """Rounded up to ``digits`` significant digits (a printed tolerance never understates)."""

    if not math.isfinite(value) or value <= 0:
        return str(value)
    scale = 10 ** (digits - 1 - math.floor(math.log10(value)))
    return f"{math.ceil(value * scale) / scale:g}"
