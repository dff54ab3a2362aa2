"""
The double integrating sphere: R and T of one specimen read at once, with the cross-talk
========================================================================================

A double-sphere instrument (IAD's double-sphere configuration; Pickering et al. 1993;
leaf instruments such as the SpectroClip-TR of Mõttus, Hovi & Rautiainen 2017) clamps
the specimen between two spheres: the **reflectance sphere** (the specimen in its
``sample`` port, the beam through its ``entrance`` port, its ``detector``) and the
**transmittance sphere** behind it (the specimen at its ``entrance`` port, its
``detector``; a ``sample`` port there holds the white standard, as in the single
sphere's transmittance reading). Both detectors read the same rays, and light passes
between the spheres through the specimen as often as the specimen lets it: the walk
(:mod:`virtspec_mi.instruments.sphere.double_walk`) follows every ray through both.

**Configurations** (three reading groups of one plan, the same rays in each):

- ``sample``: the specimen between the two spheres;
- ``standard``: the reflectance standard (Lambertian, ``standard``) in its place;
- ``open``: the sample position empty (the 100 % transmittance reading, with both spheres
  in place: the "empty sample port" of Mõttus et al. 2017).

**Readings:** M_R = ρ_std · p_R(sample) / p_R(standard) and M_T = p_T(sample) / p_T(open)
(p: a detector's fraction, m/N of its configuration's N rays). **Certificate:** each of
the four detector fractions gets a Clopper–Pearson interval at δ/4; all four hold together
with probability ≥ 1 − δ by the union bound, whatever their dependence, so both readings'
intervals [ρ_std·p⁻/q⁺, ρ_std·p⁺/q⁻] hold together. N is the settings' rule at (μ, δ/4)
(or ``rays``); a two-stage rule is refused.

The same specimen's **single-sphere readings** are each sphere alone:
:meth:`DoubleSphereOptions.single` gives the reflectance sphere's reflectance reading
and the transmittance sphere's transmittance reading (the ``sphere`` instrument, the same
settings), side by side with the double sphere's (:func:`single_and_double`).

Both spheres are ideal (knife-edge circular ports, Lambertian walls, baffles allowed);
port walls, shaped ports, holders' masks, detectors' fields of view, traced beams and
wall BSDFs (:mod:`virtspec_mi.instruments.sphere.ports`) are refused here.

References
----------
Pickering, Prahl, van Wieringen, Beek, Sterenborg & van Gemert (1993), Appl. Opt. 32(4),
399–410 (double integrating spheres); S. A. Prahl, *Inverse Adding-Doubling* manual;
Mõttus, Hovi & Rautiainen (2017), Appl. Opt. 56(3), 563–571; Hovi, Forsström, Mõttus &
Rautiainen (2018), Remote Sens. 10(1), 25; Clopper & Pearson (1934).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from virtspec_mi.budgets.rules import Columns
from virtspec_mi.engine.parameters import ParameterSpace
from virtspec_mi.engine.plan import Plan
from virtspec_mi.engine.tally import Tally
from virtspec_mi.instruments.base import Instrument, reading_grid, reading_labels
from virtspec_mi.instruments.command import Command, FigureFlag
from virtspec_mi.instruments.sphere.double_result import CONFIGURATIONS, DoubleSphereResult
from virtspec_mi.instruments.sphere.double_walk import DoubleSphereLayout
from virtspec_mi.instruments.sphere.geometry import Sphere, is_sphere_parameter, sphere_from_parameters
from virtspec_mi.instruments.sphere.walk import FATES, HEMISPHERES, SPECIMEN, Holder, SphereFate, holder_frame
from virtspec_mi.settings import Options, Settings, one_of, option, share, whole_number

__all__ = ["TRANSMITTANCE_PREFIX", "DOUBLE_COLUMNS", "DoubleSphereOptions", "DoubleSphere", "double_layout",
           "single_and_double"]

TRANSMITTANCE_PREFIX: str = "t_"
"""The transmittance sphere's integrator parameters: the single sphere's with this prefix (``t_diameter`` …)."""

DOUBLE_COLUMNS: Columns = Columns("the detector fraction of each sphere in its two configurations", 4)
"""The four detector fractions a double-sphere reading certifies, each at δ/4."""

_SPECULAR = {"SCI": "the reflectance sphere's specular port plugged with wall material",
             "SCE": "the reflectance sphere's specular port open to a light trap"}


def _check_sphere(name: str) -> Any:
    def check(value: Any) -> Sphere:
        if not isinstance(value, Sphere):
            raise ValueError(f"{name} must be a virtspec_mi.Sphere (got {type(value).__name__})")
        return value
    return check


@dataclass(frozen=True)
class DoubleSphereOptions(Options):
    """
    How a double-sphere reading is taken, and its two spheres (the ``double_sphere``
    integrator's parameters: the reflectance sphere's are the single sphere's —
    ``diameter``, ``wall_reflectance``, ``port_<name>``, ``baffle`` — the transmittance
    sphere's the same with the prefix ``t_``: ``t_diameter``, ``t_wall_reflectance``,
    ``t_port_<name>``, ``t_baffle``).
    """

    title: ClassVar[str] = "double-sphere options"

    standard: float = option(0.99, share("standard"),
                             "reflectance of the Lambertian reference standard, 0 < standard <= 1")
    specular: str = option("SCI", one_of("specular", _SPECULAR, fold=str.upper),
                           "the reflectance sphere's specular port (if any): SCI plugged, SCE open", _SPECULAR)
    max_bounces: int = option(100_000, whole_number("max_bounces", 1, 10**7, "1 <= max_bounces <= 10**7"),
                              "step cap of a walk through both spheres, 1 ... 10**7 (capped walks are counted)")
    sphere: Sphere | None = option(None, _check_sphere("sphere"),
                                   "the reflectance sphere (a virtspec_mi.Sphere: ports entrance, sample, detector)",
                                   flag=False)
    transmittance_sphere: Sphere | None = option(
        None, _check_sphere("transmittance_sphere"),
        "the transmittance sphere (a virtspec_mi.Sphere: ports entrance — where the specimen sits — and detector; "
        "a sample port holds the standard)", flag=False)

    @classmethod
    def _gathered(cls, parameters: Any) -> dict[str, Any]:
        keys = list(parameters.keys())
        out: dict[str, Any] = {}
        if any(is_sphere_parameter(name) for name in keys):
            out["sphere"] = sphere_from_parameters({k: parameters.get(k) for k in keys if is_sphere_parameter(k)})
        prefixed = {k[len(TRANSMITTANCE_PREFIX):]: parameters.get(k) for k in keys
                    if k.startswith(TRANSMITTANCE_PREFIX) and is_sphere_parameter(k[len(TRANSMITTANCE_PREFIX):])}
        if prefixed:
            out["transmittance_sphere"] = sphere_from_parameters(prefixed)
        return out

    @classmethod
    def _gathers(cls, name: str) -> bool:
        return is_sphere_parameter(name) or (name.startswith(TRANSMITTANCE_PREFIX)
                                             and is_sphere_parameter(name[len(TRANSMITTANCE_PREFIX):]))

    def as_dict(self) -> dict[str, Any]:
        """How the reading is taken, as plain data (the spheres are recorded apart)."""

        return {k: v for k, v in super().as_dict().items() if k not in ("sphere", "transmittance_sphere")}

    def spheres(self) -> tuple[Sphere, Sphere]:
        """Both spheres, checked for what a double sphere needs (``ValueError`` naming what is missing)."""

        r, t = self.sphere, self.transmittance_sphere
        if r is None or t is None:
            raise ValueError("a double-sphere reading needs two spheres: sphere (the reflectance sphere) and "
                             "transmittance_sphere (as integrator parameters: diameter, port_<name> … and "
                             "t_diameter, t_port_<name> …)")
        for name, sphere, roles in (("sphere", r, ("entrance", "sample", "detector")),
                                    ("transmittance_sphere", t, ("entrance", "detector"))):
            missing = [role for role in roles if sphere.port(role) is None]
            if missing:
                raise ValueError(f"{name}: a double sphere needs ports with roles {', '.join(roles)} (missing "
                                 f"{', '.join(missing)}; ports: {[p.name for p in sphere.ports]})")
            real = [p.name for p in sphere.ports if p.depth or p.shape != "circle" or p.aperture is not None
                    or p.field_of_view is not None or p.proud]
            if real or sphere.beam_profile is not None or sphere.wall_specular or sphere.wall_bsdf is not None:
                raise ValueError(f"{name}: a double sphere takes ideal spheres (knife-edge circular ports, a "
                                 f"Lambertian wall); not port walls, shapes, masks or fields of view (ports "
                                 f"{real}), a beam profile, a wall specular share or a wall BSDF")
        return r, t

    def single(self) -> tuple[dict[str, Any], dict[str, Any]]:
        """
        The ``sphere`` instrument's options of the same specimen's single-sphere readings:
        the reflectance sphere alone (``measurement="reflectance"``) and the transmittance
        sphere alone (``measurement="transmittance"``: the specimen at its entrance port).
        """

        r, t = self.spheres()
        common = {"standard": self.standard, "max_bounces": self.max_bounces}
        return ({"sphere": r, "measurement": "reflectance", "specular": self.specular, **common},
                {"sphere": t, "measurement": "transmittance", **common})


def _rigid(r: Sphere, t: Sphere) -> tuple[np.ndarray, np.ndarray]:
    """
    (M, c): the transmittance sphere's coordinates → the reflectance sphere's, x ↦ M x + c,
    its entrance port's plane on the reflectance sphere's sample-port plane, the axes
    opposite and the specimen's frame shared.
    """

    sample, entrance = r.port("sample"), t.port("entrance")
    m = holder_frame(sample.axis, False) @ holder_frame(entrance.axis, True).T
    c = r.port_plane_centre(sample) - m @ t.port_plane_centre(entrance)
    return m, c


def double_layout(r: Sphere, t: Sphere, configuration: str, specimen_radius: float, options: DoubleSphereOptions,
                  wavelengths: Any, specimen_bsdf: Any = SPECIMEN) -> DoubleSphereLayout:
    """
    One configuration (``sample``, ``standard`` or ``open``) of the two spheres as the
    kernel walks it (:class:`~virtspec_mi.instruments.sphere.double_walk.DoubleSphereLayout`):
    both in the reflectance sphere's coordinates, the ports numbered the reflectance
    sphere's first.
    """

    m, shift = _rigid(r, t)
    n_r = len(r.ports)
    grid = np.unique(np.asarray(wavelengths, dtype=np.float64))
    sample, entrance = r.port("sample"), t.port("entrance")
    i_sample, i_entrance = r.ports.index(sample), n_r + t.ports.index(entrance)
    specimen_frame = holder_frame(sample.axis, False)
    axis_r = tuple(float(v) for v in sample.axis)
    axis_t = tuple(float(v) for v in m @ entrance.axis)
    centre = tuple(float(v) for v in r.port_plane_centre(sample))
    offset_r = r.radius * sample.cos_half_angle(r.radius)  # as the single sphere's plane: the same floats
    offset_t = float(np.dot(axis_t, centre))
    disk = {"sample": specimen_bsdf, "standard": {"type": "diffuse", "reflectance": options.standard},
            "open": {"type": "null"}}[configuration]
    radius = specimen_radius if configuration != "open" else min(sample.radius, entrance.radius)
    holders = [Holder(i_sample, disk, radius, specimen_frame)]
    planes = [(axis_r, offset_r, centre, 0, 0, 1, float(entrance.radius), i_sample),
              (axis_t, offset_t, centre, 1, 0, 0, float(sample.radius), i_entrance)]
    standard = {"type": "diffuse", "reflectance": options.standard}
    white = t.port("sample")
    if white is not None:  # the transmittance sphere's white standard, in every configuration
        axis = m @ white.axis
        w_centre = m @ t.port_plane_centre(white) + shift
        holders.append(Holder(n_r + t.ports.index(white), standard, white.radius, holder_frame(axis, False)))
        planes.append((tuple(float(v) for v in axis), float(axis @ w_centre), tuple(float(v) for v in w_centre), 1,
                       1, -1, 0.0, n_r + t.ports.index(white)))
    caps = []
    for own, sphere, rotate, move, base in ((0, r, np.eye(3), np.zeros(3), 0), (1, t, m, shift, n_r)):
        for j, port in enumerate(sphere.ports):
            if port.role == "detector":
                action: int | None = int(SphereFate.DETECTED) if own == 0 else SphereFate.lost(base + j)
            elif port.role == "reference" or (port.role == "specular" and options.specular == "SCI"):
                action = None  # plugged with wall material
            elif own == 1 and port.role == "sample":
                action = None  # the disk in its plane catches every ray first
            else:
                action = SphereFate.lost(base + j)
            if action is not None:
                caps.append((own, tuple(float(v) for v in rotate @ port.axis),
                             sphere.radius * port.cos_half_angle(sphere.radius), int(action)))
    baffles = tuple((own, tuple(float(v) for v in rotate @ np.asarray(s.baffle.centre) + move),
                     tuple(float(v) for v in rotate @ np.asarray(s.baffle.normal)), float(s.baffle.radius))
                    for own, s, rotate, move in ((0, r, np.eye(3), np.zeros(3)), (1, t, m, shift))
                    if s.baffle is not None)
    return DoubleSphereLayout(
        radius=r.radius, ports=n_r + len(t.ports), caps=tuple(caps), planes=tuple(planes), holders=tuple(holders),
        baffle=None, max_bounces=int(options.max_bounces),
        wall=(tuple(float(w) for w in grid), tuple(float(v) for v in r.wall_reflectance_at(grid))),
        spheres=((tuple(0.0 for _ in range(3)), r.radius, True), (tuple(float(v) for v in shift), t.radius, True)),
        baffles=baffles, specimen_axis=axis_r, entries=(0, 1),
        transmittance_wall=tuple(float(v) for v in t.wall_reflectance_at(grid)))


def _check_beam(r: Sphere, theta_i: float, phi_i: float) -> None:
    """The beam axis, from the specimen's centre, must meet the reflectance sphere's wall in its entrance port."""

    theta, phi = math.radians(theta_i), math.radians(phi_i)
    local = np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])
    sample, entrance = r.port("sample"), r.port("entrance")
    hit = r.wall_point(r.port_plane_centre(sample), holder_frame(sample.axis, False) @ local)
    if r.port_at(hit) is not entrance:
        raise ValueError(f"theta_i = {theta_i:g}, phi_i = {phi_i:g}: the beam axis meets the reflectance sphere's "
                         f"wall outside its entrance port {entrance.name!r} (at {hit.round(2).tolist()} mm); give the "
                         "angles the entrance port is built for")


def port_names(r: Sphere, t: Sphere) -> list[str]:
    """The names of both spheres' ports in the walk's order: the reflectance sphere's, then ``t_<name>``."""

    return [p.name for p in r.ports] + [TRANSMITTANCE_PREFIX + p.name for p in t.ports]


DOUBLE_SPHERE_COMMAND = Command(
    "double_sphere", "a double integrating sphere: reflectance and transmittance read at once",
    "Simulate a double integrating sphere (the specimen between a reflectance sphere and a transmittance "
    "sphere) reading the scene's specimen: both detectors' fractions with the specimen, with the standard and "
    "with the sample position empty; the reflectance and transmittance readings with their certified intervals "
    "(all four fractions at delta/4), beside the hemispherical R and T of the same rays. The spheres come from "
    "the scene's double_sphere integrator.",
    ("virtspec double_sphere double_sphere_leaf --rays 20000",
     "virtspec double_sphere double_sphere_leaf --wavelengths 500:900:100 --rays 20000 --out d.json"),
    figures=(FigureFlag("--plot", "spectra", "the readings and the hemispherical values over wavelength, with their "
                                             "certified bands"),),
    scene="Mitsuba XML scene with a double_sphere integrator and 'emitter' and 'specimen' disks, or a shipped "
          "scene's name (virtspec scenes)")


class DoubleSphere(Instrument):
    """
    The double integrating sphere (see the module docstring): the three configurations of
    every reading (wavelength × θi × specimen parameter point) in one keyed run, the same
    rays in each, N the settings' rule at (μ, δ/4) or ``rays``; the result is a
    :class:`~virtspec_mi.instruments.sphere.double_result.DoubleSphereResult`.
    """

    name: ClassVar[str] = "double_sphere"
    exports: ClassVar[tuple[str, ...]] = ("DoubleSphereResult", "DoubleSphereOptions")
    options: ClassVar[type[Options] | None] = DoubleSphereOptions
    result: ClassVar[type] = DoubleSphereResult
    commands: ClassVar[tuple[Command, ...]] = (DOUBLE_SPHERE_COMMAND,)
    integrators: ClassVar[dict[str, str]] = {
        "double_sphere": "virtspec_mi.instruments.sphere.double_integrator:DoubleSphereIntegrator"}
    example: ClassVar[dict[str, Any]] = {
        "scene": "double_sphere_leaf", "wavelengths": [550, 850], "rays": 3000, "seed": 3,
        "long": {"wavelengths": "400:2500:20", "rays": 20_000, "readings": 318}}

    def init(self, bench: Any, settings: Settings, options: DoubleSphereOptions, theta_i: np.ndarray,
             parameters: ParameterSpace | None) -> Plan:
        """The three configurations' layouts and the budget (each detector fraction at δ/4)."""

        r, t = options.spheres()
        radius = float(bench.geometry.specimen_radius)
        for name, port in (("sphere", r.port("sample")), ("transmittance_sphere", t.port("entrance"))):
            if radius > port.radius * (1 + 1e-9):
                raise ValueError(f"specimen radius {radius:g} mm is larger than {name}'s port {port.name!r} "
                                 f"(radius {port.radius:g} mm): the specimen must fit in both ports")
        if settings.beam == "diffuse":
            raise ValueError("beam must be 'collimated' or 'conical' for a double-sphere reading (got 'diffuse')")
        for angle in theta_i:
            _check_beam(r, float(angle), settings.phi_i)
        if not settings.adaptive and settings.rays is None:
            settings = settings.updated(rays=settings.updated(delta=settings.delta / DOUBLE_COLUMNS.share)
                                        .rays_per_reading)
        layouts = tuple(double_layout(r, t, name, radius, options, settings.wavelengths) for name in CONFIGURATIONS)
        self.bench, self.double_options = bench, options
        self.plan = Plan(settings.updated(theta_i=float(theta_i[0])), theta_i, parameters, groups=CONFIGURATIONS,
                         hooks=layouts, columns=None, scene=self.scene, instrument=self.name,
                         refusal="a double-sphere reading is sized in advance (each of its four detector fractions "
                                 "at delta/4); give mu and delta, or rays",
                         options={"sphere": r.parameters(), "transmittance_sphere": t.parameters(),
                                  **options.as_dict()})
        return self.plan

    def postprocess(self, tally: Tally) -> DoubleSphereResult:
        """Named counts of the three configurations over the readings' dims, both spheres and the options."""

        plan = self.plan
        r, t = self.double_options.spheres()
        dims, coords = reading_labels(plan, theta_dim=False)
        detector = len(r.ports) + t.ports.index(t.port("detector"))
        named = {**_named_counts(port_names(r, t), detector, plan.hook(0), tally.bins, tally.sums),
                 "rays": tally.counts.rays}
        counts = {name: {key: reading_grid(plan, values, g, theta_dim=False) for key, values in named.items()}
                  for g, name in enumerate(CONFIGURATIONS)}
        shape = counts["sample"]["rays"].shape
        walls = [np.broadcast_to(s.wall_reflectance_at(plan.wavelengths).reshape(-1, *(1,) * (len(shape) - 1)),
                                 shape).astype(np.float64) for s in (r, t)]
        return DoubleSphereResult(
            dims=dims, coords=coords, counts=counts, wall_reflectance=walls[0], transmittance_wall=walls[1],
            spheres=f"reflectance {r.describe()} | transmittance {t.describe()}",
            options=self.double_options.as_dict(), settings=plan.settings, seconds=tally.seconds, scene=self.scene,
            sphere_parameters=r.parameters(), transmittance_parameters=t.parameters(),
            specimen_radius=float(self.bench.geometry.specimen_radius),
            parameters=None if plan.parameters is None else plan.parameters.as_dict(), source=self.source)

    def warn_if_uncertified(self, result: DoubleSphereResult, stacklevel: int = 2) -> None:
        result.warn_if_uncertified(stacklevel=stacklevel + 2)


def _named_counts(ports: list[str], detector: int, layout: Any, bins: np.ndarray,
                  sums: dict[str, np.ndarray]) -> dict[str, Any]:
    """Per-reading counts by name: both detectors, the fates, each port's losses, the first hemispheres."""

    cross = bins.reshape(len(bins), len(HEMISPHERES), layout.codes)
    by_code = cross.sum(axis=1)
    out = {name: by_code[:, k] for k, name in enumerate(FATES) if name != "detected"}
    out["detected_r"] = by_code[:, int(SphereFate.DETECTED)]
    for j, name in enumerate(ports):
        out["detected_t" if j == detector else f"lost_{name}"] = by_code[:, SphereFate.lost(j)]
    upper, lower, specular = (HEMISPHERES.index(h) for h in ("upper", "lower", "specular"))
    out["hemispherical_reflected"] = cross[:, upper, :].sum(axis=1) + cross[:, specular, :].sum(axis=1)
    out["hemispherical_transmitted"] = cross[:, lower, :].sum(axis=1)
    out.update(sums)
    return {k: np.asarray(v, dtype=np.int64) for k, v in out.items()}


def single_and_double(take: Any, scene: Any, **keywords: Any) -> dict[str, Any]:
    """
    The same specimen read by the double sphere and by each sphere alone, side by side:
    ``take(instrument, scene, **keywords)`` (e.g. :func:`virtspec_mi.take`) runs the
    ``double_sphere`` reading, then the ``sphere`` instrument's reflectance reading of the
    reflectance sphere and transmittance reading of the transmittance sphere with the same
    settings (:meth:`DoubleSphereOptions.single`). Returns ``{"double": …, "reflectance": …,
    "transmittance": …}``.
    """

    double = take(DoubleSphere.name, scene, **keywords)
    options = DoubleSphereOptions(**{k: v for k, v in double.options.items() if k in DoubleSphereOptions.names()},
                                  sphere=double.sphere_description, transmittance_sphere=double.transmittance_description)
    common = {k: v for k, v in keywords.items() if k not in DoubleSphereOptions.names()}
    reflectance, transmittance = options.single()
    single = "sphere"
    return {"double": double, "reflectance": take(single, scene, **common, **reflectance),
            "transmittance": take(single, scene, **common, **transmittance)}
