"""
Sphere results: sample over standard, certified, beside the hemispherical reading
=================================================================================

:class:`SphereResult` holds the exact counts of both configurations of an integrating
sphere reading (:mod:`virtspec_mi.instruments.sphere`) over labelled dims — ``wavelength``
and, as for a hemispherical sweep, ``theta_i`` and specimen parameters — and derives
everything from them once. Each configuration's rays are counted per reading
(``counts[configuration]["rays"]``): the two configurations, and the readings, may
trace different N (a budget sized per configuration, e.g. two-stage).

The reading is R = ρ_std · p_sample / p_standard (p: detector fractions, each m/N of
its own N rays, the same seed in both configurations). **Certificate:** each detector
fraction gets a Clopper–Pearson interval at δ/2, so both hold together with probability
≥ 1 − δ by the union bound (whatever the dependence between the configurations); the
ratio's interval is then [ρ_std·p_s⁻/p_r⁺, ρ_std·p_s⁺/p_r⁻] (the extreme combinations).
The hemispherical reading (the first specimen interaction's hemisphere) comes from the
sample configuration's very rays; the instrument error is reading − hemispherical.

**Correction:** :meth:`SphereResult.corrected` / :meth:`SphereResult.corrected_interval`
invert the sphere theory's readout model (:mod:`virtspec_mi.instruments.sphere.theory` with
the inputs of :func:`virtspec_mi.instruments.sphere.model.theory_inputs`, from the sphere
description the result keeps) to recover the hemispherical value from the reading.

It is a result like the others (:class:`~virtspec_mi.results.base.ResultBase`): ``sel`` /
``isel``, ``summary``, ``as_dict`` (format ``"virtspec-mi sphere 1"``), ``to_dataset``
(the counts over the reading's dims and ``configuration``), ``write`` / ``read``
(NetCDF, CSV, JSON, Zarr; files of the former ``"kind": "sphere_result"`` layout read
too), spectra of ``reading``, ``corrected`` or ``hemispherical`` (``spectrum``, ``to_sd``,
``colour``, :func:`virtspec_mi.applications.comparison.compare`) and :meth:`SphereResult.plot`.

References
----------
Baranoski et al. (2001), eqs. (2), (19), (23); Clopper & Pearson (1934); Goebel (1967).
"""

from __future__ import annotations

import json
from dataclasses import asdict
from functools import cached_property
from types import SimpleNamespace
from typing import Any, ClassVar, Mapping

import numpy as np

from virtspec_mi.base.version import __version__
from virtspec_mi.budgets.bounds import hoeffding_mu
from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.budgets.ratio import half_width, ratio_bounds
from virtspec_mi.base.checks import number
from virtspec_mi.budgets.scores import score_interval
from virtspec_mi.instruments.sphere.geometry import Sphere, sphere_from_parameters
from virtspec_mi.instruments.sphere.model import correct_readings, theory_inputs
from virtspec_mi.results.base import ResultBase, attribute, per_count, plain_data, round_up, span, stored
from virtspec_mi.results.integrity import CountRules, field_value, finite_labels, whole_counts
from virtspec_mi.results.figures import Figure, spectra
from virtspec_mi.results.readings import COUNT_RULES as FATE_RULES
from virtspec_mi.results.variables import READINGS, Variable, bounds
from virtspec_mi.instruments.sphere.walk import FATES
from virtspec_mi.instruments.sphere.expected import ROUNDING_BIAS, SCORE_SCALE, SCORE_SUMS, SMALLEST_WEIGHT
from virtspec_mi.settings import Settings, share

__all__ = ["CONFIGURATIONS", "COUNT_RULES", "Configured", "SphereResult"]

CONFIGURATIONS: tuple[str, ...] = ("sample", "standard")
"""The two simulated configurations of every reading."""

_UNCERTIFIED = ("capped", "invalid_directions", "weight_violations")

COUNT_RULES = CountRules(
    "rays",
    parts={"hemispherical_reflected": "rays", "hemispherical_transmitted": "rays",
           "hemispherical_specular": "hemispherical_reflected", "detected_from_upper": "detected"},
    sums=(((*FATES, "lost_*"), "rays", True),
          (("hemispherical_reflected", "hemispherical_transmitted"), "rays", False)),
)
"""How a configuration's counts add up per reading: its rays each end in one fate (detected, absorbed by the
wall, the specimen or another holder, capped, invalid, or lost through a port), and the first interaction's
hemispheres hold at most its rays. Sums over the walk (``wall_reflections``, ``weight_violations``,
``rounded_weights``) may exceed the rays."""

_FRACTION_RULES = CountRules(None, fractions=("wall_reflectance",))


class Configured:
    """
    Counts kept per configuration of a sphere reading (:attr:`CONFIGURATIONS`, in order),
    over the readings' dims and ``configuration``: the constructor's check and layout of
    them (:meth:`_configured`), and :attr:`counts`, :attr:`rays` and :meth:`fraction`.
    The single sphere's result and the double sphere's share it.
    """

    CONFIGURATIONS: ClassVar[tuple[str, ...]]
    """The configurations of a reading, in the order of the ``configuration`` dim."""

    @classmethod
    def _configured(cls, prefix: str, groups: Mapping[str, Mapping[str, Any]], readings: tuple[str, ...],
                    checked: dict[str, Any]) -> dict[str, Any]:
        """
        ``groups`` (configuration → name → counts; ``prefix`` names them: ``counts``,
        ``pilot``) added to ``checked`` and laid out as arrays over the readings' dims and
        ``configuration`` (``pilot_…`` for the pilot's); every configuration counts the same names.
        """

        configurations = cls.CONFIGURATIONS
        for configuration, named in groups.items():
            checked.update({f"{prefix}.{configuration}.{name}": (readings, values) for name, values in named.items()})
        if groups and set(groups) != set(configurations):
            raise ValueError(f"'{prefix}' must hold the counts of the configurations {', '.join(configurations)} "
                             f"(got {sorted(groups)})")
        names = list(groups.get(configurations[0], {}))
        for configuration in configurations[1:] if groups else ():
            if set(groups[configuration]) != set(names):
                raise ValueError(f"{prefix}[{configuration!r}] must count what {prefix}[{configurations[0]!r}] counts "
                                 f"({sorted(set(groups[configuration]) ^ set(names))} in only one)")
        return {("" if prefix == "counts" else f"{prefix}_") + name: (
            (*readings, "configuration"), np.stack([np.asarray(groups[c][name]) for c in configurations], axis=-1))
            for name in names}

    def _groups(self, prefix: str) -> dict[str, dict[str, np.ndarray]]:
        data = self.data  # type: ignore[attr-defined]
        names = [str(n) for n in data.data_vars if "configuration" in data.variables[n].dims]
        names = [n[len(prefix):] for n in names if n.startswith(prefix) and (prefix or not n.startswith("pilot_"))]
        axis = self.dims.index("configuration")  # type: ignore[attr-defined]
        return {c: {name: np.take(data.variables[prefix + name].values, k, axis=axis) for name in names}
                for k, c in enumerate(self.CONFIGURATIONS)}

    @cached_property
    def counts(self) -> dict[str, dict[str, np.ndarray]]:
        """Per configuration: every count by name over the readings' dims."""

        return self._groups("")

    @property
    def rays(self) -> np.ndarray:
        """N per reading and configuration, shape (…, configurations), in the order of :attr:`CONFIGURATIONS`."""

        return np.stack([self.counts[c]["rays"] for c in self.CONFIGURATIONS], axis=-1)

    def fraction(self, name: str, configuration: str = "sample") -> np.ndarray:
        """A count of ``configuration`` over its rays (e.g. ``fraction("lost_entrance")``)."""

        return self.counts[configuration][name] / self.counts[configuration]["rays"]


class SphereResult(Configured, ResultBase):
    """
    Sphere readings over labelled dims: the exact counts of both configurations and
    everything derived from them (see the module docstring). One ``xarray.Dataset``
    (:attr:`data`): every count over the readings' dims and ``configuration``, the
    pilot's as ``pilot_<count>``, ``wall_reflectance`` over the readings' dims; the
    sphere, options, settings and provenance in its attributes.

    Parameters
    ----------
    dims : tuple of str
        The dims of the readings, e.g. ``("wavelength",)``, then ``configuration`` (added
        when not given): the kind's own dim, which :meth:`sel` keeps whole.
    coords : dict of str to ndarray
        Labels: ``wavelength`` (nm), ``theta_i`` (degrees; a 0-d array for one angle),
        parameters as for :class:`~virtspec_mi.results.readings.Result`,
        ``configuration`` (``sample``, ``standard``; added when not given).
    counts : dict
        Per configuration (``"sample"``, ``"standard"``): every count by name, ``int64``
        over :attr:`dims` — ``rays`` (N of that configuration and reading), ``detected``,
        ``absorbed_wall``, …, ``lost_<port>``, the hemispherical counts of the first
        interaction, ``wall_reflections``, ``weight_violations``, ``rounded_weights``.
    wall_reflectance : ndarray
        ρw per reading (over :attr:`dims`).
    sphere : str
        The sphere in words.
    cap_fractions : dict
        Each port's cap area over the sphere's.
    options : dict
        How it was read (``measurement``, ``specular``, ``method``, ``standard``, ``max_bounces``).
    settings : Settings
        The settings used.
    seconds : float
        Time spent tracing.
    scene : str
        Fingerprint of the scene, or "".
    sphere_parameters : dict
        The sphere's description (:meth:`~virtspec_mi.instruments.sphere.geometry.Sphere.parameters`).
    specimen_radius : float or None
        Radius of the specimen disk (mm).
    version : str
        virtspec-mi version that made the result.
    parameters : dict or None
        Swept specimen parameters (as :class:`~virtspec_mi.results.readings.Result`'s).
    pilot : dict or None
        Two-stage pilot counts per configuration (spent, not in the estimates); ``None``
        for budgets sized in advance.
    source : dict or None
        The scene's name and ``-D`` defines (:func:`virtspec_mi.runtime.scene.scene_source`), or ``None``.
    """

    CONFIGURATIONS: ClassVar[tuple[str, ...]] = CONFIGURATIONS
    FORMAT: ClassVar[str] = "virtspec-mi sphere 1"
    VARIABLES: ClassVar[dict[str, tuple[str, str]]] = {
        "configuration": ("1", "sphere configuration (sample or standard in the beam)"),
        "detected": ("1", "rays that reached the detector"),
        "absorbed_wall": ("1", "rays absorbed by the sphere wall"),
        "absorbed_specimen": ("1", "rays absorbed by the specimen"),
        "absorbed_other": ("1", "rays absorbed by the standard or another holder"),
        "hemispherical_reflected": ("1", "rays the specimen reflected at its first interaction"),
        "hemispherical_specular": ("1", "rays the specimen reflected by a delta event at its first interaction"),
        "hemispherical_transmitted": ("1", "rays the specimen transmitted at its first interaction"),
        "detected_from_upper": ("1", "detected rays the specimen had first reflected"),
        "wall_reflections": ("1", "wall (and baffle) reflections, summed over the rays"),
        "beam_spill": ("1", "rays of a traced beam whose first surface was not the specimen (a beam profile)"),
        "wall_reflectance": ("1", "reflectance of the sphere wall"),
    }
    """
    ``(units, long_name)`` of this kind's stored variables and coordinates (beside
    :data:`~virtspec_mi.results.formats.VARIABLES`; a port's ``lost_<port>``: :meth:`described`).
    """
    DERIVED: ClassVar[dict[str, Variable]] = {
        "detector_fraction": Variable("1", "detected fraction with the sample: detected/rays",
                                      lambda r: r.detector_fraction, READINGS),
        "standard_fraction": Variable("1", "detected fraction with the reference standard: detected/rays",
                                      lambda r: r.standard_fraction, READINGS),
        "reading": Variable("1", "the instrument's reading: standard value * detector_fraction / standard_fraction",
                            lambda r: r.reading, READINGS),
        "reading_lower": Variable("1", "lower end of the reading's certified interval (probability >= 1 - delta)",
                                  lambda r: r.reading_interval[..., 0], READINGS),
        "reading_upper": Variable("1", "upper end of the reading's certified interval (probability >= 1 - delta)",
                                  lambda r: r.reading_interval[..., 1], READINGS),
        "hemispherical": Variable("1", "hemispherical value of the same rays (the specimen's first interaction)",
                                  lambda r: r.hemispherical, READINGS),
        **bounds({"hemispherical": "the hemispherical value at delta"},
                 lambda r, _: (r.hemispherical_interval[..., 0], r.hemispherical_interval[..., 1]),
                 lambda r: r.delta, READINGS),
        "instrument_error": Variable("1", "reading - hemispherical", lambda r: r.instrument_error, READINGS),
        "fraction_mu": Variable("1", "tolerance of each detector fraction at delta/2 (NaN: not certified)",
                                lambda r: r.fraction_mu, READINGS),
    }
    """Every variable derived from the counts, over the readings' dims: the fractions, the reading and its interval,
    the hemispherical value of the same rays, the instrument error and the certificate."""
    FIGURES: ClassVar[dict[str, Figure]] = {"spectra": spectra(("reading", "hemispherical"))}
    """The reading and the hemispherical value of the same rays (or one quantity) over wavelength, with their bands."""
    LEGACY: ClassVar[tuple[str, ...]] = ("virtspec-mi sphere 0",)
    KIND: ClassVar[str] = "integrating-sphere reading"
    KIND_DIMS: ClassVar[tuple[str, ...]] = ("configuration",)
    KIND_DIMS_REASON: ClassVar[str] = (
        "a reading is the ratio of both configurations; each one's counts are counts['sample'] and "
        "counts['standard'] (in to_dataset(): the dim configuration)")
    QUANTITIES: ClassVar[tuple[str, ...]] = ("reading", "corrected", "hemispherical")
    _QUANTITY_NOTE: ClassVar[str] = "a sphere reading has no R, T, A triple"

    def __init__(self, dims: tuple[str, ...], coords: Mapping[str, Any], counts: dict[str, dict[str, Any]],
                 wall_reflectance: Any, sphere: str, cap_fractions: dict[str, float], options: dict[str, Any],
                 settings: Settings, seconds: float = 0.0, scene: str = "", sphere_parameters: dict | None = None,
                 specimen_radius: float | None = None, version: str = __version__, parameters: dict | None = None,
                 pilot: dict[str, dict[str, Any]] | None = None, source: dict | None = None) -> None:
        options = _checked_options(options)
        if options.get("detector") == "expected":
            lacking = [f"{c}.{name}" for c, named in counts.items() for name in SCORE_SUMS if name not in named]
            if lacking:
                raise ValueError(f"an expected-value reading (options.detector = 'expected') needs the score sums "
                                 f"{', '.join(SCORE_SUMS)} of both configurations (lacks {', '.join(lacking)})")
        readings = tuple(d for d in dims if d != "configuration")
        checked = {"wall_reflectance": (readings, wall_reflectance)}
        arrays = {"wall_reflectance": (readings, wall_reflectance), **self._configured("counts", counts, readings, checked),
                  **self._configured("pilot", pilot or {}, readings, checked)}
        labels = {**coords, "configuration": np.array(CONFIGURATIONS, dtype=object)}  # variable-length text
        attrs = {"sphere": sphere, "cap_fractions": dict(cap_fractions), "options": dict(options),
                 "settings": settings, "seconds": float(seconds), "scene": scene,
                 "sphere_parameters": dict(sphere_parameters or {}), "specimen_radius": specimen_radius,
                 "version": version, "parameters": parameters, "source": source}
        self._store((*readings, "configuration"), labels, arrays, attrs, checked)

    @cached_property
    def pilot(self) -> dict[str, dict[str, np.ndarray]] | None:
        """Two-stage pilot counts per configuration (spent, not in the estimates); ``None`` for budgets sized ahead."""

        return self._groups("pilot_") if "pilot_rays" in self.data else None

    wall_reflectance = stored("wall_reflectance", "ρw per reading (over the readings' dims).")
    sphere = attribute("sphere", "The sphere in words.", str)
    cap_fractions = attribute("cap_fractions", "Each port's cap area over the sphere's.")
    options = attribute("options", "How it was read (``measurement``, ``specular``, ``method``, ``standard``, "
                                   "``max_bounces``).")
    sphere_parameters = attribute(
        "sphere_parameters", "The sphere's description (:meth:`~virtspec_mi.instruments.sphere.geometry.Sphere.parameters`).")
    specimen_radius = attribute("specimen_radius", "Radius of the specimen disk (mm), or ``None``.")

    # -- counts and fractions (counts, rays, fraction: Configured) ---------------------------

    @property
    def expected(self) -> bool:
        """True when detection was scored by its expected value (``detector="expected"``), not counted."""

        return self.options.get("detector", "counted") == "expected"

    def _detected(self, configuration: str) -> np.ndarray:
        """A configuration's detector fraction: detected/rays, or the mean score (expected-value detector)."""

        if self.expected:
            counts = self.counts[configuration]
            return counts[SCORE_SUMS[0]] / (SCORE_SCALE * counts["rays"])
        return self.fraction("detected", configuration)

    @property
    def detector_fraction(self) -> np.ndarray:
        """p_sample: the detected fraction with the sample (the mean score with ``detector="expected"``)."""

        return self._detected("sample")

    @property
    def standard_fraction(self) -> np.ndarray:
        """p_standard: the detected fraction with the reference standard (or the open port)."""

        return self._detected("standard")

    @property
    def fraction_delta(self) -> float:
        """δ/2: the failure probability of each detector fraction's interval."""

        return self.delta / 2.0

    def fraction_interval(self, configuration: str = "sample") -> np.ndarray:
        """Clopper–Pearson interval (…, 2) of a configuration's detector fraction at δ/2 (with
        ``detector="expected"``: the empirical Bernstein interval of its mean score,
        :func:`virtspec_mi.budgets.scores.score_interval`)."""

        return self._intervals[f"fraction_{configuration}"]

    @cached_property
    def _intervals(self) -> dict[str, np.ndarray]:
        """Every Clopper–Pearson interval, computed once (derived: the public state stays as built)."""

        def interval(configuration: str, name: str, delta: float) -> np.ndarray:
            counts = self.counts[configuration]
            return np.stack(clopper_pearson(counts[name], counts["rays"], delta), axis=-1)

        def scored(configuration: str, delta: float) -> np.ndarray:
            counts = self.counts[configuration]
            return np.stack(score_interval(counts[SCORE_SUMS[0]], counts[SCORE_SUMS[1]], counts["rays"], delta,
                                           SCORE_SCALE, ROUNDING_BIAS, SMALLEST_WEIGHT), axis=-1)

        fraction = scored if self.expected else (lambda c, delta: interval(c, "detected", delta))
        out = {f"fraction_{c}": fraction(c, self.fraction_delta) for c in CONFIGURATIONS}
        out["hemispherical"] = interval("sample", self._hemispherical_count, self.delta)
        return out

    @property
    def certified(self) -> np.ndarray:
        """
        False where either configuration has capped walks, invalid directions or weight
        violations, or where no light reached the detector in the standard configuration
        (p_standard = 0: the reading ρ_std·p_sample/p_standard is undefined).
        """

        bad = sum(self.counts[c][n] for c in CONFIGURATIONS for n in _UNCERTIFIED)
        return np.asarray((bad == 0) & ~self.no_light)

    @property
    def no_light(self) -> np.ndarray:
        """True where no ray of the standard configuration reached the detector (the reading is undefined)."""

        return np.asarray(self._detected("standard") == 0)

    @property
    def fraction_mu(self) -> np.ndarray:
        """
        Tolerance each detector fraction is certified to at δ/2, per reading: μ for a
        two-stage budget (each fraction sized to it), else what the N spent guarantee under
        eq. (19) (Hoeffding's μ, which holds for every N — and for the mean of scores in
        [0, 1], the expected-value detector's; the larger of the two configurations'); NaN
        where not certified.
        """

        if self.settings.adaptive and self.settings.rays is None and self.tolerance is None:
            mu = np.full(self.certified.shape, float(self.settings.mu))
        else:
            mu = np.maximum(*(per_count(self.counts[c]["rays"], lambda n: hoeffding_mu(n, self.fraction_delta))
                              for c in CONFIGURATIONS))
        return np.where(self.certified, mu, np.nan)

    @property
    def tolerance(self) -> float | None:
        """The half-width the reading's interval was sized for (``tolerance=``), or ``None``."""

        value = self.options.get("tolerance")
        return None if value is None else float(value)

    @property
    def tolerance_met(self) -> np.ndarray:
        """Per reading: whether its certified interval lies within ± :attr:`tolerance` of the reading (all True without one)."""

        if self.tolerance is None:
            return np.ones(self.certified.shape, dtype=bool)
        return np.asarray(self.certified & (half_width(self.reading, self.reading_interval) <= self.tolerance))

    # -- the readout ------------------------------------------------------------------

    @property
    def standard_value(self) -> float:
        """The standard's value: ρ_std for a reflectance reading, 1 for a transmittance one (the open port)."""

        return 1.0 if self.options["measurement"] == "transmittance" else float(self.options["standard"])

    @property
    def reading(self) -> np.ndarray:
        """The instrument's reading: standard value · p_sample / p_standard."""

        with np.errstate(divide="ignore", invalid="ignore"):
            return self.standard_value * self.detector_fraction / self.standard_fraction

    @property
    def reading_interval(self) -> np.ndarray:
        """The reading's certified interval [ρ_std·p_s⁻/p_r⁺, ρ_std·p_s⁺/p_r⁻], last axis of length 2: it holds
        with probability ≥ 1 − δ (NaN where uncertified)."""

        out = ratio_bounds(self.fraction_interval("sample"), self.fraction_interval("standard"), self.standard_value)
        return np.where(self.certified[..., None], out, np.nan)

    @property
    def _hemispherical_count(self) -> str:
        transmittance = self.options["measurement"] == "transmittance"
        return "hemispherical_transmitted" if transmittance else "hemispherical_reflected"

    @property
    def hemispherical(self) -> np.ndarray:
        """The hemispherical reading of the same rays (reflectance, or transmittance)."""

        return self.fraction(self._hemispherical_count, "sample")

    @property
    def hemispherical_interval(self) -> np.ndarray:
        """Clopper–Pearson interval (…, 2) of the hemispherical reading at δ."""

        return self._intervals["hemispherical"]

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

    @property
    def wall_reflections_per_ray(self) -> np.ndarray:
        """Mean wall (and baffle) reflections per ray, sample configuration."""

        return self.fraction("wall_reflections", "sample")

    # -- the correction (the theory's inverse of the readout) --------------------------

    @property
    def sphere_description(self) -> Sphere:
        """The :class:`~virtspec_mi.instruments.sphere.geometry.Sphere` this result was read with."""

        if not self.sphere_parameters:
            raise ValueError("this sphere result carries no sphere description (sphere_parameters is empty: "
                             "written by an older version); read the specimen again")
        return sphere_from_parameters(self.sphere_parameters)

    def theory_inputs(self) -> dict[str, Any]:
        """
        The :mod:`virtspec_mi.instruments.sphere.theory` keywords of this reading
        (:func:`virtspec_mi.instruments.sphere.model.theory_inputs` of its sphere, its reading
        mode — the ``measurement``, ``specular``, ``method`` and ``standard`` it was read with,
        as plain values — and its specimen radius).
        """

        self._check_spectrum("the sphere theory's inputs")
        mode = SimpleNamespace(**{k: self.options[k] for k in ("measurement", "specular", "method", "standard")})
        return theory_inputs(self.sphere_description, mode, np.atleast_1d(self.wavelengths), self.specimen_radius)

    def corrected(self, *, specular_reflectance: Any = 0.0, sample_reflectance: Any = None,
                  collimated_transmittance: Any = 0.0) -> np.ndarray:
        """
        The hemispherical value recovered from :attr:`reading` by the sphere theory's
        inverse (:func:`virtspec_mi.instruments.sphere.model.correct_readings`; keywords there): what
        a user computes from an instrument's reading and its sphere's description. It
        assumes the theory's sphere (flat disks, no baffle) and a Lambertian specimen
        (unless ``sample_reflectance``, its reflectance for diffuse light, is given; required
        for transmittance); the difference from :attr:`hemispherical` is the model's
        residual for this specimen. A result over more than wavelength: select one θi and
        parameter point first (:meth:`sel`).
        """

        values = correct_readings(np.atleast_1d(self.reading), self.theory_inputs(),
                                  specular_reflectance=specular_reflectance, sample_reflectance=sample_reflectance,
                                  collimated_transmittance=collimated_transmittance)
        return values.reshape(np.shape(self.reading))

    def corrected_interval(self, *, specular_reflectance: Any = 0.0, sample_reflectance: Any = None,
                           collimated_transmittance: Any = 0.0) -> np.ndarray:
        """
        :attr:`reading_interval` through the (increasing) correction, (…, 2): holds the
        corrected value of the expected reading with probability ≥ 1 − δ (NaN where not
        certified).
        """

        interval = self.reading_interval
        values = correct_readings(interval.reshape(-1, 2), self.theory_inputs(),
                                  specular_reflectance=specular_reflectance, sample_reflectance=sample_reflectance,
                                  collimated_transmittance=collimated_transmittance)
        return values.reshape(interval.shape)

    def budget(self, take: Any) -> Any:
        """
        The error budget: reading − hemispherical split into its sources, each certified
        (:func:`virtspec_mi.instruments.sphere.budget.sphere_budget`); ``take(sphere,
        **options)`` reads another sphere with this reading's scene, settings, seed and N.
        """

        from virtspec_mi.instruments.sphere.budget import sphere_budget

        return sphere_budget(self, take)

    def _check_spectrum(self, what: str) -> None:
        other = [d for d in self.reading_dims if d != "wavelength"]
        if other:
            raise ValueError(f"{what} need a reading over wavelength only: select one label of "
                             f"{', '.join(other)} first (sel)")

    # -- spectra and plots ------------------------------------------------------------

    def _quantity(self, quantity: str) -> tuple[np.ndarray, np.ndarray, float]:
        """A quantity with its tolerance: the half-width that covers its certified interval."""

        if quantity == "reading":
            values, interval = self.reading, self.reading_interval
        elif quantity == "hemispherical":
            values, interval = self.hemispherical, np.where(self.certified[..., None], self.hemispherical_interval,
                                                            np.nan)
        else:
            squeezed = self.squeeze("theta_i")
            values = squeezed.corrected().reshape(self.reading.shape)
            interval = squeezed.corrected_interval().reshape(self.reading_interval.shape)
        tolerance = np.maximum(values - interval[..., 0], interval[..., 1] - values)
        return values, tolerance, self.delta

    def spectrum_measures(self, quantity: str | None = None) -> str:
        """What the sphere measures (``reflectance`` or ``transmittance``), whichever of its quantities."""

        self.check_quantity(quantity)
        return str(self.options["measurement"])

    def rendered(self) -> np.ndarray:
        """What ``mi.render`` returns: per wavelength the reading, the hemispherical value and both detector fractions."""

        reading = self.squeeze()
        return np.stack([reading.reading, reading.hemispherical, reading.detector_fraction,
                         reading.standard_fraction], axis=1).astype(np.float32)

    # -- text -------------------------------------------------------------------------

    def summary(self) -> str:
        """A table: each reading's labels, detector fractions, reading with its interval, hemispherical, error."""

        options = self.options
        kind = "transmittance" if options["measurement"] == "transmittance" else f"reflectance ({options['specular']})"
        mu = self.fraction_mu
        detector = ("; detector: expected value of each wall bounce (mean scores, empirical Bernstein)"
                    if self.expected else "")
        lines = [f"integrating sphere {kind}, method = {options['method']}, standard = {self.standard_value:g}"
                 f"{detector}; {self.sphere}",
                 f"N = {span(self.rays)} rays per configuration and reading; "
                 + (f"each detector fraction certified to {round_up(float(np.nanmax(mu))):g} at delta/2 = "
                    f"{self.fraction_delta:g} (reading interval: both at once, probability >= "
                    f"{1 - self.delta:g})" if np.any(self.certified) else
                    "NOT CERTIFIED: no light reached the detector" if np.all(self.no_light) else
                    "NOT CERTIFIED (capped walks, invalid directions or weight violations)")
                 + f"; {self.seconds * 1e3:.1f} ms"]
        if self.tolerance is not None:
            met = self.tolerance_met
            lines.append(f"tolerance +-{self.tolerance:g} on the reading (rays sized by a pilot of "
                         f"{span(self.pilot['sample']['rays']) if self.pilot else '?'} per configuration): "
                         + ("met by every reading" if np.all(met) else
                            f"NOT MET by {int(np.sum(~met))} of {met.size} readings (their intervals are still "
                            "certified; give more pilot rays or a larger tolerance)"))
        fixed = [f"{name} = {float(value):g}" for name, value in self.coords.items() if not self.coord_dims(name)]
        if fixed:
            lines.append("at " + ", ".join(fixed))
        if "beam_spill" in self.counts["sample"]:  # a traced beam (a beam profile): the rays that missed the specimen
            spill = self.counts["sample"]["beam_spill"] / self.counts["sample"]["rays"]
            low, high = float(np.min(spill)), float(np.max(spill))
            lines.append("beam spill (rays whose first surface was not the specimen): "
                         + (f"{low:.4f}" if low == high else f"{low:.4f} to {high:.4f}") + " of the sample's rays")
        labels = list(self.reading_dims)
        heads = ["lambda/nm" if d == "wavelength" else d for d in labels]
        lines.append(" ".join(f"{h:>10}" for h in heads) + "  rho_w   p_sample  p_standard   reading  [interval]"
                     "            hemispherical    error")
        interval, certified = self.reading_interval, self.certified
        for index in np.ndindex(*(self.sizes[d] for d in labels)):
            at = " ".join(f"{float(self.coords[d][k]):>10g}" for d, k in zip(labels, index))
            lines.append(f"{at}  {self.wall_reflectance[index]:.4f}  {self.detector_fraction[index]:.5f}  "
                         f"{self.standard_fraction[index]:.5f}    {self.reading[index]:.5f}  "
                         f"[{interval[index][0]:.5f}, {interval[index][1]:.5f}]  {self.hemispherical[index]:.5f}     "
                         f"{self.instrument_error[index]:+.5f}" + ("" if certified[index] else "  NOT CERTIFIED"
                                                             + (": no light reached the detector"
                                                                if self.no_light[index] else "")))
        return "\n".join(lines)

    def __repr__(self) -> str:
        sizes = ", ".join(f"{d}: {n}" for d, n in self.sizes.items())
        return f"<SphereResult ({sizes}) N = {span(self.rays)}, {self.options['measurement']}>"

    # -- plain data, datasets and files -------------------------------------------------

    def as_dict(self) -> dict[str, Any]:
        """
        Every field as plain data (JSON-ready; NaN as ``None``): the counts of both
        configurations, the labels, the sphere, options, settings and provenance, and the
        derived values (``reading``, ``reading_interval`` (…, 2), ``hemispherical``,
        ``hemispherical_interval``, ``instrument_error``, ``fraction_mu``).
        :meth:`from_dict` reads it back.
        """

        def groups(source: dict[str, dict[str, np.ndarray]]) -> dict[str, dict[str, Any]]:
            return {c: {name: plain_data(values) for name, values in named.items()} for c, named in source.items()}

        return {
            "format": self.FORMAT,
            **self._labels_as_dict(),
            **self._parameters_as_dict(),
            "counts": groups(self.counts),
            "pilot": None if self.pilot is None else groups(self.pilot),
            "wall_reflectance": plain_data(self.wall_reflectance),
            "sphere": self.sphere,
            "cap_fractions": dict(self.cap_fractions),
            "options": dict(self.options),
            "settings": {**asdict(self.settings), "wavelengths": list(self.settings.wavelengths)},
            "seconds": self.seconds,
            "scene": self.scene,
            "sphere_parameters": self.sphere_parameters,
            "specimen_radius": self.specimen_radius,
            "version": self.version,
            "reading": plain_data(self.reading),
            "reading_interval": plain_data(self.reading_interval),
            "hemispherical": plain_data(self.hemispherical),
            "hemispherical_interval": plain_data(self.hemispherical_interval),
            "instrument_error": plain_data(self.instrument_error),
            "fraction_mu": plain_data(self.fraction_mu),
        }

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> "SphereResult":
        """The result of :meth:`as_dict` (checked by :meth:`from_dict <virtspec_mi.results.base.ResultBase.from_dict>`)."""

        def groups(source: Mapping[str, Any], what: str) -> dict[str, dict[str, np.ndarray]]:
            if not isinstance(source, Mapping) or set(source) != set(CONFIGURATIONS):
                shown = sorted(source) if isinstance(source, Mapping) else type(source).__name__
                raise ValueError(f"'{what}' must hold the counts of the configurations {', '.join(CONFIGURATIONS)} "
                                 f"(got {shown})")
            out = {}
            for configuration in CONFIGURATIONS:
                named = source[configuration]
                if not isinstance(named, Mapping):
                    raise ValueError(f"{what}[{configuration!r}] must be an object of counts")
                out[configuration] = {str(name): whole_counts(values, f"{what}[{configuration!r}] '{name}'")
                                      for name, values in named.items()}
            return out

        return cls(
            **cls.labels_from_dict(data),
            counts=groups(data["counts"], "counts"),
            pilot=None if data.get("pilot") is None else groups(data["pilot"], "pilot"),
            wall_reflectance=finite_labels(data["wall_reflectance"], "wall_reflectance"),
            sphere=field_value(data, "sphere", "text"), cap_fractions=field_value(data, "cap_fractions", "object"),
            options=field_value(data, "options", "object"), settings=Settings(**field_value(data, "settings", "object")),
            seconds=float(field_value(data, "seconds", "seconds")), scene=field_value(data, "scene", "text"),
            sphere_parameters=dict(data.get("sphere_parameters") or {}),
            specimen_radius=field_value(data, "specimen_radius", "number or null") if "specimen_radius" in data else None,
            version=field_value(data, "version", "text"),
        )

    def _count_groups(self) -> list[tuple[str, Mapping[str, np.ndarray], CountRules, tuple[str, ...]]]:
        """Each configuration's counts (and its pilot's), and the wall reflectance of every reading."""

        groups = [(f"{prefix}[{c!r}]", named[c], rules, self.reading_dims)  # a pilot's: the first interaction's fates
                  for prefix, named, rules in (("counts", self.counts, COUNT_RULES),
                                               ("pilot", self.pilot or {}, FATE_RULES)) for c in named]
        return [*groups, ("", {"wall_reflectance": self.wall_reflectance}, _FRACTION_RULES, self.reading_dims)]

    @classmethod
    def _from_plain(cls, tag: str, data: Any) -> "SphereResult":
        if tag == cls.FORMAT:
            return cls.from_dict(data)
        try:
            return cls.from_dict(_from_layout_0(data))
        except KeyError as error:
            raise ValueError(f"lacks the field {error} of a sphere result of layout 0") from None
        except (TypeError, AttributeError) as error:
            raise ValueError(f"a field of the sphere result of layout 0 has the wrong type "
                             f"({' '.join(str(error).split())})") from None

    def _file_attrs(self) -> dict[str, Any]:
        """The sphere, the options, settings and provenance as numbers and text (a NetCDF file's attributes)."""

        s = self.settings
        return {"sphere": self.sphere, **{k: v for k, v in self.options.items() if k != "max_bounces"},
                "max_bounces": int(self.options.get("max_bounces", 0)), "mu": s.mu, "delta": s.delta,
                "beam": s.beam, "seed": s.seed, "phi_i": s.phi_i, "seconds": self.seconds, "scene": self.scene,
                "version": self.version, **({} if self.parameters is None else
                                            {"parameters": json.dumps(self.parameters)})}

    def described(self) -> dict[str, tuple[str, str]]:
        """The kind's table (:meth:`ResultBase.described`) and each port's ``lost_<port>`` count."""

        ports = {name: ("1", f"rays lost through port {name[5:]!r}") for name in self.counts["sample"]
                 if name.startswith("lost_")}
        return {**super().described(), **ports}


def _from_layout_0(data: Any) -> dict[str, Any]:
    """
    The plain data (format 1) of a sphere result written before the result family:
    its JSON object (``"kind": "sphere_result"``, one N for both configurations and every
    wavelength) or its NetCDF dataset (``<configuration>_<count>`` variables, the rest in
    the ``json`` attribute).
    """

    if isinstance(data, dict):
        plain = dict(data)
        wavelengths = finite_labels(plain["wavelengths"], "wavelengths")
        counts = {c: dict(named) for c, named in plain["counts"].items()}
    else:
        extra = json.loads(data.attrs["json"])
        wavelengths = finite_labels(data["wavelength"].values, "wavelength")
        counts = {c: {} for c in CONFIGURATIONS}
        for name in data.data_vars:
            configuration, _, key = str(name).partition("_")
            if configuration in counts:
                counts[configuration][key] = data[name].values
        plain = {**extra, "wall_reflectance": data["wall_reflectance"].values, "sphere": data.attrs["sphere"],
                 "scene": data.attrs["scene"], "seconds": data.attrs["seconds"], "rays": data.attrs["rays"]}
    rays = whole_counts(plain["rays"], "rays")
    if rays.ndim:
        raise ValueError(f"'rays' of a sphere result of layout 0 is one number (got shape {rays.shape})")
    for named in counts.values():
        named["rays"] = np.full(wavelengths.shape, int(rays), dtype=np.int64)
    settings = dict(plain["settings"])
    return {"format": SphereResult.FORMAT, "dims": ["wavelength"], "wavelengths": wavelengths,
            "theta_i": settings["theta_i"], "counts": counts, "pilot": None,
            "wall_reflectance": np.asarray(plain["wall_reflectance"], dtype=np.float64),
            "sphere": plain["sphere"], "cap_fractions": plain["cap_fractions"], "options": plain["options"],
            "settings": settings, "seconds": plain["seconds"], "scene": plain.get("scene", ""),
            "sphere_parameters": plain.get("sphere_parameters") or {},
            "specimen_radius": plain.get("specimen_radius"), "version": "unknown (written before format 1)"}


def _checked_options(options: Any) -> dict[str, Any]:
    """
    How a reading was taken, as a file states it, held to the rules it was measured under
    (:class:`~virtspec_mi.instruments.sphere.SphereOptions`): the standard's reflectance
    0 < standard <= 1 (a standard of 0 would divide by zero, of 2 double every reading), the
    measurement a reflectance or a transmittance.
    """

    if not isinstance(options, Mapping):
        raise ValueError(f"'options' must be an object (got {type(options).__name__})")
    options = dict(options)
    if "standard" in options:
        options["standard"] = share("options.standard")(options["standard"])
    if options.get("detector", "counted") not in ("counted", "expected"):
        raise ValueError(f"options.detector must be counted or expected (got {options['detector']!r})")
    if options.get("measurement", "reflectance") not in ("reflectance", "transmittance"):
        raise ValueError(f"options.measurement must be reflectance or transmittance (got {options['measurement']!r})")
    if options.get("tolerance") is not None:
        tolerance = number("options.tolerance", options["tolerance"])
        if not 0 < tolerance < 1:
            raise ValueError(f"options.tolerance must satisfy 0 < tolerance < 1 (got {options['tolerance']!r})")
        options["tolerance"] = tolerance
    return options
