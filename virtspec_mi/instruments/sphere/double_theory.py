"""
Double-sphere theory: the exchange of light between two spheres through the specimen
====================================================================================

An independent NumPy model of the double integrating sphere
(:mod:`virtspec_mi.instruments.sphere.double`) for a Lambertian specimen (diffuse
reflectance ρ and transmittance τ, the same from both sides) in the **flat-port** model
of :mod:`virtspec_mi.instruments.sphere.theory` (the specimen, a standard, a detector sit
in their ports as flat disks; a wall emission lands on a region X with X's cap fraction
a_X, a disk's emission on X ≠ itself with a_X / (1 − a_disk)).

Light is followed as a Markov chain over *emissions*: the wall of either sphere (W_R,
W_T), the specimen into either sphere (S_R, S_T), the transmittance sphere's white
standard (D_T). A landing on a wall is re-emitted with probability ρw; on the specimen
from either side it becomes S of the same side with ρ, S of the other side with τ (the
**cross-talk**: light of one sphere passed into the other); on a detector it is detected;
on an open port it is lost. The probability P_X(e) that an emission e ends on sphere X's
detector solves ``(I − Q) P = d`` (Q: the emission-to-emission transitions, d: the
direct detections), the absorbing-chain form of IAD's double-sphere gain equations
(Prahl's manual: G₁₁, G₂₂ with the factor 1/(1 − a_s a_s' r_w r_w' G G' t_s²) summing
the passes through the specimen; here every pass is a term of the geometric series the
solve sums, without the manual's baffle factors (1 − a_e)).

The instrument's readings (:class:`DoubleSphereModel`):

- sample: the beam's first interaction gives S_R with ρ and S_T with τ
  (``p_R = ρ P_R(S_R) + τ P_R(S_T)``, likewise p_T);
- standard: the specimen replaced by a Lambertian reflector ρ_std (τ = 0);
- open: the sample position empty: diffuse light crosses the port as if from a perfect
  Lambertian transmitter (ρ = 0, τ = 1) and the beam lands on the transmittance sphere's
  wall (``p_T = ρw' P_T(W_T)``);

M_R = ρ_std p_R(sample)/p_R(standard), M_T = p_T(sample)/p_T(open). The same specimen in
each sphere alone (:meth:`DoubleSphereModel.single`) is the chain with the other sphere
removed: its detector fraction over the same reference. :meth:`DoubleSphereModel.inverted`
solves the readings for (ρ, τ): the double-sphere algorithm's step of recovering the
specimen's R and T from both detectors (Mõttus, Hovi & Rautiainen 2017 solve the same
exchange with sphere constants measured on an empty port and a panel; here the constants
come from the spheres' description).

Where the walk may differ from the model: light leaving one spot of a disk (the beam's
first interaction) does not land uniformly (:func:`virtspec_mi.instruments.sphere.theory.spot_landing_density`),
and the wall is not uniformly bright near dark ports; both are second order in the port
size.

References
----------
S. A. Prahl, *Inverse Adding-Doubling* manual (double-sphere equations; iadpython
``sphere.Gain_11``, ``Gain_22``, ``Two_Sphere_R``, ``Two_Sphere_T``); Pickering et al.
(1993), Appl. Opt. 32(4), 399–410; Goebel (1967), Appl. Opt. 6(1), 125–128 (eq. 2: the
sphere property); Kemeny & Snell (1960), *Finite Markov chains* (absorption probabilities).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["SphereFractions", "DoubleSphereModel", "fractions_of"]


@dataclass(frozen=True)
class SphereFractions:
    """
    One sphere of the pair as the model sees it: its wall reflectance ``rho_w`` and the
    cap fractions of the ``specimen`` port (the sample position), the ``detector``, the
    ``standard`` port (a flat Lambertian disk of the standard's reflectance; 0: none) and
    the ``open`` ports (lost); the rest (plugged ports included) is wall.
    """

    rho_w: float
    specimen: float
    detector: float
    standard: float = 0.0
    open: float = 0.0

    @property
    def wall(self) -> float:
        """a_w = 1 − the ports' fractions (a plugged port is wall)."""

        return 1.0 - self.specimen - self.detector - self.standard - self.open


def fractions_of(sphere: Any, rho_w: float, specimen_role: str, plugged: tuple[str, ...] = ("reference",)) -> SphereFractions:
    """
    The :class:`SphereFractions` of a :class:`~virtspec_mi.instruments.sphere.geometry.Sphere`
    (exact cap fractions): its ``specimen_role`` port holds the specimen, a ``sample`` port
    of the transmittance sphere (``specimen_role="entrance"``) the standard, ``plugged``
    roles are wall, every other port is open.
    """

    out = {"specimen": 0.0, "detector": 0.0, "standard": 0.0, "open": 0.0}
    for port in sphere.ports:
        fraction = sphere.cap_fraction(port)
        if port.role == specimen_role:
            out["specimen"] += fraction
        elif port.role == "detector":
            out["detector"] += fraction
        elif port.role == "sample" and specimen_role == "entrance":
            out["standard"] += fraction
        elif port.role not in plugged:
            out["open"] += fraction
    return SphereFractions(float(rho_w), **out)


@dataclass(frozen=True)
class DoubleSphereModel:
    """
    The flat-port exchange model of a double sphere (see the module docstring):
    ``reflectance`` and ``transmittance`` sphere fractions and the standard's reflectance.
    """

    reflectance: SphereFractions
    transmittance: SphereFractions
    standard: float = 0.99

    def detected(self, rho: float, tau: float, *, present: tuple[bool, bool] = (True, True)) -> np.ndarray:
        """
        P[e, X]: the probability that emission e (W_R, S_R, W_T, S_T, D_T) ends on sphere X's
        detector (X = 0 reflectance, 1 transmittance), for a specimen (ρ, τ); an absent
        sphere (``present``) loses every ray that would enter it.
        """

        spheres = (self.reflectance, self.transmittance)
        q = np.zeros((5, 5))
        d = np.zeros((5, 2))
        wall, spec, std = (0, 2), (1, 3), (None, 4)
        for x, f in enumerate(spheres):
            if not present[x]:
                continue
            other = 1 - x
            for source, own in ((wall[x], None), (spec[x], f.specimen), (std[x], f.standard)):
                if source is None:
                    continue
                scale = 1.0 if own is None else 1.0 / (1.0 - own)
                d[source, x] += scale * f.detector
                q[source, wall[x]] += scale * f.wall * f.rho_w
                if source != spec[x]:
                    q[source, spec[x]] += scale * f.specimen * rho
                    if present[other]:
                        q[source, spec[other]] += scale * f.specimen * tau
                if std[x] is not None and source != std[x]:
                    q[source, std[x]] += scale * f.standard * self.standard
        return np.linalg.solve(np.eye(5) - q, d)

    def fractions(self, rho: float, tau: float, *, present: tuple[bool, bool] = (True, True)) -> tuple[float, float]:
        """(p_R, p_T): both detectors' fractions when the beam meets a specimen (ρ, τ)."""

        p = self.detected(rho, tau, present=present)
        return tuple(float(rho * p[1, x] + tau * p[3, x]) for x in (0, 1))  # type: ignore[return-value]

    def open_fraction(self, *, present: tuple[bool, bool] = (True, True)) -> float:
        """p_T with the sample position empty: the beam on the transmittance sphere's wall."""

        return float(self.transmittance.rho_w * self.detected(0.0, 1.0, present=present)[2, 1])

    def readings(self, rho: float, tau: float) -> tuple[float, float]:
        """(M_R, M_T) of the double sphere for a Lambertian specimen (ρ, τ)."""

        p_r, p_t = self.fractions(rho, tau)
        standard_r, _ = self.fractions(self.standard, 0.0)
        return self.standard * p_r / standard_r, p_t / self.open_fraction()

    def single(self, rho: float, tau: float) -> tuple[float, float]:
        """
        (M_R, M_T) of each sphere alone: the reflectance sphere with nothing behind the
        specimen (substitution against the standard), the transmittance sphere with nothing
        in front (against its open port).
        """

        p_r, _ = self.fractions(rho, tau, present=(True, False))
        standard_r, _ = self.fractions(self.standard, 0.0, present=(True, False))
        _, p_t = self.fractions(rho, tau, present=(False, True))
        return self.standard * p_r / standard_r, p_t / self.open_fraction(present=(False, True))

    def inverted(self, reflectance: float, transmittance: float) -> tuple[float, float]:
        """
        (ρ, τ) of the Lambertian specimen whose double-sphere readings are (M_R, M_T) (a
        bounded least-squares solve, 0 ≤ ρ, τ and ρ + τ ≤ 1 enforced by the bounds of ρ and
        τ separately; ``ValueError`` where the readings are no such specimen's).
        """

        from scipy.optimize import least_squares

        target = np.array([reflectance, transmittance], dtype=np.float64)
        if not np.all(np.isfinite(target)):
            raise ValueError(f"readings must be finite (got M_R = {reflectance}, M_T = {transmittance})")
        fit = least_squares(lambda x: np.array(self.readings(*x)) - target, x0=np.clip(target, 0.01, 0.49),
                            bounds=([0.0, 0.0], [1.0, 1.0]), xtol=1e-12, ftol=1e-12, gtol=1e-12)
        if np.max(np.abs(fit.fun)) > 1e-6:
            raise ValueError(f"no Lambertian specimen reads M_R = {reflectance:.5f}, M_T = {transmittance:.5f} in "
                             f"these spheres (closest misses by {np.max(np.abs(fit.fun)):.2g})")
        return float(fit.x[0]), float(fit.x[1])
