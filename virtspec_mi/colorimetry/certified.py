"""
Certified colour: CIE XYZ, L*a*b* and sRGB with intervals from the rays spent
=============================================================================

colour-science computes every colour (:func:`virtspec_mi.colorimetry.cie.colorimetry`:
ASTM E308 weights, CIE D65 and CIE 1931 2° by default); this module adds the bounds.

- :func:`tristimulus_weights`: the 3 × n matrix W with XYZ = W·q(λ) of that very
  colorimetry at the spectrum's wavelengths (found by its linearity: the ASTM E308
  tristimulus weighting factors, adjusted to the measured range, or the weights after
  its linear interpolation onto 1 nm).
- :func:`colour_functionals`: X, Y and Z as :class:`~.functionals.Functional` s.
- :func:`certify_colour`: from the XYZ estimate and one tolerance per tristimulus value
  (Hoeffding, each at δ/3: :mod:`.functionals`), the certified box of XYZ (clipped to
  what a spectrum in [0, 1] can give), its exact image in L*a*b* (:func:`.delta_e.lab_box`)
  and in sRGB (a linear map, interval matrix product, then the monotone sRGB encoding:
  exact), and the certified radii ΔE₀₀ (a rigorous bound, :mod:`.delta_e`) and ΔE*ab
  (exact over the box) around the estimate: a :class:`CertifiedColour`.
- :func:`result_colour`: the certified colour of a hemispherical result's spectrum from
  its counts (``Result.colour()``).

References
----------
CIE 015:2018 *Colorimetry*, eqs. 7.1–7.3 (tristimulus values), 8.11–8.16 (CIELAB).
ASTM E308-22, *Standard Practice for Computing the Colors of Objects by Using the CIE
System*, Tables 5 and 6 (weighting factors, their adjustment to the measured range).
IEC 61966-2-1:1999 (sRGB), eqs. (5)–(7). Hoeffding (1963), Theorem 2.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from virtspec_mi.colorimetry.delta_e import LabBox, lab_box, radius
from virtspec_mi.budgets.functionals import Functional, certified_tolerance, union_delta
from virtspec_mi.colorimetry.cie import DEFAULT_ILLUMINANT, DEFAULT_OBSERVER, Colour, colorimetry

__all__ = ["CertifiedColour", "tristimulus_weights", "colour_functionals", "certify_colour", "result_colour"]


@dataclass(frozen=True)
class CertifiedColour(Colour):
    """
    A :class:`~virtspec_mi.colorimetry.cie.Colour` with certified intervals: with
    probability ≥ 1 − ``delta`` the colour of the true spectrum (through the same
    colorimetry) lies in every interval at once.

    Attributes
    ----------
    XYZ_interval, Lab_interval, sRGB_interval : ndarray
        Shape (3, 2): lower and upper per coordinate.
    dE00_radius, dEab_radius : float
        The largest ΔE₀₀ (a rigorous upper bound) and ΔE*ab (exact over the box) between
        the estimate and a colour of the certified box.
    delta : float
        δ of the statement (δ/3 for each tristimulus value).
    rays : int
        Rays spent on the readings behind the colour.
    method : str
        How the intervals were found, in words.
    """

    XYZ_interval: np.ndarray = field(default_factory=lambda: np.full((3, 2), np.nan))
    Lab_interval: np.ndarray = field(default_factory=lambda: np.full((3, 2), np.nan))
    sRGB_interval: np.ndarray = field(default_factory=lambda: np.full((3, 2), np.nan))
    dE00_radius: float = float("nan")
    dEab_radius: float = float("nan")
    delta: float = float("nan")
    rays: int = 0
    method: str = ""

    @property
    def lab_box(self) -> LabBox:
        return LabBox(self.Lab_interval[:, 0], self.Lab_interval[:, 1])

    def summary(self) -> str:
        lines = super().summary().splitlines()
        head, rest = lines[0], lines[1:]
        out = [head, f"certified at delta = {self.delta:g} (all together), {self.rays:,} rays: dE00 <= "
                     f"{self.dE00_radius:.4g}, dE*ab <= {self.dEab_radius:.4g} around the estimate"]
        for name, interval in (("XYZ ", self.XYZ_interval), ("Lab ", self.Lab_interval),
                               ("sRGB", self.sRGB_interval)):
            out.append(f"{name} in " + " ".join(f"[{lo:.4f}, {hi:.4f}]" for lo, hi in interval))
        return "\n".join(out[:2] + rest[:3] + out[2:] + rest[3:] + [f"method: {self.method}"])

    def as_dict(self) -> dict[str, Any]:
        return {**super().as_dict(), "XYZ_interval": self.XYZ_interval.tolist(),
                "Lab_interval": self.Lab_interval.tolist(), "sRGB_interval": self.sRGB_interval.tolist(),
                "dE00_radius": self.dE00_radius, "dEab_radius": self.dEab_radius, "delta": self.delta,
                "rays": int(self.rays), "method": self.method}


@lru_cache(maxsize=64)
def _weights(wavelengths: tuple[float, ...], illuminant: str, observer: str) -> np.ndarray:
    import colour

    grid = np.asarray(wavelengths)
    steps = np.unique(np.round(np.diff(grid), 9))
    cmfs = colour.MSDS_CMFS[observer]
    inside = (grid >= cmfs.shape.start) & (grid <= cmfs.shape.end)
    weights = np.zeros((3, len(grid)))
    if len(steps) == 1 and steps[0] in (1, 5, 10, 20) and inside.all():  # colorimetry's own ASTM E308 path
        with colour.utilities.suppress_warnings(colour_runtime_warnings=True):
            eye = colour.MultiSpectralDistributions(np.eye(len(grid)), grid)
            weights[:] = np.asarray(colour.msds_to_XYZ(eye, cmfs, colour.SDS_ILLUMINANTS[illuminant],
                                                       method="ASTM E308"), dtype=np.float64).T
        return weights
    for k in range(len(grid)):  # any other grid: colorimetry itself, one unit spectrum at a time (it is linear)
        import colour as c

        unit = np.zeros(len(grid))
        unit[k] = 1.0
        weights[:, k] = colorimetry(c.SpectralDistribution(unit, grid), illuminant, observer).XYZ
    return weights


def tristimulus_weights(wavelengths: np.ndarray, illuminant: str = DEFAULT_ILLUMINANT,
                        observer: str = DEFAULT_OBSERVER) -> np.ndarray:
    """
    W (shape (3, n)) with colorimetry(q).XYZ = W·q for every spectrum q at ``wavelengths``
    (increasing, nm; the coverage rules of :func:`~virtspec_mi.colorimetry.cie.colorimetry`
    apply: too little of the visible is refused).
    """

    import colour

    grid = np.asarray(wavelengths, dtype=np.float64)
    colorimetry(colour.SpectralDistribution(np.full(len(grid), 0.5), grid), illuminant, observer)  # its checks
    return _weights(tuple(float(w) for w in grid), illuminant, observer).copy()


def colour_functionals(wavelengths: np.ndarray, quantity: str = "reflectance", illuminant: str = DEFAULT_ILLUMINANT,
                       observer: str = DEFAULT_OBSERVER) -> list[Functional]:
    """CIE X, Y, Z (Y = 100 for the perfect reflector) of ``quantity`` at ``wavelengths`` as functionals."""

    weights = tristimulus_weights(wavelengths, illuminant, observer)
    return [Functional(name, np.asarray(wavelengths, dtype=np.float64), weights[i], quantity, "1",
                       f"CIE tristimulus value {name} of the {quantity} ({illuminant}, {observer})")
            for i, name in enumerate("XYZ")]


def _srgb_matrix(white_xy: tuple[float, float]) -> np.ndarray:
    import colour

    return np.asarray(colour.XYZ_to_sRGB(np.eye(3), illuminant=np.asarray(white_xy), apply_cctf_encoding=False),
                      dtype=np.float64).T


def certify_colour(colour_estimate: Colour, functionals: list[Functional], tolerances: np.ndarray, delta: float,
                   rays: int, method: str = "") -> CertifiedColour:
    """
    The :class:`CertifiedColour` of an estimate whose X, Y, Z (``functionals``) hold to
    ``tolerances`` (each at δ/3: ``delta`` is the joint statement's).
    """

    import colour

    XYZ = np.asarray(colour_estimate.XYZ, dtype=np.float64)
    tolerances = np.asarray(tolerances, dtype=np.float64)
    floor = np.array([f.weights[f.weights < 0].sum() for f in functionals])  # what q in [0, 1] can give
    ceiling = np.array([f.weights[f.weights > 0].sum() for f in functionals])
    lower, upper = np.clip(XYZ - tolerances, floor, ceiling), np.clip(XYZ + tolerances, floor, ceiling)
    white = colour.XYZ_to_xy(np.array([f.weights.sum() for f in functionals]) / 100.0)  # the perfect diffuser
    box = lab_box(np.maximum(lower, 0.0), upper, white)
    matrix = _srgb_matrix(tuple(white))
    positive, negative = np.clip(matrix, 0, None), np.clip(matrix, None, 0)
    linear_low = positive @ (lower / 100.0) + negative @ (upper / 100.0)
    linear_high = positive @ (upper / 100.0) + negative @ (lower / 100.0)
    encode = colour.models.eotf_inverse_sRGB
    srgb = np.stack([np.asarray(encode(linear_low)), np.asarray(encode(linear_high))], axis=1)
    de00, deab = radius(np.asarray(colour_estimate.Lab), box)
    fields = {name: getattr(colour_estimate, name) for name in ("XYZ", "Lab", "sRGB", "illuminant", "observer",
                                                                  "wavelengths", "coverage", "note")}
    return CertifiedColour(**fields, XYZ_interval=np.stack([lower, upper], axis=1),
                           Lab_interval=np.stack([box.lower, box.upper], axis=1), sRGB_interval=srgb,
                           dE00_radius=de00, dEab_radius=deab, delta=float(delta), rays=int(rays),
                           method=method or "Hoeffding (1963) on each tristimulus functional at delta/3; the XYZ "
                                            "box mapped exactly to L*a*b* and sRGB; dE00 a rigorous upper bound")


def result_colour(result: Any, quantity: str | None = None, theta_i: float | None = None,
                  illuminant: str = DEFAULT_ILLUMINANT, observer: str = DEFAULT_OBSERVER) -> Colour:
    """
    The colour of one quantity of ``result`` at one θi: a :class:`CertifiedColour` for a
    hemispherical result whose readings are all certified (intervals from the rays each
    reading actually spent, at the result's δ), else the plain colour with a note saying
    why no interval is given.
    """

    plain = colorimetry(result.to_sd(quantity, theta_i), illuminant, observer)
    reason = _uncertifiable(result)
    if reason:
        note = "; ".join(filter(None, [plain.note, f"no certified interval: {reason}"]))
        return Colour(plain.XYZ, plain.Lab, plain.sRGB, plain.illuminant, plain.observer, plain.wavelengths,
                      plain.coverage, note)
    grid = result.as_grid()
    column = grid.angle_index(theta_i)
    wavelengths = np.asarray(grid.coords["wavelength"], dtype=np.float64)
    order = np.argsort(wavelengths, kind="stable")
    wavelengths = wavelengths[order]
    rays = np.asarray(grid.rays)[order, column]
    rounding = np.asarray(grid.rounding_bias)[order, column]
    inside = np.isin(wavelengths, plain.wavelengths)
    functionals = colour_functionals(wavelengths[inside], result.check_quantity(quantity), illuminant, observer)
    delta = float(result.settings.delta)
    each = union_delta(delta, 3)
    shared = bool(result.wavelength_independent)
    tolerances = np.array([certified_tolerance(f, rays[inside], each, rounding[inside], shared=shared)
                           for f in functionals])
    spent = int(rays.max()) if shared else int(rays.sum())
    return certify_colour(plain, functionals, tolerances, delta, spent)


def _uncertifiable(result: Any) -> str:
    """Why ``result``'s colour gets no interval ("" when it does)."""

    if getattr(result, "KIND", "") != "hemispherical reading" or not hasattr(result, "certified"):
        return (f"intervals are derived for hemispherical readings only (this is a "
                f"{getattr(result, 'KIND', type(result).__name__)})")
    if not np.all(result.certified):
        return "some readings escaped their certificate (weight violations, capped walks or invalid directions)"
    return ""
