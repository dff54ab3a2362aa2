"""
The sphere's readout: sample over standard, certified, beside the hemispherical reading
=======================================================================================

A real integrating-sphere instrument reads a detector signal and ratios it against a
reference standard of known reflectance ρ_std. :func:`measure_sphere` simulates both
configurations with the sphere walk (:mod:`virtspec_mi.kernel.sphere_walk`) and returns
a :class:`SphereResult`:

- **single-beam substitution** (``method="substitution"``): the sample in the sample
  port, then the standard in its place (a reference port, if any, plugged with wall
  material). The sphere's throughput changes with what sits in the port: the
  *substitution error*;
- **comparison** (``method="comparison"``): sample and standard mounted at the same time
  (sample and reference ports), the beam on the sample; then the two swapped, the beam on
  the standard. The sphere holds the same two disks in both configurations, so its
  throughput is the same (exactly, for ports placed symmetrically about the detector);
- **transmittance** (``measurement="transmittance"``): the specimen at the entrance
  port, lit from outside; the reference is the open port (τ_std = 1); the sample port,
  if any, holds the reference standard in both configurations: the single-beam
  ("one-port") arrangement whose substitution error Kessel (1986) corrects (the specimen
  returns into the sphere light the open port lost; :meth:`SphereResult.corrected`);
- **SCI / SCE**: the ``specular`` port plugged with wall material or open to a trap.

The reading is R = ρ_std · p_sample / p_standard (p: detector fractions, each m/N of
its own N rays, the same seed in both configurations). **Certificate:** each detector
fraction gets a Clopper–Pearson interval at δ/2, so both hold together with probability
≥ 1 − δ by the union bound (whatever the dependence between the configurations); the
ratio's interval is then [ρ_std·p_s⁻/p_r⁺, ρ_std·p_s⁺/p_r⁻] (the extreme combinations).
Each configuration's N is the settings' rule at (μ, δ/2), so each fraction is within μ
with probability ≥ 1 − δ/2. The hemispherical reading (the first specimen interaction's
hemisphere, :mod:`virtspec_mi.kernel.tracer`) comes from the sample configuration's very
rays; the instrument error is reading − hemispherical.

**Correction:** :meth:`SphereResult.corrected` / :meth:`SphereResult.corrected_interval`
invert the sphere theory's readout model (:mod:`virtspec_mi.sphere_theory` with the inputs
of :func:`virtspec_mi.sphere_model.theory_inputs`, from the sphere description the result
keeps) to recover the hemispherical value from the reading.

References
----------
Baranoski et al. (2001), eqs. (2), (19), (23); Clopper & Pearson (1934); Labsphere,
*Integrating sphere theory and applications* (substitution and comparison methods);
J. Kessel (1986), Appl. Opt. 25, 2752–2756 (transmittance in a one-port sphere).
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from virtspec_mi.bounds import hoeffding_mu
from virtspec_mi.intervals import clopper_pearson
from virtspec_mi.settings import Settings
from virtspec_mi.sphere import SPHERE_SETTING_NAMES, Sphere, SphereSettings, sphere_from_parameters
from virtspec_mi.sphere_model import correct_readings, theory_inputs

__all__ = ["CONFIGURATIONS", "SphereResult", "measure_sphere", "configurations"]

CONFIGURATIONS: tuple[str, ...] = ("sample", "standard")
"""The two simulated configurations of every reading."""

_FATES = ("detected", "absorbed_wall", "absorbed_specimen", "absorbed_other", "capped", "invalid_directions")


def configurations(sphere: Sphere, options: SphereSettings, specimen_bsdf: Any, specimen_radius: float,
                   standard_bsdf: Any, open_bsdf: Any) -> dict[str, tuple[list, list]]:
    """
    Per configuration: the holders (port index, BSDF, disk radius, frame) — holder 0 in
    the beam — and each port's cap fate (a code of :mod:`virtspec_mi.kernel.sphere_walk`,
    ``None`` for a plugged port).
    """

    from virtspec_mi.kernel.sphere_walk import Holder, holder_frame

    index = {p.role: i for i, p in enumerate(sphere.ports) if p.role not in ("detector", "open")}
    transmittance = options.measurement == "transmittance"
    beam_role = "entrance" if transmittance else "sample"
    if beam_role not in index:
        raise ValueError(f"sphere: a {options.measurement} reading needs a port with role {beam_role!r} "
                         f"(ports: {[p.name for p in sphere.ports]})")
    beam_port = sphere.ports[index[beam_role]]
    if specimen_radius > beam_port.radius * (1 + 1e-9):
        raise ValueError(f"specimen radius {specimen_radius:g} mm is larger than its port {beam_port.name!r} "
                         f"(radius {beam_port.radius:g} mm): the specimen must fit in its port")
    if sphere.port("detector") is None:
        raise ValueError(f"sphere: a reading needs a port with role 'detector' (ports: {[p.name for p in sphere.ports]})")
    other_role = "sample" if transmittance else ("reference" if options.method == "comparison" else None)
    if options.method == "comparison" and not transmittance and "reference" not in index:
        raise ValueError("method='comparison' needs a port with role 'reference' (for the standard)")
    if transmittance and options.method == "comparison":
        raise ValueError("method='comparison' is for reflectance; a transmittance reading is referenced to the "
                         "open port (method='substitution')")
    other_port = None if other_role is None or other_role not in index else sphere.ports[index[other_role]]
    if other_port is not None and specimen_radius > other_port.radius * (1 + 1e-9):
        raise ValueError(f"specimen radius {specimen_radius:g} mm is larger than port {other_port.name!r} "
                         f"(radius {other_port.radius:g} mm), where the {'standard' if transmittance else 'sample'} "
                         "sits")
    actions: list[int | None] = []
    for j, port in enumerate(sphere.ports):
        lost = 6 + j
        if port.role == "detector":
            actions.append(0)
        elif port.role == "specular":
            actions.append(lost if options.specular == "SCE" else None)
        elif port.role == "reference" and other_port is None:
            actions.append(None)  # plugged with wall material
        else:
            actions.append(lost)

    def holder(port: Any, bsdf: Any, radius: float, outward: bool) -> Any:
        return Holder(sphere.ports.index(port), bsdf, radius, holder_frame(port.axis, outward))

    if transmittance:
        sample = [holder(beam_port, specimen_bsdf, specimen_radius, True)]
        standard = [holder(beam_port, open_bsdf, beam_port.radius, True)]
        if other_port is not None:  # the white standard in the reflectance port, in both
            sample.append(holder(other_port, standard_bsdf, other_port.radius, False))
            standard.append(holder(other_port, standard_bsdf, other_port.radius, False))
    elif other_port is not None:  # comparison: both mounted, then swapped
        sample = [holder(beam_port, specimen_bsdf, specimen_radius, False),
                  holder(other_port, standard_bsdf, specimen_radius, False)]
        standard = [holder(beam_port, standard_bsdf, specimen_radius, False),
                    holder(other_port, specimen_bsdf, specimen_radius, False)]
    else:
        sample = [holder(beam_port, specimen_bsdf, specimen_radius, False)]
        standard = [holder(beam_port, standard_bsdf, specimen_radius, False)]
    return {"sample": (sample, actions), "standard": (standard, actions)}


def _check_beam(sphere: Sphere, options: SphereSettings, settings: Settings, frame: np.ndarray) -> None:
    """A reflectance beam must come in through the entrance port (its axis, from the specimen centre)."""

    if settings.beam == "diffuse":
        raise ValueError("beam must be 'collimated' or 'conical' for a sphere reading (got 'diffuse')")
    if options.measurement == "transmittance":
        return
    entrance = sphere.port("entrance")
    if entrance is None:
        raise ValueError("sphere: a reflectance reading needs a port with role 'entrance'")
    theta, phi = math.radians(settings.theta_i), math.radians(settings.phi_i)
    local = np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])
    centre = sphere.port_plane_centre(sphere.port("sample"))
    hit = sphere.wall_point(centre, frame @ local)
    if sphere.port_at(hit) is not entrance:
        raise ValueError(f"theta_i = {settings.theta_i:g}, phi_i = {settings.phi_i:g}: the beam axis meets the "
                         f"sphere wall outside the entrance port {entrance.name!r} (at {hit.round(2).tolist()} mm); "
                         "give the angles the entrance port is built for")


def measure_sphere(instrument: Any, sphere: Sphere, settings: Settings, options: SphereSettings,
                   scene: str = "") -> "SphereResult":
    """
    The sphere readings of ``instrument``'s specimen at every wavelength of ``settings``
    (see the module docstring): both configurations, traced with the settings' seed,
    each with the settings' rule's N at (μ, δ/2) (or ``settings.rays``).
    """

    import mitsuba as mi

    from virtspec_mi.kernel.sphere_walk import SphereWalk, tally_sphere

    if settings.rays is None and settings.budget.adaptive:
        raise ValueError("bound='two-stage' is not available for sphere readings (each configuration is sized "
                         "in advance): use hoeffding, chebyshev or exact, or give rays")
    rays = settings.rays if settings.rays is not None else settings.updated(delta=settings.delta / 2).rays_per_reading
    standard_bsdf = mi.load_dict({"type": "diffuse", "reflectance": options.standard})
    open_bsdf = mi.load_dict({"type": "null"})
    radius = instrument.geometry.specimen_radius
    setups = configurations(sphere, options, instrument.bsdf, radius, standard_bsdf, open_bsdf)
    frame = setups["sample"][0][0].frame
    _check_beam(sphere, options, settings, frame)
    wavelengths = np.asarray(settings.wavelengths, dtype=np.float64)
    rho_w = sphere.wall_reflectance_at(wavelengths)
    counts: dict[str, dict[str, np.ndarray]] = {}
    start = time.perf_counter()
    for name, (holders, actions) in setups.items():
        walk = SphereWalk(sphere, holders, actions, options.max_bounces)
        traced = replace(instrument, bsdf=holders[0].bsdf)
        tallies = tally_sphere(walk, traced, wavelengths, rho_w, rays, settings)
        counts[name] = _named_counts(sphere, tallies)
    seconds = time.perf_counter() - start
    return SphereResult(wavelengths=wavelengths, rays=int(rays), counts=counts, sphere=sphere.describe(),
                        cap_fractions=sphere.cap_fractions, wall_reflectance=rho_w, options=options.as_dict(),
                        settings=settings.as_dict(), seconds=seconds, scene=scene,
                        sphere_parameters=sphere.parameters(), specimen_radius=float(radius))


def _named_counts(sphere: Sphere, tallies: list[dict[str, Any]]) -> dict[str, np.ndarray]:
    """Per-wavelength counts by name from the walk's histograms."""

    cross = np.stack([t["cross"] for t in tallies])  # (wavelength, hemisphere, code)
    by_code = cross.sum(axis=1)
    out = {name: by_code[:, k] for k, name in enumerate(_FATES)}
    for j, port in enumerate(sphere.ports):
        out[f"lost_{port.name}"] = by_code[:, 6 + j]
    out["hemispherical_reflected"] = cross[:, 1, :].sum(axis=1) + cross[:, 3, :].sum(axis=1)
    out["hemispherical_specular"] = cross[:, 3, :].sum(axis=1)  # reflected by a delta event (part of the above)
    out["hemispherical_transmitted"] = cross[:, 2, :].sum(axis=1)
    out["detected_from_upper"] = cross[:, 1, 0] + cross[:, 3, 0]
    for name in ("wall_reflections", "weight_violations", "rounded_weights"):
        out[name] = np.array([t[name] for t in tallies], dtype=np.int64)
    return {k: np.asarray(v, dtype=np.int64) for k, v in out.items()}


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
        """The :class:`~virtspec_mi.sphere.Sphere` this result was read with."""

        if not self.sphere_parameters:
            raise ValueError("this sphere result carries no sphere description (sphere_parameters is empty: "
                             "written by an older version); read the specimen again")
        return sphere_from_parameters(self.sphere_parameters)

    def theory_inputs(self) -> dict[str, Any]:
        """
        The :mod:`virtspec_mi.sphere_theory` keywords of this reading
        (:func:`virtspec_mi.sphere_model.theory_inputs` of its sphere, mode and specimen radius).
        """

        options = {k: v for k, v in self.options.items() if k in SPHERE_SETTING_NAMES}
        return theory_inputs(self.sphere_description, SphereSettings(**options), self.wavelengths,
                             self.specimen_radius)

    def corrected(self, *, specular_reflectance: Any = 0.0, sample_reflectance: Any = None,
                  collimated_transmittance: Any = 0.0) -> np.ndarray:
        """
        The hemispherical value recovered from :attr:`reading` by the sphere theory's
        inverse (:func:`virtspec_mi.sphere_model.correct_readings`; keywords there): what
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
