"""
Sampling weights of Mitsuba's built-in BSDFs, as the instrument sees them
=========================================================================

The spectrophotometer kernel (:mod:`virtspec_mi.kernel.tracer`,
``_Kernel.trace``) samples the specimen with ``bsdf.sample`` in
:attr:`mitsuba.TransportMode.Importance` and lets the ray survive with probability
:math:`w` = ``mi.Spectrum(weight)[0]`` (Russian roulette). That trial is an unbiased
Bernoulli trial only when :math:`0 \\le w \\le 1`; any other :math:`w` is counted as a
*weight violation*.

This diagnostic surveys the built-in surface BSDFs at the instrument's incidence
angles and wavelengths and reports, per BSDF and per (:math:`\\theta_i`,
:math:`\\lambda`) condition:

-   the largest and the smallest weight and the number of NaN weights,
-   the share of weights in :math:`(1, 1 + \\epsilon]` and in :math:`[-\\epsilon, 0)`
    for :math:`\\epsilon \\in \\{10^{-4}, 10^{-3}\\}` (float32 rounding) and the share
    above :math:`1 + 10^{-3}` (real violations),
-   the mean weight (the reflectance + transmittance of a weighted estimate) against
    the mean of :math:`\\operatorname{clip}(w, 0, 1)` (the survival estimate: the
    difference is the bias that clipping would cause).

It then proposes the rounding tolerance :math:`\\epsilon`: the smallest round value
for which no BSDF whose weights lie in [0, 1] in exact arithmetic (``Case.bounded``)
has a weight outside :math:`[-\\epsilon, 1 + \\epsilon]`. With Mitsuba 3.9.1 that is
:math:`10^{-4}`: the largest excess, :math:`6.15 \\cdot 10^{-5}`, comes from the
rational fit of the Beckmann Smith :math:`G_1` (it overshoots 1 near
:math:`a \\approx 1.59`), float32 rounding alone stays below :math:`10^{-6}`.

Run: ``.venv/bin/python tools/builtin_weights.py [--rays N] [--only LABEL] [--conditions TSV]``
(15–20 s with :math:`10^6` rays per condition, 38 cases, on two cores).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

import virtspec_mi

__all__ = [
    "THETAS",
    "WAVELENGTHS",
    "EPSILONS",
    "VIOLATION_EPSILON",
    "ROUND_TOLERANCES",
    "Case",
    "CASES",
    "SKIPPED",
    "ConditionStatistics",
    "CaseSurvey",
    "sample_weights",
    "condition_statistics",
    "survey_case",
    "survey",
    "propose_tolerance",
    "verdict",
    "format_summary",
    "format_conditions",
    "main",
]

THETAS: tuple[float, ...] = (0.0, 30.0, 45.0, 60.0, 80.0, 89.0)
"""Incidence angles :math:`\\theta_i` in degrees."""

WAVELENGTHS: tuple[float, ...] = (450.0, 551.0, 650.0)
"""Wavelengths :math:`\\lambda` in nm."""

EPSILONS: tuple[float, ...] = (1e-4, 1e-3)
"""Rounding bands :math:`(1, 1 + \\epsilon]` and :math:`[-\\epsilon, 0)` that are counted."""

VIOLATION_EPSILON: float = 1e-3
"""Weights above :math:`1 +` this are counted as real violations."""

ROUND_TOLERANCES: tuple[float, ...] = tuple(
    float(f"{m}e{e}") for e in range(-7, -1) for m in (1, 2, 5)
)
"""Candidate round tolerances, smallest first: 1e-7, 2e-7, 5e-7, 1e-6, … 5e-2."""


@dataclass(frozen=True)
class Case:
    """One built-in BSDF configuration of the survey."""

    label: str
    """Short name of the case in the tables."""

    definition: dict
    """The ``mi.load_dict`` dictionary."""

    bounded: bool
    """Whether every sampling weight lies in [0, 1] in exact arithmetic (so that any
    excess is rounding or approximation error); these cases decide the tolerance."""


_COLOURED: dict = {"type": "rgb", "value": [0.9, 0.2, 0.1]}

CASES: tuple[Case, ...] = (
    Case("diffuse", {"type": "diffuse"}, True),
    Case("diffuse R=1", {"type": "diffuse", "reflectance": 1.0}, True),
    Case("dielectric", {"type": "dielectric"}, True),
    Case("thindielectric", {"type": "thindielectric"}, True),
    *(
        Case(f"roughdielectric {d} a={a}", {"type": "roughdielectric", "distribution": d, "alpha": a}, True)
        for d in ("beckmann", "ggx")
        for a in (0.05, 0.3, 0.8)
    ),
    Case("conductor", {"type": "conductor"}, True),
    Case("conductor Au", {"type": "conductor", "material": "Au"}, True),
    *(
        Case(f"roughconductor {d} a={a}", {"type": "roughconductor", "distribution": d, "alpha": a}, True)
        for d in ("beckmann", "ggx")
        for a in (0.05, 0.3, 0.8)
    ),
    Case("roughconductor ggx a=0.3 Au",
         {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3, "material": "Au"}, True),
    Case("twosided(diffuse)", {"type": "twosided", "bsdf": {"type": "diffuse"}}, True),
    # The composites pick a nested lobe with the probability of its blend weight and
    # return the nested weight unchanged: as bounded as what they wrap.
    Case("blendbsdf(diffuse, conductor)",
         {"type": "blendbsdf", "weight": 0.5, "bsdf_0": {"type": "diffuse"}, "bsdf_1": {"type": "conductor"}},
         True),
    Case("mask(0.5, diffuse)", {"type": "mask", "opacity": 0.5, "bsdf": {"type": "diffuse"}}, True),
    Case("null", {"type": "null"}, True),
    # Energy conserving (albedo <= 1) but the per-sample weight is not bounded: the lobe
    # is chosen with a heuristic probability (Fresnel x a spectrum-mean sampling weight).
    Case("plastic", {"type": "plastic"}, False),
    Case("plastic coloured", {"type": "plastic", "diffuse_reflectance": _COLOURED}, False),
    Case("plastic R=1", {"type": "plastic", "diffuse_reflectance": 1.0}, False),
    Case("roughplastic", {"type": "roughplastic"}, False),
    Case("roughplastic ggx a=0.3", {"type": "roughplastic", "distribution": "ggx", "alpha": 0.3}, False),
    Case("roughplastic coloured", {"type": "roughplastic", "diffuse_reflectance": _COLOURED}, False),
    # Neither energy conserving nor sampled in proportion to the lobes.
    Case("pplastic", {"type": "pplastic"}, False),
    Case("pplastic coloured", {"type": "pplastic", "diffuse_reflectance": _COLOURED}, False),
    Case("principled", {"type": "principled"}, False),
    Case("principled coloured", {"type": "principled", "base_color": _COLOURED}, False),
    Case("principled metallic=1", {"type": "principled", "metallic": 1.0}, False),
    Case("principled coloured metallic=1", {"type": "principled", "base_color": _COLOURED, "metallic": 1.0}, False),
    Case("principled spec_trans=1", {"type": "principled", "spec_trans": 1.0}, False),
    Case("principledthin", {"type": "principledthin"}, False),
    Case("principledthin coloured", {"type": "principledthin", "base_color": _COLOURED}, False),
)
"""The surveyed cases. ``bounded`` marks the models whose sampling weight is in [0, 1]
in exact arithmetic; they decide the proposed tolerance, the others are reported."""

SKIPPED: dict[str, str] = {
    "hair": "a fibre BSDF for the bsplinecurve shape (its frame and offset h come from the curve), not a surface",
    "bumpmap": "needs a gradient-capable texture (bitmap)",
    "normalmap": "needs a normal-map bitmap",
    "measured": "needs a measured RGL BRDF file",
    "measured_polarized": "needs a measured pBRDF file and a polarized variant",
    "polarizer": "a polarization element (meaningful in polarized variants only), not a specimen",
    "retarder": "a polarization element (meaningful in polarized variants only), not a specimen",
}
"""Built-in BSDF plugins that are not surveyed, with the reason."""


@dataclass(frozen=True)
class ConditionStatistics:
    """Weight statistics of one BSDF at one (:math:`\\theta_i`, :math:`\\lambda`)."""

    theta: float
    wavelength: float
    rays: int
    largest: float
    smallest: float
    nan: int
    above_band: dict[float, float]
    """Share of weights in (1, 1 + eps], per eps of :data:`EPSILONS`."""
    below_band: dict[float, float]
    """Share of weights in [-eps, 0), per eps of :data:`EPSILONS`."""
    above_violation: float
    """Share of weights > 1 + :data:`VIOLATION_EPSILON`."""
    below_violation: float
    """Share of weights < -:data:`VIOLATION_EPSILON`."""
    mean: float
    """Mean weight (NaN counted as 0): the weighted estimate of reflectance + transmittance."""
    clipped_mean: float
    """Mean of clip(w, 0, 1) (NaN counted as 0): what Russian roulette would estimate."""


@dataclass
class CaseSurvey:
    """All conditions of one :class:`Case`, with the kernel's runtime."""

    case: Case
    conditions: list[ConditionStatistics] = field(default_factory=list)
    seconds: float = 0.0
    error: str | None = None

    @property
    def largest(self) -> float:
        return max((c.largest for c in self.conditions), default=math.nan)

    @property
    def smallest(self) -> float:
        return min((c.smallest for c in self.conditions), default=math.nan)

    @property
    def nan(self) -> int:
        return sum(c.nan for c in self.conditions)

    @property
    def worst(self) -> ConditionStatistics | None:
        """The condition with the largest excess outside [0, 1]."""

        if not self.conditions:
            return None
        return max(self.conditions, key=lambda c: max(c.largest - 1.0, -c.smallest))

    @property
    def largest_bias(self) -> ConditionStatistics | None:
        """The condition where clipping changes the mean most."""

        if not self.conditions:
            return None
        return max(self.conditions, key=lambda c: abs(c.mean - c.clipped_mean))


def sample_weights(mi: Any, bsdf: Any, rays: int, thetas: tuple[float, ...] = THETAS,
                   wavelengths: tuple[float, ...] = WAVELENGTHS, seed: int = 0) -> np.ndarray:
    """
    ``w = mi.Spectrum(weight)[0]`` of ``rays`` importance-mode samples of ``bsdf`` for every
    (theta, wavelength) pair, as a ``(len(thetas), len(wavelengths), rays)`` float32 array.

    The interaction is the one of ``_Kernel.trace``: specimen frame = the identity
    (normal +z), ``wi`` in the x–z plane towards the emitter, all wavelengths of
    ``si.wavelengths`` equal, uv = (0.5, 0.5), p = 0. One fused kernel covers all conditions.
    """

    import drjit as dr

    groups = len(thetas) * len(wavelengths)
    size = groups * rays
    angles = np.radians(np.repeat(np.asarray(thetas, dtype=np.float64), len(wavelengths)))
    lambdas = np.tile(np.asarray(wavelengths, dtype=np.float64), len(thetas))
    group = dr.arange(mi.UInt32, size) // rays
    sin_theta = dr.gather(mi.Float, mi.Float(np.sin(angles).astype(np.float32)), group)
    cos_theta = dr.gather(mi.Float, mi.Float(np.cos(angles).astype(np.float32)), group)
    wavelength = dr.gather(mi.Float, mi.Float(lambdas.astype(np.float32)), group)

    si = dr.zeros(mi.SurfaceInteraction3f, size)
    si.wi = mi.Vector3f(sin_theta, 0.0, cos_theta)
    si.wavelengths = mi.Spectrum(wavelength)
    si.sh_frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
    si.n = mi.Normal3f(0, 0, 1)
    si.uv = mi.Point2f(0.5, 0.5)
    si.p = mi.Point3f(0, 0, 0)

    rng = mi.PCG32(size, 0x853C49E6748FEA9B + seed)
    u = rng.next_float32()
    u1 = rng.next_float32()
    u2 = rng.next_float32()
    context = mi.BSDFContext(mi.TransportMode.Importance)
    _, weight = bsdf.sample(context, si, u, mi.Point2f(u1, u2), True)
    w = mi.Spectrum(weight)[0]
    dr.eval(w)
    values = np.asarray(w.numpy(), dtype=np.float32)
    if values.size == 1:  # a constant weight (thindielectric, null) comes back unbroadcast
        values = np.full(size, values[0], dtype=np.float32)
    return values.reshape(len(thetas), len(wavelengths), rays)


def condition_statistics(w: np.ndarray, theta: float, wavelength: float) -> ConditionStatistics:
    """The statistics of one condition's weights ``w`` (1-D float32)."""

    nan = np.isnan(w)
    finite = np.where(nan, 0.0, w).astype(np.float64)
    valid = w[~nan]
    n = w.size
    return ConditionStatistics(
        theta=theta,
        wavelength=wavelength,
        rays=n,
        largest=float(valid.max()) if valid.size else math.nan,
        smallest=float(valid.min()) if valid.size else math.nan,
        nan=int(nan.sum()),
        above_band={eps: float(np.count_nonzero((valid > 1.0) & (valid <= 1.0 + eps))) / n for eps in EPSILONS},
        below_band={eps: float(np.count_nonzero((valid >= -eps) & (valid < 0.0))) / n for eps in EPSILONS},
        above_violation=float(np.count_nonzero(valid > 1.0 + VIOLATION_EPSILON)) / n,
        below_violation=float(np.count_nonzero(valid < -VIOLATION_EPSILON)) / n,
        mean=float(finite.mean()),
        clipped_mean=float(np.clip(finite, 0.0, 1.0).mean()),
    )


def survey_case(mi: Any, case: Case, rays: int, seed: int = 0) -> CaseSurvey:
    """Load ``case`` with ``mi.load_dict`` and survey it at every condition."""

    result = CaseSurvey(case)
    start = time.perf_counter()
    try:
        bsdf = mi.load_dict(case.definition)
        weights = sample_weights(mi, bsdf, rays, seed=seed)
    except Exception as error:  # a plugin that cannot act as a specimen: report, go on
        result.error = f"{type(error).__name__}: {str(error).splitlines()[0] if str(error) else ''}"
        result.seconds = time.perf_counter() - start
        return result
    for i, theta in enumerate(THETAS):
        for j, wavelength in enumerate(WAVELENGTHS):
            result.conditions.append(condition_statistics(weights[i, j], theta, wavelength))
    result.seconds = time.perf_counter() - start
    return result


def survey(rays: int = 1_000_000, cases: tuple[Case, ...] = CASES, seed: int = 0,
           progress: bool = True) -> list[CaseSurvey]:
    """Survey ``cases`` with ``rays`` rays per (theta, wavelength) condition."""

    mi = virtspec_mi.mitsuba()
    results = []
    for case in cases:
        results.append(survey_case(mi, case, rays, seed))
        if progress:
            r = results[-1]
            state = r.error or f"max {r.largest:.7g}  min {r.smallest:.7g}  nan {r.nan}"
            print(f"{case.label:34s} {r.seconds:6.2f} s  {state}", file=sys.stderr, flush=True)
    return results


def propose_tolerance(results: list[CaseSurvey]) -> tuple[float, float]:
    """
    The largest excess of the ``bounded`` cases outside [0, 1] and the smallest round
    tolerance of :data:`ROUND_TOLERANCES` that covers it.
    """

    excess = 0.0
    for r in results:
        if r.case.bounded and r.conditions:
            excess = max(excess, r.largest - 1.0, -r.smallest)
    for eps in ROUND_TOLERANCES:
        if excess <= eps:
            return excess, eps
    return excess, math.inf


def verdict(r: CaseSurvey, eps: float) -> str:
    """``exact`` (all weights in [-eps, 1 + eps], no NaN), ``flagged`` or ``error``."""

    if r.error:
        return "error"
    if r.nan == 0 and r.largest <= 1.0 + eps and r.smallest >= -eps:
        return "exact"
    return "flagged"


def _share(x: float) -> str:
    return "0" if x == 0 else f"{x:.2e}"


def format_summary(results: list[CaseSurvey], eps: float) -> str:
    """
    Markdown table, one row per case: extremes over all conditions, shares over all
    rays; the columns marked * are those of the condition with the largest clipping bias.
    """

    lines = [
        "| BSDF | bounded | verdict | max w | min w | worst (θi, λ) | share (1,1+1e-4] | share (1,1+1e-3] "
        "| share >1+1e-3 | share [-1e-3,0) | NaN | mean w* | mean clip(w)* | clip bias* (θi, λ) | s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        bounded = "yes" if r.case.bounded else "no"
        if r.error:
            cells = [r.case.label, bounded, "error", *[""] * 10, r.error, f"{r.seconds:.1f}"]
            lines.append("| " + " | ".join(cells) + " |")
            continue
        n = sum(c.rays for c in r.conditions)

        def total(get: Any) -> float:
            return sum(get(c) * c.rays for c in r.conditions) / n

        worst, bias = r.worst, r.largest_bias
        lines.append(
            f"| {r.case.label} | {bounded} | {verdict(r, eps)} | {r.largest:.8g} | {r.smallest:.4g} "
            f"| {worst.theta:g}°, {worst.wavelength:g} nm "
            f"| {_share(total(lambda c: c.above_band[1e-4]))} | {_share(total(lambda c: c.above_band[1e-3]))} "
            f"| {_share(total(lambda c: c.above_violation))} | {_share(total(lambda c: c.below_band[1e-3]))} "
            f"| {r.nan} | {bias.mean:.5f} | {bias.clipped_mean:.5f} "
            f"| {bias.clipped_mean - bias.mean:+.2e} ({bias.theta:g}°, {bias.wavelength:g} nm) "
            f"| {r.seconds:.1f} |"
        )
    return "\n".join(lines)


def format_conditions(results: list[CaseSurvey]) -> str:
    """Tab-separated table, one row per (case, theta, wavelength)."""

    header = ["bsdf", "theta", "wavelength", "rays", "max", "min", "nan",
              *(f"share_(1,1+{e:g}]" for e in EPSILONS), *(f"share_[-{e:g},0)" for e in EPSILONS),
              f"share_>1+{VIOLATION_EPSILON:g}", f"share_<-{VIOLATION_EPSILON:g}", "mean", "clipped_mean"]
    rows = ["\t".join(header)]
    for r in results:
        for c in r.conditions:
            rows.append("\t".join(map(str, [
                r.case.label, c.theta, c.wavelength, c.rays, f"{c.largest:.9g}", f"{c.smallest:.9g}", c.nan,
                *(f"{c.above_band[e]:.3e}" for e in EPSILONS), *(f"{c.below_band[e]:.3e}" for e in EPSILONS),
                f"{c.above_violation:.3e}", f"{c.below_violation:.3e}", f"{c.mean:.6f}", f"{c.clipped_mean:.6f}",
            ])))
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> None:
    """Command line: survey, print the per-case table and the proposed tolerance."""

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--rays", type=int, default=1_000_000, help="rays per (theta, wavelength) condition")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--only", default=None, help="survey only cases whose label contains this")
    parser.add_argument("--conditions", default=None, help="write the per-condition TSV table to this path")
    args = parser.parse_args(argv)

    cases = CASES if args.only is None else tuple(c for c in CASES if args.only in c.label)
    start = time.perf_counter()
    results = survey(args.rays, cases, args.seed)
    elapsed = time.perf_counter() - start
    excess, eps = propose_tolerance(results)
    print(format_summary(results, eps))
    print()
    print(f"largest excess of the bounded cases outside [0, 1]: {excess:.3g}")
    print(f"proposed rounding tolerance eps = {eps:g}")
    print("skipped: " + "; ".join(f"{name} ({why})" for name, why in SKIPPED.items()))
    print(f"{args.rays} rays x {len(THETAS) * len(WAVELENGTHS)} conditions x {len(cases)} cases "
          f"in {elapsed:.1f} s")
    if args.conditions:
        with open(args.conditions, "w", encoding="utf-8") as handle:
            handle.write(format_conditions(results) + "\n")


if __name__ == "__main__":
    main()
