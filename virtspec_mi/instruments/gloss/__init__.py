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
  lies within the cone (wo · m ≥ cos ``cone``, m the mirror direction of its reading's
  incidence direction ω: m = (−ωx, −ωy, ωz)), bin 1 (K: not binned) for every other ray.
  The kernel tallies it exactly per reading.
- **Its result** (:class:`GlossResult`): the gloss fraction g = m/N of each reading (the
  share of the N rays that reach the receptor) with its certificate: one proportion of
  the reading's N rays, so the settings' ray budget certifies |g − p| < μ with
  probability ≥ 1 − δ exactly as it does the reflectance (eq. 23), and a Clopper–Pearson
  interval at δ brackets it. A two-stage rule sizes N from the pilot's gloss counts.
- **Gloss units** (ISO 2813 §3.3, §5.2): 100 GU is what the meter reads on the primary
  standard, a polished black glass of refractive index n = 1.567 at 587.6 nm, at each
  angle: its Fresnel reflectance R_s(θi) (the standard returns nothing from below its
  surface, and its mirror reflection lies whole in any receptor about the mirror
  direction under a collimated beam). So GU = 100 g / R_s(θi), and its interval is the
  gloss fraction's scaled by the same exact factor (R_s: 0.0491 at 20°, 0.1001 at 60°,
  0.6191 at 85°). The receptor here is a cone, not the standard's rectangular apertures:
  a gloss value in GU compares with a meter's only as far as the specimen's reflection
  lies within both.

**The angles.** Without ``theta_i`` the meter reads at ISO 2813's three geometries at
once, :data:`ISO_2813_ANGLES`: 20° (high gloss), 60° (all gloss levels) and 85° (low
gloss, matt), one reading of each wavelength at each, every one with its own rays, its
own receptor cone about its own mirror direction and its own certificate (the scene's θi
is not used: a gloss meter's geometry is the standard's). ``theta_i`` given (one angle or
several) is read as asked; the summary names any angle that is none of ISO 2813's.

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
from functools import cached_property
from typing import Any, ClassVar, Mapping

import numpy as np

from virtspec_mi.budgets.intervals import clopper_pearson
from virtspec_mi.base.checks import number, shown_value
from virtspec_mi.engine.parameters import ParameterSpace
from virtspec_mi.engine.plan import Columns, Plan
from virtspec_mi.engine.tally import Tally
from virtspec_mi.instruments.base import Instrument, reading_grid, readings_result
from virtspec_mi.instruments.command import Command, FigureFlag
from virtspec_mi.kernel.counts import Fate
from virtspec_mi.kernel.hooks import ExitHook
from virtspec_mi.references.quadrature import fresnel_reflectance
from virtspec_mi.results.base import attribute, plain_data, stored
from virtspec_mi.results.readings import Result
from virtspec_mi.results.integrity import CountRules, whole_counts
from virtspec_mi.results.variables import Variable, bounds
from virtspec_mi.settings import Options, Settings, option

__all__ = ["GlossOptions", "MirrorCone", "GlossResult", "GlossMeter", "ISO_2813_ANGLES", "ISO_2813_STANDARD_INDEX",
           "standard_reflectance"]

ISO_2813_ANGLES: tuple[float, ...] = (20.0, 60.0, 85.0)
"""The geometries of ISO 2813 (degrees from the normal): high gloss, all levels, low gloss."""

ISO_2813_STANDARD_INDEX: float = 1.567
"""Refractive index of ISO 2813's primary standard (polished black glass) at 587.6 nm: 100 GU at every angle."""


def standard_reflectance(theta_i: Any) -> np.ndarray:
    """ISO 2813's black glass standard's reflectance at ``theta_i`` (degrees): Fresnel's, unpolarised."""

    return fresnel_reflectance(np.asarray(theta_i, dtype=np.float64), ISO_2813_STANDARD_INDEX)


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
    degrees of the mirror direction of its reading's incidence direction ``wi`` (each
    reading's own θi and φi).
    """

    cone: float
    """Half-angle of the receptor cone, degrees."""
    incidence: ClassVar[bool] = True

    @property
    def size(self) -> int:
        return 1

    def bin(self, wo: Any, fate: Any, phi_i: Any, wi: Any = None) -> Any:
        import drjit as dr
        import mitsuba as mi

        mirror = mi.Vector3f(-wi.x, -wi.y, wi.z)  # wi points towards the emitter
        inside = (fate == int(Fate.REFLECTED)) & (dr.dot(wo, mirror) >= math.cos(math.radians(self.cone)))
        return dr.select(inside, mi.UInt32(0), mi.UInt32(1))


_GLOSS_RULES = CountRules(None, parts={"glossy": "reflected"})
"""The receptor's rays are reflected rays: 0 <= glossy <= reflected per reading."""


class GlossResult(Result):
    """
    Gloss readings over the readings' dims (wavelength, θi, parameters): the hemispherical
    reading of the same rays (:class:`~virtspec_mi.results.readings.Result`, every
    field and method of it) with the receptor's exact counts and its certificate; a result
    kind of its own (format ``"virtspec-mi gloss 1"``: files, ``sel``, plots, colour).
    Its Dataset is the reading's with ``glossy`` beside the counts and ``cone`` in its attributes.

    Parameters
    ----------
    reading : Result
        The hemispherical reading of the same rays.
    glossy : ndarray
        Rays reflected into the receptor cone, per reading (``int64``, over ``dims``).
    cone : float
        Half-angle of the receptor cone, degrees.
    """

    FORMAT: ClassVar[str] = "virtspec-mi gloss 1"
    KIND: ClassVar[str] = "gloss reading"
    QUANTITIES: ClassVar[tuple[str, ...]] = ("gloss", *Result.QUANTITIES)
    VARIABLES: ClassVar[dict[str, tuple[str, str]]] = {"glossy": ("1", "rays reflected into the receptor cone")}
    DERIVED: ClassVar[dict[str, Variable]] = {
        **Result.DERIVED,
        "gloss": Variable("1", "gloss fraction m/N (rays into the receptor cone)", lambda r: r.gloss),
        **bounds({"gloss": "the gloss fraction at delta"}, lambda r, name: r.interval(name), lambda r: r.interval_delta),
    }
    """The reading's variables, the gloss fraction and its Clopper-Pearson interval."""

    def __init__(self, reading: Result, glossy: Any, cone: float = 2.0) -> None:
        self._extend(reading, {"glossy": (reading.dims, glossy)}, {}, {"cone": _check_cone(cone)})

    glossy = stored("glossy", "Rays reflected into the receptor cone, per reading (``int64``, over ``dims``).")
    cone = attribute("cone", "Half-angle of the receptor cone, degrees.", float)

    @property
    def gloss(self) -> np.ndarray:
        """The gloss fraction g = m/N per reading (m: rays into the receptor cone)."""

        return self.glossy / self.rays

    def quantity(self, name: str) -> np.ndarray:
        """``gloss``, ``reflectance``, ``transmittance`` or ``absorptance`` by name."""

        if name == "gloss":
            return self.gloss
        if name not in self.QUANTITIES:
            raise ValueError(f"quantity must be one of {', '.join(self.QUANTITIES)} (got {name!r})")
        return super().quantity(name)

    @property
    def delta(self) -> float:
        """The failure probability of the certificate and the interval: the reading's (δ, or δ/2 with ``joint``)."""

        return self.interval_delta

    @cached_property
    def _intervals(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """
        Every quantity's Clopper–Pearson interval; the gloss fraction's is one proportion
        of the reading's N rays, certified as its reflectance is (:attr:`certified_mu`:
        the rule's μ for N, μ itself for a two-stage reading sized with the gloss
        fraction among its columns, plus the rounding bias; NaN where no rule applies).
        """

        return {**super()._intervals, "gloss": clopper_pearson(self.glossy, self.rays, self.interval_delta)}

    @property
    def gloss_interval(self) -> np.ndarray:
        """The Clopper–Pearson interval ``[lower, upper]`` of each gloss fraction at :attr:`delta`, shape (…, 2)."""

        return np.stack(self.interval("gloss"), axis=-1)

    @property
    def standard(self) -> np.ndarray:
        """The gloss fraction of ISO 2813's black glass standard at each reading's θi (100 GU), over ``dims``."""

        theta = np.asarray(self.coords["theta_i"], dtype=np.float64)
        if "theta_i" not in self.dims:
            return np.broadcast_to(standard_reflectance(theta), self.shape)
        shape = [len(theta) if d == "theta_i" else 1 for d in self.dims]
        return np.broadcast_to(standard_reflectance(theta).reshape(shape), self.shape)

    @property
    def gloss_units(self) -> np.ndarray:
        """The gloss value in gloss units (GU): 100 g / R_s(θi), R_s the black glass standard's (module docstring)."""

        return 100.0 * self.gloss / self.standard

    @property
    def gloss_units_interval(self) -> np.ndarray:
        """The gloss fraction's interval in gloss units (the same exact scaling), shape (…, 2)."""

        return 100.0 * self.gloss_interval / self.standard[..., None]

    def summary(self, sized_by: str | None = None) -> str:
        """The gloss fraction of every reading with its certificate, then the hemispherical reading's summary."""

        shown = self.squeeze(*(d for d, n in zip(self.dims, self.shape) if n == 1 and d != "wavelength"))
        angles = sorted({float(t) for t in np.atleast_1d(shown.coords["theta_i"])})
        others = [t for t in angles if not any(abs(t - a) < 1e-9 for a in ISO_2813_ANGLES)]
        lines = [f"gloss meter, receptor cone {self.cone:g} deg about the mirror direction "
                 f"(probability >= {1 - self.delta:g} per reading); GU: 100 = ISO 2813's black glass standard "
                 f"(n = {ISO_2813_STANDARD_INDEX:g}) at the same angle"
                 + (f" (theta_i {', '.join(f'{t:g}' for t in others)} deg: not one of ISO 2813's 20, 60, 85)"
                    if others else "")]
        interval, units, span = shown.gloss_interval, shown.gloss_units, shown.gloss_units_interval
        for index in np.ndindex(shown.shape):
            mu, n = shown.certified_mu[index], int(shown.rays[index])
            certificate = "NOT CERTIFIED" if np.isnan(mu) else f"|g - p| < {mu:.4g}"
            labels = ", ".join(f"{dim} {float(np.asarray(shown.coords[dim])[k]):g}"
                               for dim, k in zip(shown.dims, index))
            lines.append(f"  {labels}: g = {shown.gloss[index]:.6f} in [{interval[index][0]:.6f}, "
                         f"{interval[index][1]:.6f}], {certificate} (N = {n:,}); {units[index]:.1f} GU in "
                         f"[{span[index][0]:.1f}, {span[index][1]:.1f}]")
        return "\n".join(lines) + "\n" + super().summary(sized_by)

    def as_dict(self) -> dict[str, Any]:
        return {**super().as_dict(), "glossy": plain_data(self.glossy), "gloss": plain_data(self.gloss),
                "gloss_interval": plain_data(self.gloss_interval), "cone": self.cone}

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> "GlossResult":
        return cls(Result._from_dict(data), whole_counts(data["glossy"], "glossy"), data["cone"])

    def _count_groups(self) -> list[tuple[str, Mapping[str, np.ndarray], CountRules, tuple[str, ...]]]:
        receptor = ("", {"glossy": self.glossy, "reflected": self.reflected}, _GLOSS_RULES, self.dims)
        return [*super()._count_groups(), receptor]

    def _file_attrs(self) -> dict[str, Any]:
        return {**super()._file_attrs(), "cone": self.cone}


class GlossMeter(Instrument):
    """
    The gloss meter (see the module docstring): one θi (its geometry), the settings' beam
    and ray budget; a two-stage rule sizes each reading from its pilot's gloss fraction
    (with R, T and A, as a hemispherical reading's).
    """

    name: ClassVar[str] = "gloss"
    angles: ClassVar[tuple[float, ...] | None] = ISO_2813_ANGLES
    exports: ClassVar[tuple[str, ...]] = ("GlossResult",)
    options: ClassVar[type[Options] | None] = GlossOptions
    result: ClassVar[type] = GlossResult
    commands: ClassVar[tuple[Command, ...]] = (Command(
        "gloss", "a specular gloss meter: the share of rays reflected into a cone about the mirror direction",
        "Light the specimen at ISO 2813's geometries, 20, 60 and 85 degrees (or at the --theta-i given), and read "
        "the share of the rays reflected into a receptor cone of half-angle --cone about each mirror direction: "
        "the gloss fraction of every wavelength and angle with the tolerance its rays guarantee (as the "
        "reflectance's, eq. 23) and a Clopper-Pearson interval, in gloss units against ISO 2813's black glass, "
        "beside the hemispherical reading of the same rays.",
        ("virtspec gloss diamond_collimated --cone 2",
         "virtspec gloss diamond_collimated --theta-i 60",
         "virtspec gloss soybean_abmb --theta-i 20 --wavelengths 450,550,650 --out gloss.nc --plot gloss.png"),
        figures=(FigureFlag("--plot", "sweep", "the gloss fraction against theta_i (one curve per wavelength) or "
                                          "wavelength, with the band of its certified tolerance"),)),)
    example: ClassVar[dict[str, Any]] = {
        "scene": "diamond_collimated", "theta_i": 60, "wavelengths": [450, 650], "rays": 4000, "cone": 2, "seed": 4,
        "long": {"scene": "soybean_abmb", "theta_i": 20, "wavelengths": "400:2500:5", "rays": 100_000,
                 "readings": 421}}

    def init(self, bench: Any, settings: Settings, options: GlossOptions, theta_i: np.ndarray,
             parameters: ParameterSpace | None) -> Plan:
        if settings.beam == "diffuse":  # no incidence direction: no mirror direction for the receptor's cone
            raise ValueError("beam must be collimated or conical for a gloss meter (got 'diffuse': a diffuse beam has "
                             "no mirror direction for the receptor's cone about it)")
        self.bench, self.gloss_options = bench, options
        self.plan = Plan(settings.updated(theta_i=float(theta_i[0])), theta_i, parameters,
                         hooks=(MirrorCone(options.cone),),
                         columns=replace(Columns.fates(settings.joint), bins="each"), scene=self.scene,
                         instrument=self.name, options=options.as_dict())
        return self.plan

    def postprocess(self, tally: Tally) -> GlossResult:
        reading = readings_result(self.bench, self.plan, tally, self.scene, self.source)
        return GlossResult(reading, reading_grid(self.plan, tally.bins[:, 0]), self.gloss_options.cone)

    def warn_if_uncertified(self, result: GlossResult, stacklevel: int = 2) -> None:
        result.warn_if_uncertified(stacklevel=stacklevel + 2)
