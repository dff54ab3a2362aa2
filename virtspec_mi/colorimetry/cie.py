"""
Colorimetry of measured spectra through colour-science
======================================================

- :func:`spectral_distribution` / :func:`multi_spectral_distributions`: a result of
  any kind (a reading or a sweep, a goniophotometer's R and T, a sphere's reading …) at
  one θi as ``colour.SpectralDistribution`` (one quantity) or
  ``colour.MultiSpectralDistributions`` (reflectance, transmittance, absorptance).
- :func:`colorimetry`: CIE XYZ, CIE L*a*b* and sRGB of a reflectance or
  transmittance spectrum under an illuminant (CIE D65 by default) and an observer
  (CIE 1931 2° by default), as a :class:`Colour`.

Wavelengths outside the observer's colour-matching range (360–830 nm for CIE 1931
2°) stay in the data but are left out of the colorimetry; :attr:`Colour.note` says
which. Inside that range colour-science integrates the spectrum (ASTM E308 weights;
outside the measured span it extends the spectrum by its end values); spectra not
evenly sampled at 1, 5, 10 or 20 nm are first linearly interpolated onto 1 nm (noted).

References
----------
CIE 015:2018 *Colorimetry*; ASTM E308; colour-science (Mansencal et al.),
``colour.sd_to_XYZ``, ``colour.XYZ_to_Lab``, ``colour.XYZ_to_sRGB``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from virtspec_mi.kernel.counts import QUANTITIES

__all__ = [
    "DEFAULT_ILLUMINANT",
    "DEFAULT_OBSERVER",
    "Colour",
    "spectral_distribution",
    "multi_spectral_distributions",
    "colorimetry",
    "MIN_COVERAGE",
    "coverage",
]

MIN_COVERAGE: float = 0.95
"""
Least share of the colour-matching weight a spectrum must cover for its colour to be
reported: the weight is (x̄ + ȳ + z̄)·S(λ) of the observer and illuminant, and a spectrum
covers the part between its first and last wavelength inside the observer's range
(400–700 nm covers 99.8 % under D65 and CIE 1931 2°, 420–680 nm 98.0 %, 465–800 nm only
70.5 %). Below it the colour would rest on colour-science extending the end values.
"""

DEFAULT_ILLUMINANT: str = "D65"
DEFAULT_OBSERVER: str = "CIE 1931 2 Degree Standard Observer"


@dataclass(frozen=True)
class Colour:
    """
    The colour of a spectrum.

    Attributes
    ----------
    XYZ : ndarray
        CIE XYZ tristimulus values, Y = 100 for a perfect reflector.
    Lab : ndarray
        CIE L*a*b* relative to the illuminant's white point (the perfect reflecting
        diffuser integrated over the same wavelengths).
    sRGB : ndarray
        Non-linear sRGB in [0, 1] before clipping (values outside mean out of gamut),
        chromatically adapted (CAT02) to D65 when the illuminant is another.
    illuminant, observer : str
        Names in ``colour.SDS_ILLUMINANTS`` and ``colour.MSDS_CMFS``.
    wavelengths : ndarray
        The wavelengths used (inside the colour-matching range).
    coverage : float
        Share of the colour-matching weight between the first and last wavelength used
        (see :data:`MIN_COVERAGE`).
    note : str
        Empty, or which wavelengths were left out.
    """

    XYZ: np.ndarray
    Lab: np.ndarray
    sRGB: np.ndarray
    illuminant: str
    observer: str
    wavelengths: np.ndarray
    coverage: float = 1.0
    note: str = ""

    def summary(self) -> str:
        lines = [
            f"illuminant {self.illuminant}, observer {self.observer}, "
            f"{len(self.wavelengths)} wavelengths {self.wavelengths.min():g}-{self.wavelengths.max():g} nm, "
            f"covering {self.coverage:.1%} of the colour-matching weight",
            "XYZ  = " + " ".join(f"{v:9.4f}" for v in self.XYZ),
            "Lab  = " + " ".join(f"{v:9.4f}" for v in self.Lab),
            "sRGB = " + " ".join(f"{v:9.4f}" for v in self.sRGB)
            + f"  (#{''.join(f'{int(round(255 * c)):02x}' for c in np.clip(self.sRGB, 0, 1))})",
        ]
        if self.note:
            lines.append(f"note: {self.note}")
        return "\n".join(lines)

    def as_dict(self) -> dict[str, Any]:
        """Plain data (JSON-ready): XYZ, Lab, sRGB and its hex, illuminant, observer, wavelengths, coverage, note."""

        clipped = np.clip(self.sRGB, 0, 1)
        return {
            "XYZ": self.XYZ.tolist(),
            "Lab": self.Lab.tolist(),
            "sRGB": self.sRGB.tolist(),
            "hex": "#" + "".join(f"{int(round(255 * c)):02x}" for c in clipped),
            "illuminant": self.illuminant,
            "observer": self.observer,
            "wavelengths": self.wavelengths.tolist(),
            "coverage": float(self.coverage),
            "note": self.note,
        }


def spectral_distribution(result: Any, quantity: str | None = None, theta_i: float | None = None) -> Any:
    """
    One quantity of a result of any kind at one θi (optional for a one-angle result) as a
    ``colour.SpectralDistribution`` (:meth:`~virtspec_mi.results.base.ResultBase.spectrum`;
    ``quantity`` ``None``: the kind's first, e.g. reflectance, a sphere's reading).
    """

    import colour

    spectrum = result.spectrum(quantity, theta_i)
    if len(spectrum.wavelengths) < 2:
        raise ValueError(f"a spectrum needs at least two wavelengths (the result has {len(spectrum.wavelengths)})")
    with colour.utilities.suppress_warnings(colour_runtime_warnings=True):  # "not uniform" is fine here
        return colour.SpectralDistribution(spectrum.values, spectrum.wavelengths, name=spectrum.name)


def multi_spectral_distributions(result: Any, theta_i: float | None = None) -> Any:
    """Reflectance, transmittance and absorptance at one θi as ``colour.MultiSpectralDistributions``."""

    import colour

    spectra = [result.spectrum(q, theta_i) for q in QUANTITIES]
    values = np.stack([spectrum.values for spectrum in spectra], axis=1)
    return colour.MultiSpectralDistributions(values, spectra[0].wavelengths, labels=QUANTITIES,
                                             name=f"theta_i={spectra[0].theta_i:g}")


def colorimetry(sd: Any, illuminant: str = DEFAULT_ILLUMINANT, observer: str = DEFAULT_OBSERVER) -> Colour:
    """
    CIE XYZ, L*a*b* and sRGB of a reflectance or transmittance spectrum.

    Parameters
    ----------
    sd
        A ``colour.SpectralDistribution`` (e.g. ``result.to_sd()``), at least two
        wavelengths inside the observer's range, or a result at one θi (its first
        quantity's spectrum: a reflectance, a sphere's reading).
    illuminant
        A name of ``colour.SDS_ILLUMINANTS`` (default ``"D65"``).
    observer
        A name of ``colour.MSDS_CMFS`` (default CIE 1931 2°).
    """

    import colour

    if hasattr(sd, "to_sd"):  # a Result: its reflectance spectrum
        sd = sd.to_sd()
    if illuminant not in colour.SDS_ILLUMINANTS:
        raise ValueError(f"illuminant must be a name of colour.SDS_ILLUMINANTS, e.g. D65, A, D50 (got {illuminant!r})")
    if observer not in colour.MSDS_CMFS:
        raise ValueError(f"observer must be a name of colour.MSDS_CMFS, e.g. {DEFAULT_OBSERVER!r} (got {observer!r})")
    cmfs = colour.MSDS_CMFS[observer]
    low, high = cmfs.shape.start, cmfs.shape.end
    wavelengths, values = np.asarray(sd.wavelengths, dtype=np.float64), np.asarray(sd.values, dtype=np.float64)
    inside = (wavelengths >= low) & (wavelengths <= high)
    note = ""
    if not inside.all():
        left_out = wavelengths[~inside]
        note = (f"{len(left_out)} wavelengths outside the colour-matching range {low:g}-{high:g} nm "
                f"({', '.join(f'{w:g}' for w in left_out[:5])}{', ...' if len(left_out) > 5 else ''}) "
                "are kept in the data and left out of the colorimetry")
    if inside.sum() < 2:
        raise ValueError(f"colorimetry needs at least two wavelengths within {low:g}-{high:g} nm "
                         f"(got {int(inside.sum())})")
    light = colour.SDS_ILLUMINANTS[illuminant]
    covered = coverage(wavelengths[inside].min(), wavelengths[inside].max(), cmfs, light)
    if covered < MIN_COVERAGE:
        raise ValueError(
            f"the spectrum covers {wavelengths[inside].min():g}-{wavelengths[inside].max():g} nm, only "
            f"{covered:.1%} of the colour-matching weight of {observer} under {illuminant} (at least "
            f"{MIN_COVERAGE:.0%} is needed, e.g. 400-700 nm): measure more wavelengths")
    # colour-science reports every re-sampling it does (ASTM E308 aligns shapes): expected here
    with colour.utilities.suppress_warnings(colour_runtime_warnings=True):
        used = colour.SpectralDistribution(values[inside], wavelengths[inside])
        steps = np.unique(np.round(np.diff(np.sort(wavelengths[inside])), 9))
        if len(steps) != 1 or steps[0] not in (1, 5, 10, 20):
            # ASTM E308 integrates 1, 5, 10 or 20 nm data: interpolate others onto 1 nm
            used = used.copy().interpolate(colour.SpectralShape(used.shape.start, used.shape.end, 1),
                                           interpolator=colour.LinearInterpolator)
            note = "; ".join(filter(None, [note, "wavelengths not evenly 1, 5, 10 or 20 nm apart: "
                                                 "linearly interpolated to 1 nm for the colorimetry"]))
        XYZ = np.asarray(colour.sd_to_XYZ(used, cmfs, light), dtype=np.float64)
        # White point: the perfect reflecting diffuser integrated the same way (same domain).
        perfect = colour.SpectralDistribution(np.ones(len(used.wavelengths)), used.wavelengths)
        white = colour.XYZ_to_xy(np.asarray(colour.sd_to_XYZ(perfect, cmfs, light)) / 100.0)
    Lab = np.asarray(colour.XYZ_to_Lab(XYZ / 100.0, white), dtype=np.float64)
    sRGB = np.asarray(colour.XYZ_to_sRGB(XYZ / 100.0, illuminant=white), dtype=np.float64)
    return Colour(XYZ, Lab, sRGB, illuminant, observer, wavelengths[inside], covered, note)


def coverage(low: float, high: float, cmfs: Any, illuminant: Any) -> float:
    """Share of the weight (x̄ + ȳ + z̄)·S(λ) of ``cmfs`` under ``illuminant`` within [low, high] nm."""

    wavelengths = np.asarray(cmfs.wavelengths, dtype=np.float64)
    light = np.interp(wavelengths, np.asarray(illuminant.wavelengths), np.asarray(illuminant.values))
    weight = np.asarray(cmfs.values, dtype=np.float64).sum(axis=1) * light
    within = (wavelengths >= low) & (wavelengths <= high)
    return float(weight[within].sum() / weight.sum())
