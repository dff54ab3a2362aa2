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
invert the sphere theory's readout model (:mod:`virtspec_mi.references.sphere_theory` with the inputs
of :func:`virtspec_mi.references.sphere_model.theory_inputs`, from the sphere description the result
keeps) to recover the hemispherical value from the reading.

References
----------
Baranoski et al. (2001), eqs. (2), (19), (23); Clopper & Pearson (1934); Labsphere,
*Integrating sphere theory and applications* (substitution and comparison methods);
J. Kessel (1986), Appl. Opt. 25, 2752–2756 (transmittance in a one-port sphere).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from virtspec_mi.engine.plan import Plan
from virtspec_mi.engine.readings import run
from virtspec_mi.geometry.sphere import Sphere, SphereSettings
from virtspec_mi.kernel.sphere_walk import FATES, HEMISPHERES, SPECIMEN, Holder, SphereFate, holder_frame
from virtspec_mi.results.sphere import CONFIGURATIONS, SphereResult
from virtspec_mi.settings import Settings

__all__ = ["measure_sphere", "configurations"]


def configurations(sphere: Sphere, options: SphereSettings, specimen_radius: float,
                   specimen_bsdf: Any = SPECIMEN) -> dict[str, tuple[list, list]]:
    """
    Per configuration: the holders (port index, BSDF, disk radius, frame) — holder 0 in
    the beam — and each port's cap fate (a :class:`~virtspec_mi.kernel.sphere_walk.SphereFate`
    code, ``None`` for a plugged port). The specimen's BSDF is ``specimen_bsdf`` (by
    default :data:`~virtspec_mi.kernel.sphere_walk.SPECIMEN`: the bench's), the standard
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
    *Transitional* (until the sphere instrument builds its plan): the sphere readings of
    ``instrument``'s specimen at every wavelength of ``settings`` (see the module
    docstring): both configurations, one keyed run of the engine
    (:func:`virtspec_mi.engine.readings.run`; reading k of a configuration traces the
    global rays [k·N, k·N + N) with the settings' seed, the same rays in both), each with
    the settings' rule's N at (μ, δ/2) (or ``settings.rays``).
    """

    if settings.rays is None and settings.budget.adaptive:
        raise ValueError("bound='two-stage' is not available for sphere readings (each configuration is sized "
                         "in advance): use hoeffding, chebyshev or exact, or give rays")
    rays = settings.rays if settings.rays is not None else settings.updated(delta=settings.delta / 2).rays_per_reading
    radius = instrument.geometry.specimen_radius
    setups = configurations(sphere, options, radius)
    frame = setups["sample"][0][0].frame
    _check_beam(sphere, options, settings, frame)
    wavelengths = np.asarray(settings.wavelengths, dtype=np.float64)
    layouts = tuple(sphere.layout(holders, actions, options.max_bounces, wavelengths)
                    for holders, actions in (setups[name] for name in CONFIGURATIONS))
    plan = Plan(settings.updated(rays=rays), (settings.theta_i,), groups=CONFIGURATIONS, hooks=layouts, scene=scene,
                instrument="sphere", options={"sphere": sphere.parameters(), **options.as_dict()},
                refusal="each configuration is sized in advance")
    tally = run(instrument, plan, keyed=True)
    n = len(wavelengths)
    counts = {name: _named_counts(sphere, layouts[g], tally.bins[g * n:(g + 1) * n],
                                  {key: value[g * n:(g + 1) * n] for key, value in tally.sums.items()})
              for g, name in enumerate(CONFIGURATIONS)}
    for named in counts.values():  # N per configuration and reading
        named["rays"] = np.full(wavelengths.shape, int(rays), dtype=np.int64)
    rho_w = sphere.wall_reflectance_at(wavelengths)
    return SphereResult(dims=("wavelength",), coords={"wavelength": wavelengths,
                                                      "theta_i": np.asarray(settings.theta_i, dtype=np.float64)},
                        counts=counts, wall_reflectance=np.asarray(rho_w, dtype=np.float64), sphere=sphere.describe(),
                        cap_fractions=sphere.cap_fractions, options=options.as_dict(), settings=settings,
                        seconds=tally.seconds, scene=scene, sphere_parameters=sphere.parameters(),
                        specimen_radius=float(radius))


def _named_counts(sphere: Sphere, layout: Any, bins: np.ndarray, sums: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Per-wavelength counts by name from the walk's bins (readings, hemisphere · codes + fate) and sums."""

    cross = bins.reshape(len(bins), len(HEMISPHERES), layout.codes)  # (wavelength, hemisphere, code)
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
