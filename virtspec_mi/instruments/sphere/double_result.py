"""
Double-sphere results: reflectance and transmittance read at once, certified
============================================================================

:class:`DoubleSphereResult` holds the exact counts of the three configurations of a
double-sphere reading (:mod:`virtspec_mi.instruments.sphere.double`: ``sample``,
``standard``, ``open``) over labelled dims (``wavelength``; ``theta_i`` and specimen
parameters as a sphere result's) and derives from them:

- the **reflectance reading** M_R = ρ_std · p_R(sample) / p_R(standard) and the
  **transmittance reading** M_T = p_T(sample) / p_T(open) (p_R, p_T: the reflectance and
  the transmittance sphere's detector fractions);
- their **certified intervals**: each of the four fractions has a Clopper–Pearson
  interval at δ/4, so all four hold together with probability ≥ 1 − δ (union bound) and
  both readings' intervals (the extreme ratios) hold together;
- the **hemispherical R and T** of the same rays (the specimen's first interaction) and
  each reading's instrument error, reading − hemispherical.

A reading is not certified where a configuration has capped walks, invalid directions or
weight violations, or where no ray reached a detector in a reference configuration.

References
----------
Clopper & Pearson (1934); Baranoski et al. (2001), eqs. (2), (19); S. A. Prahl, *Inverse
Adding-Doubling* manual (M_R, M_T of a double sphere).
"""

from __future__ import annotations

import json
import warnings
from dataclasses import asdict
from functools import cached_property
from typing import Any, ClassVar, Mapping

import numpy as np

from virtspec_mi.base.version import __version__
from virtspec_mi.budgets.bounds import hoeffding_mu
from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.budgets.ratio import ratio_bounds
from virtspec_mi.instruments.sphere.geometry import Sphere, sphere_from_parameters
from virtspec_mi.instruments.sphere.result import Configured
from virtspec_mi.results.base import ResultBase, attribute, per_count, plain_data, round_up, span, stored
from virtspec_mi.results.figures import Figure, spectra
from virtspec_mi.results.integrity import CountRules, field_value, finite_labels, whole_counts
from virtspec_mi.results.variables import READINGS, Variable
from virtspec_mi.settings import Settings, share

__all__ = ["CONFIGURATIONS", "COUNT_RULES", "DoubleSphereResult"]

CONFIGURATIONS: tuple[str, ...] = ("sample", "standard", "open")
"""The three simulated configurations of every reading: the specimen, the standard, the empty position."""

_FATES = ("detected_r", "detected_t", "absorbed_wall", "absorbed_specimen", "absorbed_other", "capped",
          "invalid_directions")
_UNCERTIFIED = ("capped", "invalid_directions", "weight_violations")
COUNT_RULES = CountRules(
    "rays",
    parts={"hemispherical_reflected": "rays", "hemispherical_transmitted": "rays"},
    sums=(((*_FATES, "lost_*"), "rays", True),
          (("hemispherical_reflected", "hemispherical_transmitted"), "rays", False)),
)
"""A configuration's rays each end in one fate (either detector, absorbed, capped, invalid, or lost through a
port of either sphere); the first interaction's hemispheres hold at most its rays."""
_FRACTION_RULES = CountRules(None, fractions=("wall_reflectance", "transmittance_wall"))
_QUANTITIES = ("reflectance", "transmittance", "hemispherical_reflectance", "hemispherical_transmittance")


def _reading(name: str, formula: str) -> dict[str, Variable]:
    """A reading's variable and the two ends of its certified interval."""

    ends = {"lower": 0, "upper": 1}
    return {name: Variable("1", f"{name} reading: {formula}", lambda r: getattr(r, name), READINGS),
            **{f"{name}_{end}": Variable("1", f"{end} end of the {name} reading's certified interval",
                                         lambda r, k=k: getattr(r, f"{name}_interval")[..., k], READINGS)
               for end, k in ends.items()}}


class DoubleSphereResult(Configured, ResultBase):
    """
    Double-sphere readings over labelled dims (see the module docstring): one
    ``xarray.Dataset`` (:attr:`data`), every count over the readings' dims and
    ``configuration``, both walls' ρw over the readings' dims, both spheres, the options,
    settings and provenance in its attributes.

    Parameters
    ----------
    dims : tuple of str
        The readings' dims, e.g. ``("wavelength",)`` (``configuration`` is added).
    coords : dict
        Labels as for :class:`~virtspec_mi.instruments.sphere.result.SphereResult`.
    counts : dict
        Per configuration (``sample``, ``standard``, ``open``): every count by name, ``int64``
        over ``dims`` — ``rays``, ``detected_r``, ``detected_t``, the other fates, ``lost_<port>``
        (the transmittance sphere's ports as ``t_<name>``), the hemispherical counts of the
        first interaction and the walk's sums.
    wall_reflectance, transmittance_wall : ndarray
        ρw of the reflectance and of the transmittance sphere per reading.
    spheres : str
        Both spheres in words.
    options : dict
        How it was read (``standard``, ``specular``, ``max_bounces``).
    settings : Settings
        The settings used.
    seconds : float
        Time spent tracing.
    scene : str
        Fingerprint of the scene, or "".
    sphere_parameters, transmittance_parameters : dict
        Each sphere's description (:meth:`~virtspec_mi.instruments.sphere.geometry.Sphere.parameters`).
    specimen_radius : float or None
        Radius of the specimen disk (mm).
    version : str
        virtspec-mi version that made the result.
    parameters : dict or None
        Swept specimen parameters.
    source : dict or None
        The scene's name and ``-D`` defines.
    """

    CONFIGURATIONS: ClassVar[tuple[str, ...]] = CONFIGURATIONS
    FORMAT: ClassVar[str] = "virtspec-mi double sphere 1"
    KIND: ClassVar[str] = "double-sphere reading"
    KIND_DIMS: ClassVar[tuple[str, ...]] = ("configuration",)
    KIND_DIMS_REASON: ClassVar[str] = (
        "a reading is the ratio of two configurations; each one's counts are counts['sample'], counts['standard'] "
        "and counts['open'] (in to_dataset(): the dim configuration)")
    QUANTITIES: ClassVar[tuple[str, ...]] = _QUANTITIES
    _QUANTITY_NOTE: ClassVar[str] = "a double-sphere reading's quantities"
    VARIABLES: ClassVar[dict[str, tuple[str, str]]] = {
        "configuration": ("1", "configuration (the specimen, the standard, or the empty sample position)"),
        "detected_r": ("1", "rays that reached the reflectance sphere's detector"),
        "detected_t": ("1", "rays that reached the transmittance sphere's detector"),
        "absorbed_wall": ("1", "rays absorbed by either sphere's wall or baffle"),
        "absorbed_specimen": ("1", "rays absorbed by the disk in the sample position"),
        "absorbed_other": ("1", "rays absorbed by the transmittance sphere's standard"),
        "hemispherical_reflected": ("1", "rays the specimen reflected at its first interaction"),
        "hemispherical_transmitted": ("1", "rays the specimen transmitted at its first interaction"),
        "wall_reflections": ("1", "wall (and baffle) reflections in both spheres, summed over the rays"),
        "wall_reflectance": ("1", "reflectance of the reflectance sphere's wall"),
        "transmittance_wall": ("1", "reflectance of the transmittance sphere's wall"),
    }
    DERIVED: ClassVar[dict[str, Variable]] = {
        **_reading("reflectance", "standard * p_R(sample) / p_R(standard)"),
        **_reading("transmittance", "p_T(sample) / p_T(open)"),
        "hemispherical_reflectance": Variable("1", "hemispherical reflectance of the same rays",
                                              lambda r: r.hemispherical_reflectance, READINGS),
        "hemispherical_transmittance": Variable("1", "hemispherical transmittance of the same rays",
                                                lambda r: r.hemispherical_transmittance, READINGS),
    }
    FIGURES: ClassVar[dict[str, Figure]] = {"spectra": spectra(_QUANTITIES)}

    def __init__(self, dims: tuple[str, ...], coords: Mapping[str, Any], counts: dict[str, dict[str, Any]],
                 wall_reflectance: Any, transmittance_wall: Any, spheres: str, options: dict[str, Any],
                 settings: Settings, seconds: float = 0.0, scene: str = "", sphere_parameters: dict | None = None,
                 transmittance_parameters: dict | None = None, specimen_radius: float | None = None,
                 version: str = __version__, parameters: dict | None = None, source: dict | None = None) -> None:
        options = _checked_options(options)
        readings = tuple(d for d in dims if d != "configuration")
        if not counts:
            raise ValueError(f"'counts' must hold the counts of the configurations {', '.join(CONFIGURATIONS)} "
                             "(got none)")
        checked = {"wall_reflectance": (readings, wall_reflectance), "transmittance_wall": (readings, transmittance_wall)}
        arrays = {"wall_reflectance": (readings, wall_reflectance), "transmittance_wall": (readings, transmittance_wall),
                  **self._configured("counts", counts, readings, checked)}
        labels = {**coords, "configuration": np.array(CONFIGURATIONS, dtype=object)}
        attrs = {"spheres": spheres, "options": dict(options), "settings": settings, "seconds": float(seconds),
                 "scene": scene, "sphere_parameters": dict(sphere_parameters or {}),
                 "transmittance_parameters": dict(transmittance_parameters or {}),
                 "specimen_radius": specimen_radius, "version": version, "parameters": parameters, "source": source}
        self._store((*readings, "configuration"), labels, arrays, attrs, checked)

    wall_reflectance = stored("wall_reflectance", "ρw of the reflectance sphere per reading.")
    transmittance_wall = stored("transmittance_wall", "ρw of the transmittance sphere per reading.")
    spheres = attribute("spheres", "Both spheres in words.", str)
    options = attribute("options", "How it was read (``standard``, ``specular``, ``max_bounces``).")
    sphere_parameters = attribute("sphere_parameters", "The reflectance sphere's description.")
    transmittance_parameters = attribute("transmittance_parameters", "The transmittance sphere's description.")
    specimen_radius = attribute("specimen_radius", "Radius of the specimen disk (mm), or ``None``.")

    @property
    def sphere_description(self) -> Sphere:
        """The reflectance sphere (:class:`~virtspec_mi.instruments.sphere.geometry.Sphere`)."""

        return sphere_from_parameters(self.sphere_parameters)

    @property
    def transmittance_description(self) -> Sphere:
        """The transmittance sphere."""

        return sphere_from_parameters(self.transmittance_parameters)

    @property
    def fraction_delta(self) -> float:
        """δ/4: the failure probability of each detector fraction's interval."""

        return self.delta / 4.0

    @cached_property
    def _intervals(self) -> dict[str, np.ndarray]:
        def interval(configuration: str, name: str, delta: float) -> np.ndarray:
            counts = self.counts[configuration]
            return np.stack(clopper_pearson(counts[name], counts["rays"], delta), axis=-1)

        out = {f"{name}_{c}": interval(c, name, self.fraction_delta)
               for name, configurations in (("detected_r", ("sample", "standard")),
                                            ("detected_t", ("sample", "open"))) for c in configurations}
        out["hemispherical_reflectance"] = interval("sample", "hemispherical_reflected", self.delta)
        out["hemispherical_transmittance"] = interval("sample", "hemispherical_transmitted", self.delta)
        return out

    def fraction_interval(self, name: str, configuration: str) -> np.ndarray:
        """The Clopper–Pearson interval (…, 2) at δ/4 of ``detected_r`` (sample, standard) or ``detected_t``
        (sample, open)."""

        return self._intervals[f"{name}_{configuration}"]

    @property
    def certified(self) -> np.ndarray:
        """False where a configuration has capped walks, invalid directions or weight violations, or where no ray
        reached a detector in its reference configuration."""

        bad = sum(self.counts[c][n] for c in CONFIGURATIONS for n in _UNCERTIFIED)
        return np.asarray((bad == 0) & (self.counts["standard"]["detected_r"] > 0)
                          & (self.counts["open"]["detected_t"] > 0))

    @property
    def fraction_mu(self) -> np.ndarray:
        """Tolerance each detector fraction is certified to at δ/4 (Hoeffding's μ of the N spent; NaN where not
        certified)."""

        mu = np.maximum.reduce([per_count(self.counts[c]["rays"], lambda n: hoeffding_mu(n, self.fraction_delta))
                                for c in CONFIGURATIONS])
        return np.where(self.certified, mu, np.nan)

    def _ratio(self, name: str, reference: str, scale: float) -> tuple[np.ndarray, np.ndarray]:
        with np.errstate(divide="ignore", invalid="ignore"):
            value = scale * self.fraction(name, "sample") / self.fraction(name, reference)
        interval = ratio_bounds(self.fraction_interval(name, "sample"), self.fraction_interval(name, reference), scale)
        return value, np.where(self.certified[..., None], interval, np.nan)

    @property
    def reflectance(self) -> np.ndarray:
        """M_R = ρ_std · p_R(sample) / p_R(standard)."""

        return self._ratio("detected_r", "standard", float(self.options["standard"]))[0]

    @property
    def reflectance_interval(self) -> np.ndarray:
        """M_R's certified interval (…, 2): with M_T's, it holds with probability ≥ 1 − δ (NaN where uncertified)."""

        return self._ratio("detected_r", "standard", float(self.options["standard"]))[1]

    @property
    def transmittance(self) -> np.ndarray:
        """M_T = p_T(sample) / p_T(open)."""

        return self._ratio("detected_t", "open", 1.0)[0]

    @property
    def transmittance_interval(self) -> np.ndarray:
        """M_T's certified interval (…, 2): with M_R's, it holds with probability ≥ 1 − δ."""

        return self._ratio("detected_t", "open", 1.0)[1]

    @property
    def hemispherical_reflectance(self) -> np.ndarray:
        """The hemispherical reflectance of the same rays (the specimen's first interaction)."""

        return self.fraction("hemispherical_reflected")

    @property
    def hemispherical_transmittance(self) -> np.ndarray:
        """The hemispherical transmittance of the same rays."""

        return self.fraction("hemispherical_transmitted")

    @property
    def reflectance_error(self) -> np.ndarray:
        """M_R − hemispherical reflectance."""

        return self.reflectance - self.hemispherical_reflectance

    @property
    def transmittance_error(self) -> np.ndarray:
        """M_T − hemispherical transmittance."""

        return self.transmittance - self.hemispherical_transmittance

    def _quantity(self, quantity: str) -> tuple[np.ndarray, np.ndarray, float]:
        if quantity in ("reflectance", "transmittance"):
            values = getattr(self, quantity)
            interval = getattr(self, f"{quantity}_interval")
        else:
            values = getattr(self, quantity)
            interval = np.where(self.certified[..., None], self._intervals[quantity], np.nan)
        return values, np.maximum(values - interval[..., 0], interval[..., 1] - values), self.delta

    def spectrum_measures(self, quantity: str | None = None) -> str:
        """``reflectance`` or ``transmittance``."""

        return "transmittance" if "transmittance" in self.check_quantity(quantity) else "reflectance"

    def rendered(self) -> np.ndarray:
        """What ``mi.render`` returns: per wavelength M_R, M_T and the hemispherical R and T of the same rays."""

        reading = self.squeeze()
        return np.stack([reading.reflectance, reading.transmittance, reading.hemispherical_reflectance,
                         reading.hemispherical_transmittance], axis=1).astype(np.float32)

    def warn_if_uncertified(self, stacklevel: int = 2) -> None:
        """A ``RuntimeWarning`` where no ray reached a detector in its reference configuration."""

        dark = (self.counts["standard"]["detected_r"] == 0) | (self.counts["open"]["detected_t"] == 0)
        if np.any(dark):
            warnings.warn(f"not certified: in {int(np.sum(dark))} of {dark.size} readings no ray reached a detector "
                          "with the standard or the empty position (the reading is undefined there); trace more rays",
                          RuntimeWarning, stacklevel=stacklevel + 1)

    def summary(self) -> str:
        """A table: each reading's labels, both readings with their intervals, the hemispherical R and T."""

        mu = self.fraction_mu
        lines = [f"double integrating sphere, standard = {float(self.options['standard']):g}; {self.spheres}",
                 f"N = {span(self.rays)} rays per configuration and reading; "
                 + (f"each of the 4 detector fractions certified to {round_up(float(np.nanmax(mu))):g} at delta/4 = "
                    f"{self.fraction_delta:g} (both readings' intervals at once: probability >= {1 - self.delta:g})"
                    if np.any(self.certified) else "NOT CERTIFIED")
                 + f"; {self.seconds * 1e3:.1f} ms"]
        labels = list(self.reading_dims)
        lines.append(" ".join(f"{'lambda/nm' if d == 'wavelength' else d:>10}" for d in labels)
                     + "   M_R  [interval]                R_hemi     M_T  [interval]                T_hemi")
        r_int, t_int, certified = self.reflectance_interval, self.transmittance_interval, self.certified
        for index in np.ndindex(*(self.sizes[d] for d in labels)):
            at = " ".join(f"{float(np.atleast_1d(self.coords[d])[k]):>10g}" for d, k in zip(labels, index))
            lines.append(f"{at}   {self.reflectance[index]:.5f} [{r_int[index][0]:.5f}, {r_int[index][1]:.5f}]  "
                         f"{self.hemispherical_reflectance[index]:.5f}   {self.transmittance[index]:.5f} "
                         f"[{t_int[index][0]:.5f}, {t_int[index][1]:.5f}]  "
                         f"{self.hemispherical_transmittance[index]:.5f}"
                         + ("" if certified[index] else "  NOT CERTIFIED"))
        return "\n".join(lines)

    def __repr__(self) -> str:
        sizes = ", ".join(f"{d}: {n}" for d, n in self.sizes.items())
        return f"<DoubleSphereResult ({sizes}) N = {span(self.rays)}>"

    def as_dict(self) -> dict[str, Any]:
        """Every field as plain data (JSON-ready), and the readings with their intervals."""

        return {
            "format": self.FORMAT, **self._labels_as_dict(), **self._parameters_as_dict(),
            "counts": {c: {name: plain_data(v) for name, v in named.items()} for c, named in self.counts.items()},
            "wall_reflectance": plain_data(self.wall_reflectance),
            "transmittance_wall": plain_data(self.transmittance_wall),
            "spheres": self.spheres, "options": dict(self.options),
            "settings": {**asdict(self.settings), "wavelengths": list(self.settings.wavelengths)},
            "seconds": self.seconds, "scene": self.scene, "sphere_parameters": self.sphere_parameters,
            "transmittance_parameters": self.transmittance_parameters, "specimen_radius": self.specimen_radius,
            "version": self.version,
            "reflectance": plain_data(self.reflectance), "reflectance_interval": plain_data(self.reflectance_interval),
            "transmittance": plain_data(self.transmittance),
            "transmittance_interval": plain_data(self.transmittance_interval),
            "hemispherical_reflectance": plain_data(self.hemispherical_reflectance),
            "hemispherical_transmittance": plain_data(self.hemispherical_transmittance),
        }

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> "DoubleSphereResult":
        source = data["counts"]
        if not isinstance(source, Mapping) or set(source) != set(CONFIGURATIONS):
            raise ValueError(f"'counts' must hold the counts of the configurations {', '.join(CONFIGURATIONS)}")
        counts = {c: {str(name): whole_counts(values, f"counts[{c!r}] '{name}'")
                      for name, values in source[c].items()} for c in CONFIGURATIONS}
        return cls(
            **cls.labels_from_dict(data), counts=counts,
            wall_reflectance=finite_labels(data["wall_reflectance"], "wall_reflectance"),
            transmittance_wall=finite_labels(data["transmittance_wall"], "transmittance_wall"),
            spheres=field_value(data, "spheres", "text"), options=field_value(data, "options", "object"),
            settings=Settings(**field_value(data, "settings", "object")),
            seconds=float(field_value(data, "seconds", "seconds")), scene=field_value(data, "scene", "text"),
            sphere_parameters=dict(data.get("sphere_parameters") or {}),
            transmittance_parameters=dict(data.get("transmittance_parameters") or {}),
            specimen_radius=data.get("specimen_radius"), version=field_value(data, "version", "text"))

    def _count_groups(self) -> list[tuple[str, Mapping[str, np.ndarray], CountRules, tuple[str, ...]]]:
        groups = [(f"counts[{c!r}]", self.counts[c], COUNT_RULES, self.reading_dims) for c in CONFIGURATIONS]
        return [*groups, ("", {"wall_reflectance": self.wall_reflectance,
                               "transmittance_wall": self.transmittance_wall}, _FRACTION_RULES, self.reading_dims)]

    def _file_attrs(self) -> dict[str, Any]:
        s = self.settings
        return {"spheres": self.spheres, "standard": float(self.options.get("standard", 0.99)),
                "specular": str(self.options.get("specular", "SCI")),
                "max_bounces": int(self.options.get("max_bounces", 0)), "mu": s.mu, "delta": s.delta, "beam": s.beam,
                "seed": s.seed, "phi_i": s.phi_i, "seconds": self.seconds, "scene": self.scene,
                "version": self.version, **({} if self.parameters is None else
                                            {"parameters": json.dumps(self.parameters)})}

    def described(self) -> dict[str, tuple[str, str]]:
        """The kind's table and each port's ``lost_<port>`` count."""

        ports = {name: ("1", f"rays lost through port {name[5:]!r}") for name in self.counts["sample"]
                 if name.startswith("lost_")}
        return {**super().described(), **ports}


def _checked_options(options: Any) -> dict[str, Any]:
    """How a reading was taken, held to its rules: 0 < standard <= 1."""

    if not isinstance(options, Mapping):
        raise ValueError(f"'options' must be an object (got {type(options).__name__})")
    options = dict(options)
    options["standard"] = share("options.standard")(options.get("standard", 0.99))
    return options
