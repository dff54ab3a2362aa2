"""
The sphere's readout: sample over standard, certified, beside the hemispherical reading
=======================================================================================

A real integrating-sphere instrument reads a detector signal and ratios it against a
reference standard of known reflectance ρ_std. :class:`IntegratingSphere` simulates both
configurations with the sphere walk (:mod:`virtspec_mi.instruments.sphere.walk`) and returns
a :class:`SphereResult` (:class:`SphereOptions`: its options, the sphere among them):

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
with probability ≥ 1 − δ/2. With ``detector="expected"`` each fraction is a mean score in
[0, 1] (:mod:`virtspec_mi.instruments.sphere.expected`: each bounce scores its exact chance
of reaching the detector) with an empirical Bernstein interval at δ/2
(:func:`virtspec_mi.budgets.scores.score_interval`), the ratio's interval built alike. The
hemispherical reading (the first specimen interaction's hemisphere,
:mod:`virtspec_mi.kernel.tracer`) comes from the sample configuration's very rays; the
instrument error is reading − hemispherical.

**Correction:** :meth:`SphereResult.corrected` / :meth:`SphereResult.corrected_interval`
invert the sphere theory's readout model (:mod:`virtspec_mi.instruments.sphere.theory` with the inputs
of :func:`virtspec_mi.instruments.sphere.model.theory_inputs`, from the sphere description the result
keeps) to recover the hemispherical value from the reading.

References
----------
Baranoski et al. (2001), eqs. (2), (19), (23); Clopper & Pearson (1934); Labsphere,
*Integrating sphere theory and applications* (substitution and comparison methods);
J. Kessel (1986), Appl. Opt. 25, 2752–2756 (transmittance in a one-port sphere).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace
from typing import Any, ClassVar

import numpy as np

from virtspec_mi.budgets.ratio import ratio_rays
from virtspec_mi.budgets.rules import DETECTOR_COLUMNS
from virtspec_mi.budgets.twostage import stage_two_seed
from virtspec_mi.engine.parameters import ParameterSpace
from virtspec_mi.engine.plan import Columns, Plan
from virtspec_mi.engine.tally import Tally
from virtspec_mi.instruments.sphere.geometry import Baffle, Port, Sphere, is_sphere_parameter, sphere_from_parameters
from virtspec_mi.instruments.base import Instrument, reading_grid, reading_labels
from virtspec_mi.instruments.command import Command, FigureFlag, Session
from virtspec_mi.instruments.sphere.walk import FATES, HEMISPHERES, SPECIMEN, Holder, SphereFate, holder_frame
from virtspec_mi.instruments.sphere.result import CONFIGURATIONS, SphereResult
from virtspec_mi.instruments.sphere.beam import BeamProfile
from virtspec_mi.instruments.sphere.real import check_traced_beam
from virtspec_mi.instruments.sphere.expected import expected_layout
from virtspec_mi.base.checks import number, shown_value
from virtspec_mi.base.surface import spoken
from virtspec_mi.results.base import plain_data
from virtspec_mi.settings import Options, Settings, one_of, option, share, true_or_false, whole_number

__all__ = ["MEASUREMENTS", "SPECULAR", "METHODS", "DETECTORS", "TOLERANCE_PILOT_RAYS", "SphereOptions", "IntegratingSphere", "configurations",
           "SphereCorrection", "Sphere", "Port", "Baffle", "BeamProfile", "SphereResult"]

MEASUREMENTS: dict[str, str] = {
    "reflectance": "8/d-type reflectance: the specimen in the sample port, lit through the entrance port",
    "transmittance": "the specimen at the entrance port, light transmitted into the sphere (reference: open port)",
}
SPECULAR: dict[str, str] = {
    "SCI": "specular component included: the specular port closed by a plug of wall material",
    "SCE": "specular component excluded: the specular port open to a light trap",
}
DETECTORS: dict[str, str] = {
    "counted": "every ray reaching the detector port counted (exact counts, Clopper-Pearson)",
    "expected": "each wall bounce scores its exact chance of reaching the detector (a bounded score per ray, "
                "empirical Bernstein; a plain sphere: knife-edge circular ports, no field of view, a Lambertian wall)",
}
METHODS: dict[str, str] = {
    "substitution": "single beam: sample, then the standard, in the same port (the reference port plugged)",
    "comparison": "sample and standard both mounted (sample and reference ports), then swapped",
}


TOLERANCE_PILOT_RAYS: int = 50_000
"""
The pilot's rays per configuration and reading that size a reading to its ``tolerance``
(unless ``pilot_rays`` is given): at the shipped 150 mm sphere's detector fractions
(0.027 and 0.059) the reading's N is then 1.3 times the least that meets ±0.005 (8.4·10⁶
against 6.5·10⁶ from the true fractions; 2.7·10⁷ with a pilot of 2,000).
"""


def _check_tolerance(value: Any) -> float | None:
    if value is None:
        return None
    tolerance = number("tolerance", value)
    if not 0.0 < tolerance < 1.0:
        raise ValueError(f"tolerance must satisfy 0 < tolerance < 1 (got {shown_value(value)})")
    return tolerance


def _check_sphere(value: Any) -> Sphere:
    if not isinstance(value, Sphere):
        raise ValueError(f"sphere must be a virtspec_mi.Sphere (got {type(value).__name__})")
    return value


@dataclass(frozen=True)
class SphereOptions(Options):
    """
    How a sphere reading is taken, and the sphere (defined once: the API keywords, the
    CLI flags and the ``integrating_sphere`` integrator's parameters derive from these
    fields; the sphere is read from the integrator's flat parameters ``diameter``,
    ``wall_reflectance``, ``port_<name>`` and ``baffle``:
    :func:`virtspec_mi.instruments.sphere.geometry.sphere_from_parameters`).
    """

    title: ClassVar[str] = "sphere options"

    measurement: str = option("reflectance", one_of("measurement", MEASUREMENTS), "what the sphere measures",
                              MEASUREMENTS)
    specular: str = option("SCI", one_of("specular", SPECULAR, fold=str.upper),
                           "specular component included or excluded", SPECULAR)
    method: str = option("substitution", one_of("method", METHODS), "how the reference standard is measured",
                         METHODS)
    standard: float = option(0.99, share("standard"),
                             "reflectance of the Lambertian reference standard, 0 < standard <= 1")
    max_bounces: int = option(100_000, whole_number("max_bounces", 1, 10**7, "1 <= max_bounces <= 10**7"),
                              "step cap of a sphere walk, 1 ... 10**7 (capped walks are counted)")
    detector: str = option("counted", one_of("detector", DETECTORS),
                           "how detection is scored: counted rays, or the expected value of each wall bounce",
                           DETECTORS)
    tolerance: float | None = option(
        None, _check_tolerance, "half-width the reading's certified interval is sized for, 0 < tolerance < 1: a pilot "
                                "sizes the rays of both configurations (two-stage; counted detector)")
    sphere: Sphere | None = option(
        None, _check_sphere, "the integrating sphere (a virtspec_mi.Sphere; as integrator parameters: diameter, "
                             "wall_reflectance, port_<name>, baffle)", flag=False)

    @classmethod
    def _gathered(cls, parameters: Any) -> dict[str, Any]:
        """The sphere, from its flat parameters (when any is given)."""

        if not any(is_sphere_parameter(name) for name in parameters.keys()):
            return {}
        return {"sphere": sphere_from_parameters(parameters)}

    @classmethod
    def _gathers(cls, name: str) -> bool:
        return is_sphere_parameter(name)

    def as_dict(self) -> dict[str, Any]:
        """
        How the reading is taken, as plain data (the sphere is recorded apart: :meth:`Sphere.parameters`); a
        counted detector is not recorded (the default: files and checkpoints as before the option).
        """

        return {name: value for name, value in super().as_dict().items()
                if name != "sphere" and not (name == "detector" and value == "counted")
                and not (name == "tolerance" and value is None)}


def configurations(sphere: Sphere, options: SphereOptions, specimen_radius: float,
                   specimen_bsdf: Any = SPECIMEN) -> dict[str, tuple[list, list]]:
    """
    Per configuration: the holders (port index, BSDF, disk radius, frame) — holder 0 in
    the beam — and each port's cap fate (a :class:`~virtspec_mi.instruments.sphere.walk.SphereFate`
    code, ``None`` for a plugged port). The specimen's BSDF is ``specimen_bsdf`` (by
    default :data:`~virtspec_mi.instruments.sphere.walk.SPECIMEN`: the bench's), the standard
    a Lambertian of reflectance ``options.standard`` and the open port a null BSDF, as
    Mitsuba plugin dicts.
    """

    standard_bsdf = {"type": "diffuse", "reflectance": options.standard}
    open_bsdf = {"type": "null"}
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
        lost = SphereFate.lost(j)
        if port.role == "detector":
            actions.append(int(SphereFate.DETECTED))
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


def _check_beam(sphere: Sphere, options: SphereOptions, settings: Settings, frame: np.ndarray) -> None:
    """A reflectance beam must come in through the entrance port (its axis, from the specimen centre)."""

    if settings.beam == "diffuse":
        raise ValueError("beam must be 'collimated' or 'conical' for a sphere reading (got 'diffuse')")
    if sphere.beam_profile is not None:
        theta, phi = math.radians(settings.theta_i), math.radians(settings.phi_i)
        check_traced_beam(sphere, options.measurement, settings.beam, np.array(
            [math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)]), frame)
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


# -- the command line: ``virtspec sphere`` and its correction -----------------------------------


def _fraction(name: str) -> Any:
    """The check of a value 0 <= x <= 1 that the correction assumes."""

    def check(value: Any) -> float:
        result = number(name, value)
        if not 0.0 <= result <= 1.0:
            shown = value if isinstance(value, str) else shown_value(value)
            raise ValueError(f"{name} must satisfy 0 <= {name} <= 1 (got {shown})")
        return result
    return check


@dataclass(frozen=True)
class SphereCorrection(Options):
    """
    ``virtspec sphere``'s own flags: the reading corrected by the sphere theory
    (:meth:`~virtspec_mi.instruments.sphere.result.SphereResult.corrected`) and what the correction
    assumes (each of those implies ``--correct``).
    """

    title: ClassVar[str] = "correction by the sphere theory"

    correct: bool = option(False, true_or_false("correct"),
                           "also print the reading corrected by the sphere theory (the hemispherical value it "
                           "implies) and its interval, beside the reading (--json: corrected, corrected_interval)")
    specular_reflectance: float | None = option(
        None, _fraction("specular_reflectance"), "the specimen's specular (mirror) reflectance at the beam's angle, "
        "0 ... 1 (reflectance readings; default 0: a matte specimen); implies --correct")
    sample_reflectance: float | None = option(
        None, _fraction("sample_reflectance"), "the specimen's reflectance for diffuse light from inside the "
        "sphere, 0 ... 1 (required for a transmittance reading; a reflectance reading: default the corrected value "
        "itself, a Lambertian specimen); implies --correct")
    collimated_transmittance: float | None = option(
        None, _fraction("collimated_transmittance"), "the unscattered part of a transmittance reading, 0 ... 1 "
        "(default 0); implies --correct")
    budget: bool = option(False, true_or_false("budget"),
                          "also print the error budget: reading - hemispherical split into its sources (port walls, "
                          "holder, beam, wall, field of view, substitution, the ideal sphere's ports, interactions), "
                          "each a certified difference of two readings of the same rays (--json: budget)")

    def assumptions(self) -> dict[str, float] | None:
        """What the correction assumes (the values given), or ``None`` when no correction is asked for."""

        given = {name: getattr(self, name) for name in self.names()
                 if name not in ("correct", "budget") and getattr(self, name) is not None}
        return given if (self.correct or given) else None


def _respond_sphere(session: Session) -> int:
    """``virtspec sphere``: the summary, and with ``--correct`` the corrected readings beside the readings."""

    assumptions = session.flags.assumptions()
    result = session.take()
    text, data = result.summary(), None
    if assumptions is not None:
        corrected, interval = _corrected(result, assumptions)
        text += "\n" + _correction_table(result, corrected, interval, assumptions)
        data = {**result.as_dict(), "corrected": plain_data(corrected), "corrected_interval": plain_data(interval),
                "correction": assumptions}
    if session.flags.budget:
        budget = result.budget(lambda sphere, **options: session.take(sphere=sphere, **options))
        text += "\n" + budget.summary()
        data = {**(data or result.as_dict()), "budget": budget.as_dict()}
    return session.report(result, text, session.draw(result), data)


def _corrected(result: Any, assumptions: dict[str, float]) -> tuple[Any, Any]:
    """
    :meth:`~virtspec_mi.instruments.sphere.result.SphereResult.corrected` and
    :meth:`~virtspec_mi.instruments.sphere.result.SphereResult.corrected_interval` of every reading
    of ``result`` (one spectrum per θi and parameter point), over its reading dims.
    """

    dims = list(result.reading_dims)
    other = [d for d in dims if d != "wavelength"]
    values, interval = np.full(np.shape(result.reading), np.nan), np.full(np.shape(result.reading_interval), np.nan)
    for index in np.ndindex(*(result.sizes[d] for d in other)):
        spectrum = result.isel(dict(zip(other, index)))
        at = tuple(index[other.index(d)] if d in other else slice(None) for d in dims)
        try:
            values[at] = spectrum.corrected(**assumptions)
            interval[at] = spectrum.corrected_interval(**assumptions)
        except ValueError as error:  # what the sphere theory needs to be told (e.g. a transmittance reading)
            raise ValueError(f"--correct: {error}") from None
    return values, interval


def _correction_table(result: Any, corrected: Any, interval: Any, assumptions: dict[str, float]) -> str:
    """Each reading with its interval, beside the corrected reading with its interval, and the hemispherical value."""

    taken = {"specular_reflectance": "0 (matte)", "sample_reflectance": "the corrected value (Lambertian)",
             "collimated_transmittance": "0"}
    if result.options["measurement"] == "reflectance":
        del taken["collimated_transmittance"]
    else:
        del taken["specular_reflectance"]
    taken.update({name: f"{value:g}" for name, value in assumptions.items()})
    labels = list(result.reading_dims)
    lines = ["corrected by the sphere theory (" + ", ".join(f"{name} = {value}" for name, value in taken.items())
             + "; the theory's sphere: flat ports, no baffle): the hemispherical value each reading implies, and",
             f"the reading interval's image: it holds the corrected expected reading with probability >= "
             f"{1 - result.delta:g} (the theory's own error is not in it)",
             " ".join(f"{'lambda/nm' if d == 'wavelength' else d:>10}" for d in labels)
             + "    reading  [interval]              corrected  [interval]              hemispherical"]
    reading, bounds = result.reading, result.reading_interval
    for index in np.ndindex(*(result.sizes[d] for d in labels)):
        at = " ".join(f"{float(np.atleast_1d(result.coords[d])[k]):>10g}" for d, k in zip(labels, index))
        lines.append(f"{at}    {reading[index]:.5f}  [{bounds[index][0]:.5f}, {bounds[index][1]:.5f}]    "
                     f"{corrected[index]:.5f}  [{interval[index][0]:.5f}, {interval[index][1]:.5f}]    "
                     f"{result.hemispherical[index]:.5f}")
    return "\n".join(lines)


SPHERE_COMMAND = Command(
    "sphere", "an integrating sphere's readout (sample over standard)",
    "Simulate an integrating-sphere instrument reading the scene's specimen: the detector fractions with the "
    "sample and with the reference standard, their certified ratio (the reading), the hemispherical reading of "
    "the same rays and the instrument error; with --correct also the reading corrected by the sphere theory, "
    "with its interval. The sphere comes from the scene's integrating_sphere integrator.",
    ("virtspec sphere sphere_150mm_8d --specular SCE --rays 20000",
     "virtspec sphere sphere_150mm_8d --method comparison --wavelengths 400:700:100 --rays 20000 "
     "--correct --out r.json"),
    figures=(FigureFlag("--plot", "spectra", "the reading and the hemispherical value of the same rays over wavelength, "
                                      "with their certified bands; several theta_i: one figure per angle, "
                                      "FIG_<deg>deg.png", dim="theta_i"),),
    flags=SphereCorrection, function="sphere_measure", respond=_respond_sphere,
    scene="Mitsuba XML scene with an integrating_sphere integrator and 'emitter' and 'specimen' disks, or a "
          "shipped scene's name (virtspec scenes)")


class IntegratingSphere(Instrument):
    """
    The integrating sphere (see the module docstring): both configurations of every
    reading (wavelength × θi × specimen parameter point) in one keyed run of the engine —
    reading k of a configuration traces the global rays [k·N, k·N + N) with the settings'
    seed, the same rays in both (two reading groups of one plan) — each with the settings'
    rule's N at (μ, δ/2) (or ``settings.rays``), or sized per reading by a two-stage pilot
    of its detector fraction at δ/2; the result is a
    :class:`~virtspec_mi.instruments.sphere.result.SphereResult`.
    """

    name: ClassVar[str] = "sphere"
    exports: ClassVar[tuple[str, ...]] = ("Sphere", "Port", "Baffle", "SphereResult", "SphereOptions")
    options: ClassVar[type[Options] | None] = SphereOptions
    result: ClassVar[type] = SphereResult
    commands: ClassVar[tuple[Command, ...]] = (SPHERE_COMMAND,)
    integrators: ClassVar[dict[str, str]] = {
        "integrating_sphere": "virtspec_mi.instruments.sphere.integrator:IntegratingSphereIntegrator"}
    example: ClassVar[dict[str, Any]] = {
        "scene": "sphere_150mm_8d", "wavelengths": [450, 650], "rays": 4000, "seed": 3,
        "long": {"wavelengths": "400:2500:20", "rays": 40_000, "method": "comparison", "readings": 212}}

    def init(self, bench: Any, settings: Settings, options: SphereOptions, theta_i: np.ndarray,
             parameters: ParameterSpace | None) -> Plan:
        """The configurations (holders and port fates), the beam through the entrance port at every θi, the budget."""

        if options.sphere is None:
            raise ValueError("a sphere reading needs a sphere: an 'integrating_sphere' integrator in the scene or "
                             "sphere=Sphere(...)")
        sphere = options.sphere
        setups = configurations(sphere, options, bench.geometry.specimen_radius)
        for angle in theta_i:
            _check_beam(sphere, options, settings.updated(theta_i=float(angle)), setups["sample"][0][0].frame)
        if options.tolerance is not None:  # a pilot first sizes both configurations for the reading's tolerance
            if options.detector == "expected" or settings.rays is not None or settings.adaptive:
                raise ValueError(f"tolerance = {options.tolerance:g} sizes the rays from a pilot of counted detector "
                                 "fractions: give it " + spoken("without rays, without a two-stage bound and with "
                                                                "detector='counted'",
                                                                "without --rays, without --bound two-stage and with "
                                                                "--detector counted"))
            pilot = settings.pilot_rays or TOLERANCE_PILOT_RAYS
            settings = settings.updated(rays=pilot)  # the pilot's rays; process sizes the reading's from its counts
        if not settings.adaptive and settings.rays is None:  # each detector fraction at delta/2
            settings = settings.updated(rays=settings.updated(delta=settings.delta / DETECTOR_COLUMNS.share)
                                        .rays_per_reading)
        if options.detector == "expected" and settings.adaptive and settings.rays is None:
            raise ValueError("detector='expected' takes a number of rays fixed before the run (rays=N, or the "
                             "rule's N at (mu, delta/2) without adaptive): the two-stage pilot sizes counted "
                             "detector fractions")
        build = expected_layout if options.detector == "expected" else Sphere.layout
        layouts = tuple(build(sphere, holders, caps, options.max_bounces, settings.wavelengths)
                        for holders, caps in (setups[name] for name in CONFIGURATIONS))
        self.bench, self.sphere_options = bench, options
        detected = layouts[0].codes_of(SphereFate.DETECTED)  # the detector fraction: a two-stage column
        self.plan = Plan(settings.updated(theta_i=float(theta_i[0])), theta_i, parameters, groups=CONFIGURATIONS,
                         hooks=layouts, columns=Columns(DETECTOR_COLUMNS, bins=(detected,)), scene=self.scene,
                         instrument=self.name, options={"sphere": sphere.parameters(), **options.as_dict()})
        return self.plan

    def process(self, plan: Plan, *, checkpoint: Any = None, progress: bool | None = False,
                runner: Any = None) -> Tally:
        """
        The plan traced; with ``tolerance``, ``plan`` is the pilot's (its rays, the seed's
        second stream: :func:`~virtspec_mi.budgets.twostage.stage_two_seed`), whose detector
        counts size the reading's N (:func:`~virtspec_mi.budgets.ratio.ratio_rays`, the most
        any reading needs), then the reading itself is traced at the settings' seed with N
        rays — the counts of the same call with ``rays=N`` — its pilot's counts kept beside.
        """

        tolerance = self.sphere_options.tolerance
        if tolerance is None:
            return super().process(plan, checkpoint=checkpoint, progress=progress, runner=runner)
        settings = plan.settings
        pilot = super().process(replace(plan, settings=settings.updated(seed=stage_two_seed(settings.seed))),
                                progress=progress, runner=runner)
        detected = _named_counts(self.sphere_options.sphere, plan.hook(0), pilot.bins, pilot.sums)["detected"]
        half = len(detected) // 2  # flat readings: the sample's, then the standard's (engine.plan)
        standard = 1.0 if self.sphere_options.measurement == "transmittance" else self.sphere_options.standard
        rays = ratio_rays(detected[:half], detected[half:], int(settings.rays), tolerance, standard, settings.delta,
                          settings.pilot_delta_value)
        self.plan = replace(plan, settings=settings.updated(rays=int(rays.max())))
        tally = super().process(self.plan, checkpoint=checkpoint, progress=progress, runner=runner)
        return replace(tally, pilot=pilot.counts)

    def postprocess(self, tally: Tally) -> SphereResult:
        """The readout: named counts of both configurations over the readings' dims, the sphere and its mode."""

        plan, sphere = self.plan, self.sphere_options.sphere
        dims, coords = reading_labels(plan, theta_dim=False)
        named = {**_named_counts(sphere, plan.hook(0), tally.bins, tally.sums), "rays": tally.counts.rays}
        counts = {name: {key: reading_grid(plan, values, g, theta_dim=False) for key, values in named.items()}
                  for g, name in enumerate(CONFIGURATIONS)}
        pilot = None if tally.pilot is None else {  # its stored counts (absorbed: what the others leave)
            name: {key: reading_grid(plan, values, g, theta_dim=False) for key, values in tally.pilot.as_dict().items()
                   if key not in ("largest_weight", "absorbed")} for g, name in enumerate(CONFIGURATIONS)}
        shape = counts["sample"]["rays"].shape
        rho_w = sphere.wall_reflectance_at(plan.wavelengths).reshape(-1, *(1,) * (len(shape) - 1))
        return SphereResult(dims=dims, coords=coords, counts=counts, pilot=pilot,
                            wall_reflectance=np.broadcast_to(rho_w, shape).astype(np.float64),
                            sphere=sphere.describe(), cap_fractions=sphere.cap_fractions,
                            options=self.sphere_options.as_dict(), settings=plan.settings, seconds=tally.seconds,
                            scene=self.scene, sphere_parameters=sphere.parameters(),
                            specimen_radius=float(self.bench.geometry.specimen_radius),
                            parameters=None if plan.parameters is None else plan.parameters.as_dict(),
                            source=self.source)

    def warn_if_uncertified(self, result: SphereResult, stacklevel: int = 2) -> None:
        """
        A ``RuntimeWarning`` where no light reached the detector in the standard
        configuration: the reading ρ_std·p_sample/p_standard is undefined there, never a
        silent NaN (those readings are not certified).
        """

        dark = result.no_light
        if np.any(dark):
            at = [float(w) for w in np.asarray(result.coords["wavelength"]).reshape(-1)[
                np.unique(np.nonzero(dark)[0])]]
            warnings.warn(f"not certified: no light reached the detector in {int(np.sum(dark))} of {dark.size} "
                          f"readings (the standard configuration's detector count is 0, at wavelength "
                          f"{', '.join(f'{w:g}' for w in at[:5])}{' ...' if len(at) > 5 else ''} nm): their reading "
                          "sample/standard is undefined; check the sphere (wall reflectance, ports, baffle) or trace "
                          "more rays", RuntimeWarning, stacklevel=stacklevel + 1)


def _named_counts(sphere: Sphere, layout: Any, bins: np.ndarray, sums: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Per-reading counts by name from the walk's bins (readings, hemisphere · codes + fate) and sums."""

    cross = bins.reshape(len(bins), len(HEMISPHERES), layout.codes)  # (reading, hemisphere, code)
    by_code = cross.sum(axis=1)
    out = {name: by_code[:, k] for k, name in enumerate(FATES)}
    for j, port in enumerate(sphere.ports):
        out[f"lost_{port.name}"] = by_code[:, SphereFate.lost(j)]
    upper, lower, specular = (HEMISPHERES.index(h) for h in ("upper", "lower", "specular"))
    out["hemispherical_reflected"] = cross[:, upper, :].sum(axis=1) + cross[:, specular, :].sum(axis=1)
    out["hemispherical_specular"] = cross[:, specular, :].sum(axis=1)  # reflected by a delta event (part of the above)
    out["hemispherical_transmitted"] = cross[:, lower, :].sum(axis=1)
    detected = int(SphereFate.DETECTED)
    out["detected_from_upper"] = cross[:, upper, detected] + cross[:, specular, detected]
    out.update(sums)
    return {k: np.asarray(v, dtype=np.int64) for k, v in out.items()}

