"""
A gloss meter: the share of rays reflected within a cone about the mirror direction
===================================================================================

The example of a fourth instrument (one module and one row of
:data:`virtspec_mi.instruments.INSTRUMENTS`). A specular gloss meter lights the specimen
at one angle (20°, 60° or 85° in ISO 2813) and reads the light reflected into a small
receptor aperture about the mirror direction. Here the receptor is a cone of half-angle
``cone`` degrees about the mirror direction of the incidence (θi, φi), i.e. about
(θi, φi + 180°): the instrument's one option (:class:`GlossOptions`).

- **What a ray's exit adds** (:class:`MirrorCone`, an exit hook of the one tally path:
  :mod:`virtspec_mi.kernel.hooks`): bin 0 for a reflected ray whose outgoing direction
  lies within the cone (wo · m ≥ cos ``cone``, m the mirror direction), bin 1 (K:
  not binned) for every other ray. The kernel tallies it exactly per reading.
- **Its result** (:class:`GlossResult`): the gloss fraction g = m/N of each reading (the
  share of the N rays that reach the receptor) with its certificate: one proportion of
  the reading's N rays, so the settings' ray budget certifies |g − p| < μ with
  probability ≥ 1 − δ exactly as it does the reflectance (eq. 23), and a Clopper–Pearson
  interval at δ brackets it. A two-stage rule sizes N from the pilot's gloss counts.

The specimen frame, beam and sampling are the spectrophotometer's: with a collimated
beam every ray comes in along the incidence direction, so a smooth specimen reflects
every reflected ray exactly into the mirror direction (its gloss fraction is its Fresnel
reflectance).

References
----------
ISO 2813:2014, Paints and varnishes — Determination of gloss value at 20°, 60° and 85°
(the geometry). Baranoski et al. (2001), eqs. (2), (23); Clopper & Pearson (1934).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, ClassVar

import numpy as np

from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.checks import number, shown_value
from virtspec_mi.engine.parameters import ParameterSpace
from virtspec_mi.engine.plan import Columns, Plan
from virtspec_mi.engine.tally import Tally
from virtspec_mi.instruments.base import Instrument, reading_grid
from virtspec_mi.instruments.hemispherical import hemispherical_result
from virtspec_mi.kernel.counts import Fate
from virtspec_mi.kernel.hooks import ExitHook
from virtspec_mi.results.hemispherical import Result
from virtspec_mi.settings import Options, Settings, option

__all__ = ["GlossOptions", "MirrorCone", "GlossResult", "GlossMeter"]


def _check_cone(value: Any) -> float:
    cone = number("cone", value)
    if not 0.0 < cone <= 90.0:
        raise ValueError(f"cone must satisfy 0 < cone <= 90 degrees (got {shown_value(value)})")
    return cone


@dataclass(frozen=True)
class GlossOptions(Options):
    """The gloss meter's one option (validated on construction)."""

    title: ClassVar[str] = "gloss meter options"

    cone: float = option(2.0, _check_cone, "half-angle of the receptor cone about the mirror direction, degrees "
                                           "in (0, 90]")


@dataclass(frozen=True, eq=False)
class MirrorCone(ExitHook):
    """
    The exit hook (plain values, picklable): bin 0 for a reflected ray within ``cone``
    degrees of the mirror direction of the incidence (``theta_i``, the reading's φi).
    """

    theta_i: float
    """Polar incidence angle, degrees."""
    cone: float
    """Half-angle of the receptor cone, degrees."""

    @property
    def size(self) -> int:
        return 1

    def bin(self, wo: Any, fate: Any, phi_i: Any) -> Any:
        import drjit as dr
        import mitsuba as mi

        theta = math.radians(self.theta_i)
        phi = phi_i * (math.pi / 180.0)
        mirror = mi.Vector3f(-math.sin(theta) * dr.cos(phi), -math.sin(theta) * dr.sin(phi), math.cos(theta))
        inside = (fate == int(Fate.REFLECTED)) & (dr.dot(wo, mirror) >= math.cos(math.radians(self.cone)))
        return dr.select(inside, mi.UInt32(0), mi.UInt32(1))


@dataclass(frozen=True, eq=False)
class GlossResult:
    """
    Gloss readings over the readings' dims (wavelength, θi): the exact counts and the
    certificate.

    Attributes
    ----------
    result : virtspec_mi.results.hemispherical.Result
        The hemispherical reading of the same rays.
    glossy : ndarray
        Rays reflected into the receptor cone, per reading (``int64``, over ``result.dims``).
    cone : float
        Half-angle of the receptor cone, degrees.
    """

    result: Result
    glossy: np.ndarray
    cone: float

    @property
    def gloss(self) -> np.ndarray:
        """The gloss fraction g = m/N per reading."""

        return self.glossy / self.result.rays

    @property
    def delta(self) -> float:
        """The failure probability of the certificate and the interval: the reading's (δ, or δ/2 with ``joint``)."""

        return self.result.interval_delta

    @property
    def certified_mu(self) -> np.ndarray:
        """
        |g − p| < μ at :attr:`delta`, per reading: one proportion of the reading's N rays,
        certified as its reflectance is (:attr:`Result.certified_mu`: the rule's μ for N,
        μ itself for a two-stage reading sized with the gloss fraction among its columns,
        plus the rounding bias; NaN where no rule applies).
        """

        return self.result.certified_mu

    @property
    def interval(self) -> np.ndarray:
        """The Clopper–Pearson interval of each gloss fraction at :attr:`delta`, shape (…, 2)."""

        return np.stack(clopper_pearson(self.glossy, self.result.rays, self.delta), axis=-1)

    def summary(self) -> str:
        """The gloss fraction of every reading with its certificate."""

        lines = [f"gloss meter, theta_i = {float(np.ravel(self.result.coords['theta_i'])[0]):g} deg, receptor cone "
                 f"{self.cone:g} deg about the mirror direction (probability >= {1 - self.delta:g})"]
        for index in np.ndindex(self.gloss.shape):
            mu, n = self.certified_mu[index], int(self.result.rays[index])
            certificate = "NOT CERTIFIED" if np.isnan(mu) else f"|g - p| < {mu:.4g}"
            lines.append(f"  {self.result.wavelengths[index[0]]:g} nm: g = {self.gloss[index]:.6f}, {certificate} "
                         f"(N = {n:,})")
        return "\n".join(lines)


class GlossMeter(Instrument):
    """
    The gloss meter (see the module docstring): one θi (its geometry), the settings' beam
    and ray budget; a two-stage rule sizes each reading from its pilot's gloss fraction
    (with R, T and A, as a hemispherical reading's).
    """

    name: ClassVar[str] = "gloss"
    options: ClassVar[type[Options] | None] = GlossOptions
    result: ClassVar[type] = GlossResult

    def init(self, bench: Any, settings: Settings, options: GlossOptions, theta_i: np.ndarray,
             parameters: ParameterSpace | None) -> Plan:
        if len(theta_i) != 1:
            raise ValueError(f"a gloss meter reads at one theta_i, its geometry (got {len(theta_i)} angles)")
        if settings.beam == "diffuse":  # no incidence direction: no mirror direction for the receptor's cone
            raise ValueError("beam must be collimated or conical for a gloss meter (got 'diffuse': a diffuse beam has "
                             "no mirror direction for the receptor's cone about it)")
        self.bench, self.gloss_options = bench, options
        self.plan = Plan(settings.updated(theta_i=float(theta_i[0])), theta_i, parameters,
                         hooks=(MirrorCone(float(theta_i[0]), options.cone),),
                         columns=replace(Columns.fates(settings.joint), bins="each"), scene=self.scene,
                         instrument=self.name, options=options.as_dict())
        return self.plan

    def postprocess(self, tally: Tally) -> GlossResult:
        return GlossResult(hemispherical_result(self.bench, self.plan, tally, self.scene, self.source),
                           reading_grid(self.plan, tally.bins[:, 0]), self.gloss_options.cone)
