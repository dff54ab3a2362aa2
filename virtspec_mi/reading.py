"""
Certified readings: :func:`measure` and :class:`Reading`
========================================================

:func:`measure` takes a scene (XML path, dict or ``mi.Scene``), resolves the
settings (explicit arguments, then the scene's ``spectrophotometer`` integrator,
then the paper's defaults), sizes each reading with the ray budget and returns a
:class:`Reading`: reflectance ρ = m/N (eq. 2), transmittance τ and absorptance
α = 1 − ρ − τ per wavelength, with the exact counts behind them.

With N from eq. (23) (or the ``exact`` and ``two-stage`` budgets), each of ρ and τ is
within μ of its expectation with probability ≥ 1 − δ (each on its own; ``joint=True``
certifies the pair together by giving each δ/2). Every reading also carries the
Clopper–Pearson interval of ρ, τ and α at the δ of each quantity.

References
----------
Baranoski et al. (2001), eqs. (1), (2) and (23); Sect. 3.2.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

import virtspec_mi
from virtspec_mi.geometry import InstrumentGeometry, backlit_fraction
from virtspec_mi.instrument import find_instrument
from virtspec_mi.intervals import clopper_pearson
from virtspec_mi.settings import Settings
from virtspec_mi.tally import take_readings

__all__ = ["Reading", "measure", "uncertified_lines", "warn_if_uncertified"]


@dataclass(frozen=True)
class Reading:
    """
    A certified spectrophotometer reading at one incidence, over wavelength.

    Attributes
    ----------
    wavelengths : ndarray
        Wavelengths in nm, in the order requested.
    reflectance, transmittance, absorptance : ndarray
        ρ = m/N, τ = t/N and α = 1 − ρ − τ per wavelength (exactly, from counts).
    reflected, transmitted, absorbed : ndarray of int64
        Ray counts per wavelength (absorbed = rays − reflected − transmitted − capped).
    rays : ndarray of int64
        Rays N per wavelength behind the estimates (equal for a fixed bound; each
        reading's own second batch N₂ for ``two-stage``).
    pilot_rays : ndarray of int64 or None
        Two-stage pilot rays per wavelength (spent, not in the estimates); ``None`` for
        a fixed bound. ``rays_spent`` = rays + pilot_rays.
    weight_violations : ndarray of int64
        Rays whose BSDF weight was outside [0, 1] or NaN (0 for a valid specimen).
    capped : ndarray of int64
        Rays whose random walk hit the specimen's step cap (see :mod:`virtspec_mi.walk`):
        counted in none of the three fates, so ρ + τ + α = 1 − capped/N.
    backlit_fraction : float
        Share of the emitter area below the specimen plane (conical beam, θi > atan(D/r₁)):
        those rays strike the specimen's back face.
    seconds : float
        Wall time of the measurement (tracing and tallies).
    settings : Settings
        The settings used (μ, δ, bound, beam, sampling, seed, θi, φi).
    geometry : InstrumentGeometry
        r₁, r₂ and D of the scene.
    specular_reflected, regular_transmitted : ndarray of int64
        The reflected and the transmitted rays whose sampled event was a delta event
        (``DeltaReflection`` or ``DeltaTransmission``; part of ``reflected`` /
        ``transmitted``). For ``turbid_slab``: rays that left without
        scattering (top-face specular reflection, MCML's Rsp, plus unscattered internal
        bounces; unscattered transmission). See :attr:`specular_reflectance`,
        :attr:`diffuse_reflectance`, :attr:`regular_transmittance`,
        :attr:`diffuse_transmittance`.
    wavelength_independent : bool
        True when the specimen declared itself wavelength-independent: it was traced
        once and every wavelength reports the same counts (see :mod:`virtspec_mi.tally`).
    """

    wavelengths: np.ndarray
    reflectance: np.ndarray
    transmittance: np.ndarray
    absorptance: np.ndarray
    reflected: np.ndarray
    transmitted: np.ndarray
    absorbed: np.ndarray
    rays: np.ndarray
    weight_violations: np.ndarray
    capped: np.ndarray
    backlit_fraction: float
    seconds: float
    settings: Settings
    geometry: InstrumentGeometry
    version: str = field(default=virtspec_mi.__version__)
    specular_reflected: np.ndarray | None = None
    regular_transmitted: np.ndarray | None = None

    @property
    def specular_reflectance(self) -> np.ndarray:
        """ρs: reflected by a mirror (delta) event, per wavelength (CIE regular reflectance; MCML Rsp)."""

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
    wavelength_independent: bool = False
    pilot_rays: np.ndarray | None = None

    @property
    def theta_i(self) -> float:
        return self.settings.theta_i

    @property
    def phi_i(self) -> float:
        return self.settings.phi_i

    @property
    def mu(self) -> float:
        return self.settings.mu

    @property
    def delta(self) -> float:
        return self.settings.delta

    @property
    def bound(self) -> str:
        """The ray budget used: the settings' bound, or ``"rays"`` when N was given explicitly."""

        return self.settings.bound if self.settings.rays is None else "rays"

    @property
    def rays_spent(self) -> np.ndarray:
        """All rays traced per wavelength (two-stage: pilot included)."""

        rays = np.broadcast_to(np.asarray(self.rays, dtype=np.int64), self.wavelengths.shape)
        return rays if self.pilot_rays is None else rays + self.pilot_rays

    @property
    def interval_delta(self) -> float:
        """δ of each interval: the reading's δ, or δ/2 with ``joint`` (R and T together at δ)."""

        return self.settings.quantity_delta

    def _interval(self, counts: np.ndarray) -> np.ndarray:
        lower, upper = clopper_pearson(counts, self.rays, self.interval_delta)
        return np.stack([lower, upper], axis=-1)

    @property
    def reflectance_interval(self) -> np.ndarray:
        """Clopper–Pearson interval ``[lower, upper]`` of ρ per wavelength, shape (n, 2)."""

        return self._interval(self.reflected)

    @property
    def transmittance_interval(self) -> np.ndarray:
        """Clopper–Pearson interval of τ per wavelength, shape (n, 2)."""

        return self._interval(self.transmitted)

    @property
    def absorptance_interval(self) -> np.ndarray:
        """Clopper–Pearson interval of α per wavelength (from the absorbed count), shape (n, 2)."""

        return self._interval(self.absorbed)

    def as_dict(self) -> dict[str, Any]:
        """Plain data with every field by name (for ``--json``)."""

        parts = {} if self.specular_reflected is None else {
            "specular_reflected": self.specular_reflected.tolist(),
            "regular_transmitted": self.regular_transmitted.tolist(),
            "specular_reflectance": self.specular_reflectance.tolist(),
            "diffuse_reflectance": self.diffuse_reflectance.tolist(),
            "regular_transmittance": self.regular_transmittance.tolist(),
            "diffuse_transmittance": self.diffuse_transmittance.tolist(),
        }
        return {
            "wavelengths": self.wavelengths.tolist(),
            "reflectance": self.reflectance.tolist(),
            "transmittance": self.transmittance.tolist(),
            "absorptance": self.absorptance.tolist(),
            "reflected": self.reflected.tolist(),
            "transmitted": self.transmitted.tolist(),
            "absorbed": self.absorbed.tolist(),
            "rays": np.asarray(self.rays).tolist(),
            "rays_spent": self.rays_spent.tolist(),
            "pilot_rays": None if self.pilot_rays is None else self.pilot_rays.tolist(),
            "bound": self.bound,
            "interval_delta": self.interval_delta,
            "reflectance_interval": self.reflectance_interval.tolist(),
            "transmittance_interval": self.transmittance_interval.tolist(),
            "absorptance_interval": self.absorptance_interval.tolist(),
            "weight_violations": self.weight_violations.tolist(),
            "capped": self.capped.tolist(),
            "backlit_fraction": self.backlit_fraction,
            "seconds": self.seconds,
            "settings": self.settings.as_dict(),
            "geometry": {
                "emitter_radius": self.geometry.emitter_radius,
                "specimen_radius": self.geometry.specimen_radius,
                "distance": self.geometry.distance,
            },
            "version": self.version,
            **parts,
            "wavelength_independent": self.wavelength_independent,
        }

    def summary(self) -> str:
        """Human-readable table of the reading."""

        s = self.settings
        incidence = (
            "cosine-weighted over the hemisphere" if s.beam == "diffuse"
            else f"theta_i = {s.theta_i:g} deg, phi_i = {s.phi_i:g} deg"
        )
        rays = np.asarray(self.rays)
        low, high = int(rays.min()), int(rays.max())
        count = f"{low:,}" if low == high else f"{low:,} to {high:,}"
        pilot = "" if self.pilot_rays is None else f" + {int(self.pilot_rays.max()):,} pilot"
        together = "R and T together" if s.joint else "|rho - m/N|"
        lines = [
            f"{s.beam} reading, {incidence}, sampling = {s.sampling}, seed = {s.seed}",
            f"N = {count}{pilot} rays per wavelength ({self.bound} bound: {together} < {s.mu:g} "
            f"with probability >= {1 - s.delta:g}); {self.seconds * 1e3:.1f} ms",
            f"{'lambda/nm':>10} {'reflectance':>12} {'transmittance':>14} {'absorptance':>12}"
            f"   Clopper-Pearson {1 - self.interval_delta:g} intervals (R; T)",
        ]
        r_int, t_int = self.reflectance_interval, self.transmittance_interval
        for i, wavelength in enumerate(self.wavelengths):
            lines.append(
                f"{wavelength:>10g} {self.reflectance[i]:>12.5f} {self.transmittance[i]:>14.5f} "
                f"{self.absorptance[i]:>12.5f}   [{r_int[i, 0]:.5f}, {r_int[i, 1]:.5f}]; "
                f"[{t_int[i, 0]:.5f}, {t_int[i, 1]:.5f}]"
                + ("" if low == high else f"  N = {int(rays[i]):,}")
            )
        mixed = False if self.specular_reflected is None else (0 < self.specular_reflected) & (self.specular_reflected < self.reflected) | (
            (0 < self.regular_transmitted) & (self.regular_transmitted < self.transmitted)
        )
        if np.any(mixed):  # a specimen with both mirror and scattered light: show the parts
            lines.append(f"{'lambda/nm':>10} {'specular R':>12} {'diffuse R':>14} {'regular T':>12} {'diffuse T':>12}")
            for i, wavelength in enumerate(self.wavelengths):
                lines.append(
                    f"{wavelength:>10g} {self.specular_reflectance[i]:>12.5f} {self.diffuse_reflectance[i]:>14.5f} "
                    f"{self.regular_transmittance[i]:>12.5f} {self.diffuse_transmittance[i]:>12.5f}"
                )
        if self.wavelength_independent and len(self.wavelengths) > 1:
            lines.append("note: wavelength-independent specimen: traced once, the same rays for every wavelength")
        if self.backlit_fraction > 0:
            lines.append(f"note: {self.backlit_fraction:.2%} of the emitter lies below the specimen plane")
        lines += uncertified_lines(self.weight_violations, self.capped)
        return "\n".join(lines)


def measure(
    scene: Any,
    *,
    theta_i: float | None = None,
    phi_i: float | None = None,
    wavelengths: float | Sequence[float] | str | None = None,
    mu: float | None = None,
    delta: float | None = None,
    rays: int | None = None,
    beam: str | None = None,
    sampling: str | None = None,
    seed: int | None = None,
    bound: str | None = None,
    chunk_size: int | None = None,
    joint: bool | None = None,
    pilot_rays: int | None = None,
    pilot_delta: float | None = None,
) -> Reading:
    """
    Measure the specimen of ``scene`` and return a certified :class:`Reading`.

    Parameters
    ----------
    scene
        XML path, scene dict or loaded ``mi.Scene`` with ``emitter`` and ``specimen`` disks.
    theta_i, phi_i
        Incidence in degrees (θi ∈ [0, 90]); default 0, 0.
    wavelengths
        nm: a number, a sequence or a string such as ``"400:700:10"``; default 551.
    mu, delta
        Certified tolerance and failure probability; default 0.005 and 0.01.
    rays
        Rays per wavelength; default from the bound (105,967 at the defaults, eq. 23).
    beam, sampling
        ``conical``/``collimated`` and ``jittered``/``random``/``concentric``.
    seed
        Random seed; the same seed gives the same counts whatever the chunking.
    bound
        ``hoeffding`` (eq. 23, default), ``chebyshev`` (eq. 15), ``exact`` (the smallest
        N certified by the exact binomial law) or ``two-stage`` (pilot + sized second
        batch per wavelength, :mod:`virtspec_mi.twostage`).
    chunk_size
        Rays per kernel launch (memory), default 2²².
    joint
        Certify reflectance and transmittance together (each at δ/2); default False.
    pilot_rays, pilot_delta
        Two-stage pilot size n₁ (default ⌈10/μ⌉) and failure probability δ₁ (default δ/10).

    Any argument left ``None`` comes from the scene's ``spectrophotometer``
    integrator when it has one, else from the defaults above.

    References
    ----------
    Baranoski et al. (2001), eqs. (2), (23).
    """

    instrument = find_instrument(scene)
    base = instrument.integrator.settings if instrument.integrator is not None else Settings()
    settings = base.updated(
        theta_i=theta_i, phi_i=phi_i, wavelengths=wavelengths, mu=mu, delta=delta, rays=rays,
        beam=beam, sampling=sampling, seed=seed, bound=bound, chunk_size=chunk_size,
        joint=joint, pilot_rays=pilot_rays, pilot_delta=pilot_delta,
    )
    start = time.perf_counter()
    tallies = take_readings(
        instrument, [(w, settings.theta_i, settings.phi_i) for w in settings.wavelengths], settings
    )
    seconds = time.perf_counter() - start
    n = tallies.rays
    reflected, transmitted, absorbed = tallies.reflected, tallies.transmitted, tallies.absorbed
    violations, capped = tallies.weight_violations, tallies.capped
    warn_if_uncertified(violations, capped)
    backlit = backlit_fraction(instrument.geometry, settings.theta_i) if settings.beam == "conical" else 0.0
    return Reading(
        wavelengths=np.array(settings.wavelengths),
        reflectance=reflected / n,
        transmittance=transmitted / n,
        absorptance=absorbed / n,
        reflected=reflected,
        transmitted=transmitted,
        absorbed=absorbed,
        rays=n,
        weight_violations=violations,
        capped=capped,
        backlit_fraction=backlit,
        seconds=seconds,
        settings=settings,
        geometry=instrument.geometry,
        specular_reflected=tallies.specular,
        regular_transmitted=tallies.regular,
        wavelength_independent=tallies.wavelength_independent,
        pilot_rays=None if tallies.pilot is None else tallies.pilot.rays,
    )


def warn_if_uncertified(violations: np.ndarray, capped: np.ndarray, stacklevel: int = 3) -> None:
    """
    ``RuntimeWarning`` when rays escaped the certificate: BSDF weights outside [0, 1]
    (the specimen is not energy conserving) or random walks stopped by a step cap.
    """

    if np.any(violations):
        warnings.warn(
            f"{int(np.sum(violations))} BSDF sample weights fell outside [0, 1]: the specimen is not "
            "energy conserving, so the certified guarantee does not hold for this reading",
            RuntimeWarning,
            stacklevel=stacklevel,
        )
    if np.any(capped):
        warnings.warn(
            f"{int(np.sum(capped))} random walks reached the specimen's step cap; they are counted "
            "in capped and in none of reflectance, transmittance and absorptance",
            RuntimeWarning,
            stacklevel=stacklevel,
        )


def uncertified_lines(violations: np.ndarray, capped: np.ndarray) -> list[str]:
    """Summary lines for rays that escaped the certificate (none for a sound reading)."""

    lines = []
    if np.any(violations):
        lines.append(f"WARNING: {int(np.sum(violations))} BSDF weights outside [0, 1]")
    if np.any(capped):
        lines.append(f"WARNING: {int(np.sum(capped))} random walks hit the step cap (in no tally)")
    return lines
