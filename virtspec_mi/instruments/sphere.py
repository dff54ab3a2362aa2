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
import time
from dataclasses import replace
from typing import Any

import numpy as np

from virtspec_mi.geometry.sphere import Sphere, SphereSettings
from virtspec_mi.results.sphere import SphereResult
from virtspec_mi.settings import Settings

__all__ = ["measure_sphere", "configurations"]

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
    for named in counts.values():  # N per configuration and reading
        named["rays"] = np.full(wavelengths.shape, int(rays), dtype=np.int64)
    return SphereResult(dims=("wavelength",), coords={"wavelength": wavelengths,
                                                      "theta_i": np.asarray(settings.theta_i, dtype=np.float64)},
                        counts=counts, wall_reflectance=np.asarray(rho_w, dtype=np.float64), sphere=sphere.describe(),
                        cap_fractions=sphere.cap_fractions, options=options.as_dict(), settings=settings,
                        seconds=seconds, scene=scene, sphere_parameters=sphere.parameters(),
                        specimen_radius=float(radius))


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
