"""
The goniophotometer: the spectrophotometer's rays binned by their outgoing direction
====================================================================================

:class:`GonioOptions` is the one definition of the goniophotometer's options beside the
common :class:`~virtspec_mi.settings.Settings`: how the escaping rays are binned by
their outgoing direction (θo, φo) in the specimen frame (:mod:`virtspec_mi.instruments.goniophotometer.bins`)
and how N is sized over the K bins (``guarantee``, :mod:`virtspec_mi.budgets.bins`).
:func:`virtspec_mi.gonio` takes them as keywords, ``virtspec gonio`` as flags and the
``spectrophotometer`` integrator as parameters; a bad value raises ``ValueError`` naming
it, once, when the options are built (the bins are laid out then:
:attr:`GonioOptions.bins`).

References
----------
Baranoski et al. (2001), Sect. 6; Nicodemus et al. (1977), NBS Monograph 160.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from virtspec_mi.budgets import rules
from virtspec_mi.budgets.rules import GUARANTEES, check_gonio_options
from virtspec_mi.base.checks import check_brdf_floor, check_relative_tolerance
from virtspec_mi.engine.parameters import ParameterSpace
from virtspec_mi.engine.plan import Columns, Plan
from virtspec_mi.engine.tally import Tally
from virtspec_mi.instruments.goniophotometer.bins import BINNINGS, HEMISPHERES, GonioBins, make_bins, parse_edges
from virtspec_mi.instruments.base import Instrument, reading_grid, readings_result
from virtspec_mi.instruments.command import Command, FigureFlag, Session
from virtspec_mi.instruments.goniophotometer.result import GonioResult
from virtspec_mi.instruments.goniophotometer.rgl_reading import RGLReading
from virtspec_mi.instruments.goniophotometer.warped import DEFAULT_RESOLUTION, WarpedGrid, check_resolution
from virtspec_mi.settings import Options, Settings, one_of, option, text, true_or_false

__all__ = ["GonioOptions", "Goniophotometer", "GonioResult", "RGLReading", "RglFlags", "GONIO_BINNINGS"]

GONIO_BINNINGS: dict[str, str] = {
    **BINNINGS,
    "rgl": "the cells of an RGL .bsdf's grid (rgl_resolution nodes per axis), by half vector, reflection only: the "
           "reading is an RGLReading whose cell means are what the .bsdf stores (collimated beam)",
}
"""The goniophotometer's binnings: the θo ones (:data:`~virtspec_mi.instruments.goniophotometer.bins.BINNINGS`)
and ``rgl``, the grid of Mitsuba's measured plugin (:mod:`virtspec_mi.instruments.goniophotometer.warped`)."""

_THETA_PHI_OPTIONS = ("theta_o_bins", "phi_o_bins", "fold_phi", "hemispheres")


def _bin_spec(name: str) -> Any:
    """The check of a bin specification as written: a whole number of bins, or edges (a tuple of degrees)."""

    def check(value: Any) -> int | tuple[float, ...]:
        spec = parse_edges(name, value)
        return spec if isinstance(spec, int) else tuple(float(v) for v in spec)
    return check


@dataclass(frozen=True)
class GonioOptions(Options):
    """
    How a goniophotometer reading bins its rays and sizes N (validated on construction;
    ``GonioOptions.describe()`` lists every option).
    """

    title: ClassVar[str] = "goniophotometer options"

    theta_o_bins: int | tuple[float, ...] = option(
        18, _bin_spec("theta_o_bins"),
        "theta_o bins per hemisphere (1 ... 32768), or theta_o edges in degrees within [0, 180] (numbers, or "
        "start:stop:step; 90 an edge if crossed)", words=True)
    phi_o_bins: int | tuple[float, ...] = option(
        36, _bin_spec("phi_o_bins"),
        "phi_o bins over [0, 360) (folded: [0, 180]), 1 ... 65536, or phi_o edges in degrees", words=True)
    binning: str = option("uniform", one_of("binning", GONIO_BINNINGS), "theta_o binning of a number of bins, or "
                          "rgl: the RGL .bsdf's grid", GONIO_BINNINGS)
    rgl_resolution: int = option(DEFAULT_RESOLUTION, check_resolution,
                                 "binning rgl: nodes per axis of the .bsdf's grid, 3 ... 1025 (K = 1 + (n - 1)^2 "
                                 "cells)")
    fold_phi: bool = option(False, true_or_false("fold_phi"),
                            "fold phi_o to the relative azimuth |phi_o - phi_i| in [0, 180] (isotropic specimens)")
    hemispheres: str = option("both", one_of("hemispheres", HEMISPHERES), "what a number of theta_o bins covers",
                              {name: f"theta_o {low:g} ... {high:g}" for name, (low, high) in HEMISPHERES.items()})
    guarantee: str = option("union", one_of("guarantee", GUARANTEES), "how N is sized when rays is not given",
                            GUARANTEES)
    relative_tolerance: float | None = option(None, check_relative_tolerance,
                                              "guarantee relative: relative tolerance on f_k, 0 < eps <= 1")
    brdf_floor: float | None = option(
        None, check_brdf_floor, "guarantee relative: the BRDF/BTDF value (1/sr) above which f_k is held to "
                            "relative_tolerance")

    def _check_together(self) -> None:
        """The bins are laid out (a bad specification names its option)."""

        if self.binning == "rgl":  # the .bsdf's grid: the θo × φo options have no meaning
            given = [name for name in _THETA_PHI_OPTIONS
                     if getattr(self, name) != type(self).__dataclass_fields__[name].default]
            if given:
                raise ValueError(f"{', '.join(given)}: no meaning with binning 'rgl' (its cells are the .bsdf's "
                                 "grid, rgl_resolution nodes per axis, reflection only)")
            object.__setattr__(self, "_bins", WarpedGrid(self.rgl_resolution))
            return
        object.__setattr__(self, "_bins", make_bins(self.theta_o_bins, self.phi_o_bins, self.binning, self.fold_phi,
                                                    self.hemispheres))

    @property
    def bins(self) -> GonioBins | WarpedGrid:
        """
        The θo × φo bins these options lay out
        (:func:`virtspec_mi.instruments.goniophotometer.bins.make_bins`), or with ``binning="rgl"`` the
        .bsdf's grid (:class:`~virtspec_mi.instruments.goniophotometer.warped.WarpedGrid`).
        """

        return self._bins  # type: ignore[attr-defined]

    @property
    def smallest_solid_angle(self) -> float:
        """Ω_min: the smallest projected solid angle of a bin (sr; the relative guarantee's N depends on it)."""

        return float(np.min(self.bins.projected_solid_angles()))




@dataclass(frozen=True)
class RglFlags(Options):
    """``virtspec gonio``'s own flag: the reflection measured on the grid of Mitsuba's measured ``.bsdf``, written."""

    title: ClassVar[str] = "Mitsuba measured BSDF"

    rgl: str | None = option(
        None, text("rgl", "a file path"), "measure the reflection on the grid of an RGL .bsdf (binning rgl, "
                                          "--rgl-resolution nodes per axis, a collimated beam unless --beam is given) "
                                          "and write FILE for Mitsuba's measured plugin: each node its cell's mean "
                                          "of f cos(theta_o) with its certified interval (see RGLReading)")


def _respond_gonio(session: Session) -> int:
    """``virtspec gonio``: the reading printed and drawn; with ``--rgl FILE`` taken on the ``.bsdf``'s grid, written."""

    if session.flags.rgl is None:
        return session.default()
    overrides: dict[str, Any] = {"binning": "rgl"}
    if session.keywords.get("beam") is None:
        overrides["beam"] = "collimated"
    result = session.take(**overrides)
    status = session.report(result, result.summary(), session.draw(result))
    result.to_rgl(session.flags.rgl)
    if not session.args.json:
        print(f"rgl: {session.flags.rgl} (Mitsuba's measured plugin; reflection only)")
    return status


GONIO_COMMAND = Command(
    "gonio", "goniophotometer: certified BRDF/BTDF by outgoing direction",
    "Measure the specimen of a scene as the spectrophotometer does, and bin every escaping ray by its outgoing "
    "direction (theta_o, phi_o) in the specimen frame: exact counts, fractions and BRDF/BTDF per bin with their "
    "certificate (DKW for the CDFs, union bound for the bins, Clopper-Pearson intervals for f). Prints R and T "
    "with their certificate, the bins' certificate and a table with one row per theta_o bin (its centre) and "
    "one column per reading: the fraction of the incident rays leaving into that theta_o bin, summed over "
    "phi_o (the reflection rows add up to R, the transmission rows to T; each within 2 x the DKW tolerance of "
    "the CDF of theta_o); f per bin is in --out and --json.",
    ("virtspec gonio diamond_collimated --theta-i 30 --theta-o-bins 9 --phi-o-bins 12",
     "virtspec gonio diamond_collimated --theta-i 0 30 --binning projected --fold-phi --out brdf.nc --plot brdf.png",
     "virtspec gonio soybean_abmb --wavelengths 550 650 --theta-o-bins 9 --phi-o-bins 12 --fold-phi --mu 0.02 "
     "--plot leaf.png"),
    figures=(FigureFlag("--plot", "polar", "polar plots of f in and across the plane of incidence, one curve per theta_i "
                                      "with its certified band; several wavelengths: one figure per wavelength, "
                                      "FIG_<nm>nm.png", dim="wavelength"),
             FigureFlag("--plot-series", "series", "the distribution over theta_i as a series (f in the plane of "
                                                    "incidence and the CDF of theta_o, certified bands); several "
                                                    "wavelengths: one figure per wavelength", dim="wavelength")),
    flags=RglFlags, function="gonio", respond=_respond_gonio)
"""``virtspec gonio``: its reading, or with ``--klems`` the Klems matrices (the application's hook, by import path)."""


def _check_rgl(settings: Settings, options: GonioOptions, theta_i: np.ndarray) -> None:
    """The rules of ``binning="rgl"``: a collimated beam, θi below 90°, no relative guarantee."""

    if settings.beam != "collimated":
        raise ValueError(f"beam must be collimated with binning 'rgl' (got {settings.beam!r}): a cell's mean of "
                         "f cos(theta_o) is certified for one direction of incidence")
    if np.any(np.asarray(theta_i) >= 90.0):
        raise ValueError(f"theta_i must be below 90 degrees with binning 'rgl' (got {np.max(theta_i):g})")
    if isinstance(rules.guarantee_of(options.guarantee), rules.Relative):
        raise ValueError("guarantee 'relative' is not available with binning 'rgl' (its cells' solid angles change "
                         "with theta_i, and some are 0): use union, or give rays")


class Goniophotometer(Instrument):
    """
    The goniophotometer (see the module docstring): the spectrophotometer's readings
    over every (wavelength, θi, parameter point), every escaping ray also binned by its
    outgoing direction (the kernel hook :class:`~virtspec_mi.instruments.goniophotometer.hook.BinLayout`); the
    result is a :class:`~virtspec_mi.instruments.goniophotometer.result.GonioResult`.

    N is ``settings.rays``, or sized by ``guarantee`` over the K bins (a row of
    :data:`virtspec_mi.budgets.rules.GUARANTEES`), or — a two-stage rule — sized per
    reading from its pilot where the guarantee's row allows it (its
    :meth:`~virtspec_mi.budgets.rules.Guarantee.stage_two`; refused with the row's reason
    otherwise): the pilot's columns are then every bin fraction (δ shared over the K bins,
    as the union bound) and the reading's R, T and A, each at the same share, so that
    the reading's R/T certificate holds as well as its bins'.
    """

    name: ClassVar[str] = "goniophotometer"
    exports: ClassVar[tuple[str, ...]] = ("GonioResult", "GonioOptions", "RGLReading")
    options: ClassVar[type[Options] | None] = GonioOptions
    result: ClassVar[type] = GonioResult
    commands: ClassVar[tuple[Command, ...]] = (GONIO_COMMAND,)
    example: ClassVar[dict[str, Any]] = {
        "scene": "diamond_collimated", "theta_i": [0, 30], "rays": 4000, "theta_o_bins": 3, "phi_o_bins": 4,
        "seed": 2, "long": {"theta_i": "0:90:1", "rays": 200_000, "theta_o_bins": 6, "phi_o_bins": 8,
                 "parameters": {"specimen.eta": [1.5, 2.4]}, "readings": 182}}

    def init(self, bench: Any, settings: Settings, options: GonioOptions, theta_i: np.ndarray,
             parameters: ParameterSpace | None) -> Plan:
        """The bins (the kernel hook) and N, or the two-stage columns, of the options."""

        bins = options.bins
        grid = isinstance(bins, WarpedGrid)
        if grid:
            _check_rgl(settings, options, theta_i)
        rule, relative, floor = check_gonio_options(options.guarantee, settings.delta, bins.size,
                                                    options.relative_tolerance, options.brdf_floor)
        columns, refusal, self.guarantee = None, "", rule.name
        if settings.rays is not None:
            self.guarantee = rules.RAYS_GIVEN.name
        elif settings.adaptive:
            try:
                budget = rule.stage_two(bins.size)
            except ValueError as why:  # the row's reason: the engine refuses the plan with it
                refusal = str(why)
            else:
                fates = Columns.fates(settings.joint)
                share = max(budget.share, fates.budget.share)
                columns = Columns(rules.Columns(f"{budget.what} and {fates.budget.what}", share),
                                  counts=fates.counts, bins="each")
        else:
            settings = settings.updated(rays=rule.rays(settings.mu, settings.delta, bins.size, relative=relative,
                                                       floor=floor, smallest_solid_angle=options.smallest_solid_angle))
        self.bench, self.gonio_options = bench, options
        described = {"binning": "rgl", "rgl_resolution": bins.resolution} if grid else bins.as_dict()
        self.plan = Plan(settings.updated(theta_i=float(theta_i[0])), theta_i, parameters, hooks=(bins.layout(),),
                         columns=columns, refusal=refusal, scene=self.scene, instrument=self.name,
                         options={"bins": described, "guarantee": self.guarantee})
        return self.plan

    def postprocess(self, tally: Tally) -> GonioResult | RGLReading:
        """
        The hemispherical reading of the same rays and its per-bin counts over the readings' dims (with
        ``binning="rgl"``: its per-cell counts, an :class:`RGLReading`).
        """

        plan, options = self.plan, self.gonio_options
        result = readings_result(self.bench, plan, tally, self.scene, self.source)
        if isinstance(options.bins, WarpedGrid):
            return RGLReading(result=result, cell_counts=reading_grid(plan, tally.bins.reshape(-1, options.bins.size)),
                              resolution=options.bins.resolution, guarantee=self.guarantee)
        bin_counts = reading_grid(plan, tally.bins.reshape(-1, *options.bins.shape))
        return GonioResult(result=result, bin_counts=bin_counts, bins=options.bins, guarantee=self.guarantee,
                           relative_tolerance=options.relative_tolerance, brdf_floor=options.brdf_floor)

    def warn_if_uncertified(self, result: GonioResult, stacklevel: int = 2) -> None:
        result.result.warn_if_uncertified(stacklevel=stacklevel + 2)
